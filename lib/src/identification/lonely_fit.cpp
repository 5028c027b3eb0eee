#include "scpkit/identification/lonely_fit.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "scpkit/error.hpp"
#include "scpkit/identification/nnls.hpp"

namespace scpkit {

LonelyFit fit_lonely(std::span<const double> input, std::span<const double> output,
                     std::span<const char> starts, const LonelyFitOptions& options) {
  const std::size_t n = input.size();
  if (output.size() != n || (!starts.empty() && starts.size() != n))
    throw_invalid("lonely fit: sizes differ");
  if (options.levels < 1 || options.levels > 200)
    throw_invalid("lonely fit: levels must be 1..200");
  PreisachGrid grid;
  grid.levels = options.levels;
  const int p = grid.cells(), L = grid.levels;
  if (n < static_cast<std::size_t>(2 * (p + L + 1)) / 3) {
    throw IdentificationError(
        fmt::format("{} samples are too few for a lonely-stroke model with L = {}", n, L));
  }
  const auto [umin, umax] = std::minmax_element(input.begin(), input.end());
  const auto [ymin, ymax] = std::minmax_element(output.begin(), output.end());
  if (!(*umax > *umin)) throw IdentificationError("the input never changes: nothing to identify");
  if (!(*ymax > *ymin))
    throw IdentificationError("the response never changes: nothing to identify");
  grid.lo = options.lo.value_or(*umin);
  grid.hi = options.hi.value_or(*umax);
  grid.validate();
  const int sign = options.sign != 0 ? options.sign : response_direction(input, output);
  // Regressor: cell signed areas, sigma * running-maximum columns, bias.
  const double h = grid.step();
  Eigen::MatrixXd A(static_cast<Eigen::Index>(n), p + L + 1);
  Eigen::VectorXd row(p);
  PreisachState state = PreisachState::negative_saturation(grid);
  double M = grid.lo, sigma = 1.0;
  for (std::size_t t = 0; t < n; ++t) {
    if (t == 0 || (!starts.empty() && starts[t] != kContinue)) {
      state = PreisachState::negative_saturation(grid);
      M = grid.lo;
      sigma = !starts.empty() && starts[t] == kRestartAfterLoadIncrease ? -1.0 : 1.0;
    }
    state.apply(input[t]);
    M = std::max(M, state.input());
    signed_area_fractions(grid, state, row);
    const auto r = static_cast<Eigen::Index>(t);
    A.row(r).head(p) = row.transpose() * static_cast<double>(sign);
    for (int j = 0; j < L; ++j) {
      A(r, p + j) = sign * sigma * (2.0 * std::clamp((M - (grid.lo + j * h)) / h, 0.0, 1.0) - 1.0);
    }
    A(r, p + L) = 1.0;
  }
  const Eigen::Map<const Eigen::VectorXd> y(output.data(), static_cast<Eigen::Index>(n));
  const Eigen::MatrixXd G = A.transpose() * A / static_cast<double>(n);
  const Eigen::VectorXd f = A.transpose() * y / static_cast<double>(n);
  std::vector<bool> constrained(static_cast<std::size_t>(p + L + 1), true);
  constrained.back() = false;
  const NnlsResult r = solve_nnls(G, f, constrained);

  LonelyFit fit{
      LonelyModel{PreisachModel(grid, r.x.head(p) * static_cast<double>(sign), r.x[p + L]), {}},
      {},
      grid.lo,
      grid.hi,
      ""};
  for (int j = 0; j < L; ++j) fit.model.column_weights.push_back(sign * r.x[p + j]);
  const Eigen::VectorXd fitted = A * r.x;
  fit.train = error_metrics(output, std::span<const double>(fitted.data(), n));
  double w_sum = 0.0;
  for (double w : fit.model.column_weights) w_sum += std::abs(w);
  fit.report = fmt::format(
      "lonely-stroke Preisach fit: L = {} ({} cells + {} running-maximum columns), sign {:+d}, {}\n"
      "  lonely stroke (sum |W_j|, twice that in output units): {:.4g}\n"
      "  identification: E_max {:.3f} %, E_RMS {:.3f} % of the response range",
      L, p, L, sign, r.converged ? "converged" : "NOT converged", w_sum, fit.train.max_pct_range,
      fit.train.rms_pct_range);
  return fit;
}

}  // namespace scpkit
