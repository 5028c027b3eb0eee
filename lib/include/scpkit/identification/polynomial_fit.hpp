#pragma once
// Least-squares polynomials: the augmented linear model's H (paper 000 Eq. 9, MATLAB polyfit)
// and paper 001's second-order comparison model; also the quadratic load maps f1, f2 of the
// augmented model (paper 000 Eqs. 14-15).
#include <span>

#include "scpkit/hysteresis/operator.hpp"

namespace scpkit {

/// Coefficients c0..c_degree of the least-squares polynomial (degree 1 or 2), on the input
/// range of the data. IdentificationError when the data cannot determine them.
PolynomialModel fit_polynomial(std::span<const double> x, std::span<const double> y, int degree);

}  // namespace scpkit
