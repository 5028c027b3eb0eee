#include "scpkit/metrics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "scpkit/error.hpp"

namespace scpkit {

ErrorMetrics error_metrics(std::span<const double> measured, std::span<const double> predicted) {
  if (measured.size() != predicted.size()) {
    throw_invalid("error metrics: {} measured vs {} predicted samples", measured.size(),
                  predicted.size());
  }
  if (measured.size() < 2) throw_invalid("error metrics need at least 2 samples");
  ErrorMetrics m;
  m.count = static_cast<int>(measured.size());
  const auto [lo, hi] = std::minmax_element(measured.begin(), measured.end());
  m.range = *hi - *lo;
  double sum_abs = 0.0, sum_sq = 0.0, max_abs = 0.0;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    const double e = std::abs(predicted[i] - measured[i]);
    sum_abs += e;
    sum_sq += e * e;
    max_abs = std::max(max_abs, e);
  }
  const double n = static_cast<double>(m.count);
  m.mean_abs = sum_abs / n;
  double var = 0.0;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    const double d = std::abs(predicted[i] - measured[i]) - m.mean_abs;
    var += d * d;
  }
  m.sd_abs = std::sqrt(var / (n - 1.0));
  const double P = m.range > 0.0 ? m.range : 1.0;
  m.max_pct_range = 100.0 * max_abs / P;
  m.rms_pct_range = 100.0 * std::sqrt(sum_sq / n) / P;
  return m;
}

std::string ErrorMetrics::brief(const std::string& unit) const {
  return fmt::format(
      "E_max {:.3f} %  E_RMS {:.3f} % of range {:.4g} {};  mean|e| {:.4g} +- {:.4g} {}  ({} "
      "points)",
      max_pct_range, rms_pct_range, range, unit, mean_abs, sd_abs, unit, count);
}

}  // namespace scpkit
