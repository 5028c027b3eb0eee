#include "scpkit/identification/polynomial_fit.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>

#include "scpkit/error.hpp"

namespace scpkit {

PolynomialModel fit_polynomial(std::span<const double> x, std::span<const double> y, int degree) {
  if (degree < 1 || degree > 2) throw_invalid("polynomial degree must be 1 or 2, got {}", degree);
  if (x.size() != y.size()) throw_invalid("polynomial fit: {} x vs {} y", x.size(), y.size());
  const auto n = static_cast<Eigen::Index>(x.size());
  if (n < degree + 1) {
    throw IdentificationError(
        fmt::format("{} samples are too few for a degree-{} polynomial", n, degree));
  }
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  if (!(*hi > *lo)) throw IdentificationError("the input never changes: nothing to identify");
  // Centre and scale the abscissa for conditioning, then expand back.
  const double mid = 0.5 * (*lo + *hi), half = 0.5 * (*hi - *lo);
  Eigen::MatrixXd A(n, degree + 1);
  for (Eigen::Index t = 0; t < n; ++t) {
    const double s = (x[t] - mid) / half;
    for (int k = 0; k <= degree; ++k) A(t, k) = std::pow(s, k);
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  if (qr.rank() < degree + 1) {
    throw IdentificationError(
        fmt::format("the data do not determine a degree-{} polynomial", degree));
  }
  const Eigen::VectorXd b = qr.solve(Eigen::Map<const Eigen::VectorXd>(y.data(), n));
  PolynomialModel p;
  p.v_min = *lo;
  p.v_max = *hi;
  // y = sum_k b_k ((x - mid)/half)^k, expanded in powers of x.
  p.coefficients.assign(static_cast<std::size_t>(degree) + 1, 0.0);
  p.coefficients[0] =
      b[0] - b[1] * mid / half + (degree == 2 ? b[2] * mid * mid / (half * half) : 0.0);
  p.coefficients[1] = b[1] / half - (degree == 2 ? 2.0 * b[2] * mid / (half * half) : 0.0);
  if (degree == 2) p.coefficients[2] = b[2] / (half * half);
  return p;
}

}  // namespace scpkit
