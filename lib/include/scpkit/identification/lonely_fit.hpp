#pragma once
// Identification of the lonely-stroke model (paper 001, equivalent form, lonely.hpp): linear
// least squares in the conventional cell masses, the running-maximum column weights W_j and
// the bias, all masses and W of one sign (paper 001: all densities <= 0 for its falling
// response), solved exactly by solve_nnls. Default L = 13 (paper 001).
#include <optional>
#include <span>
#include <string>

#include "scpkit/hysteresis/lonely.hpp"
#include "scpkit/metrics.hpp"

namespace scpkit {

struct LonelyFitOptions {
  int levels = 13;
  int sign = 0;  ///< +1 / -1; 0: from the data
  std::optional<double> lo, hi;
};

struct LonelyFit {
  LonelyModel model;
  ErrorMetrics train;
  double input_min = 0.0, input_max = 0.0;
  std::string report;
};

/// `starts`: RestartFlag per sample (optional): where the memory restarts and the expanded
/// hysterons re-arm, with the sign of the load change.
LonelyFit fit_lonely(std::span<const double> input, std::span<const double> output,
                     std::span<const char> starts, const LonelyFitOptions& options);

}  // namespace scpkit
