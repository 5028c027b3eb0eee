#pragma once
// Error measures reported on every fit and prediction.
//   E_max = max|e| / P * 100 %,  E_RMS = rms(e) / P * 100 %   (paper 000 Eqs. 1-2),
//   P = max(measured) - min(measured), the output range;
//   E_avg = mean|e|, sigma = sqrt(sum (|e_i| - E_avg)^2 / (M - 1))   (paper 002 Eqs. 9-10),
// the last two in the response's own units (strain-% for strain, mm for displacement).
#include <span>
#include <string>

namespace scpkit {

struct ErrorMetrics {
  double max_pct_range = 0.0;
  double rms_pct_range = 0.0;
  double mean_abs = 0.0;
  double sd_abs = 0.0;
  double range = 0.0;  ///< P, in the response's units
  int count = 0;
  std::string brief(const std::string& unit) const;
  /// The same errors with the response in other units (e.g. 100 for strain -> strain-%).
  ErrorMetrics scaled(double factor) const {
    ErrorMetrics m = *this;
    m.mean_abs *= factor;
    m.sd_abs *= factor;
    m.range *= factor;
    return m;
  }
};

/// Throws InvalidArgument when sizes differ or fewer than 2 samples are given.
ErrorMetrics error_metrics(std::span<const double> measured, std::span<const double> predicted);

}  // namespace scpkit
