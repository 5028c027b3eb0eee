#pragma once
// Sign-constrained least squares in normal-equation form (Lawson & Hanson, "Solving Least
// Squares Problems", 1974, ch. 23; the Gram-matrix variant of Bro & de Jong, 1997):
//
//   minimise 1/2 x' G x - f' x   subject to  x_i >= 0 for every constrained i,
//
// with G = A'A (+ a regularisation term) symmetric positive semi-definite. Unconstrained
// entries (the Preisach bias) stay free. The active set is warm-started by projected
// coordinate descent and then made exact by block principal pivoting (Kim & Park 2011, an
// active-set method that exchanges many indices per step), with the classic Lawson-Hanson
// iteration as a safety net, so the answer meets the KKT conditions to round-off:
//   x_i >= 0, w_i = f_i - (G x)_i <= tol, x_i w_i = 0 (constrained); w_i = 0 (free).
#include <Eigen/Core>
#include <span>
#include <string>
#include <vector>

namespace scpkit {

struct NnlsOptions {
  int max_iterations = 0;             ///< Lawson-Hanson steps; 0 means 3 * n + 30
  int warm_start_sweeps = 40;         ///< coordinate-descent sweeps before the exact phase
  double relative_tolerance = 1e-11;  ///< gradient tolerance, relative to max |f| and diag G
};

struct NnlsResult {
  Eigen::VectorXd x;
  int iterations = 0;
  bool converged = false;
  double kkt_violation = 0.0;  ///< kkt_violation(G, f, x, ...) at the answer
  int passive = 0;             ///< number of entries strictly inside their bound (plus free ones)
  int rank_deficient_pivots = 0;  ///< tiny pivots met in the passive-set factorisation
  std::string message;
};

/// Solves the problem above. `constrained` has one entry per unknown. A non-empty
/// `warm_start` (e.g. the answer for a nearby problem) replaces the coordinate-descent phase.
NnlsResult solve_nnls(const Eigen::MatrixXd& G, const Eigen::VectorXd& f,
                      const std::vector<bool>& constrained, const NnlsOptions& options = {},
                      const Eigen::VectorXd& warm_start = Eigen::VectorXd());

/// Largest violation of the KKT conditions, scaled like the solver's tolerance (so a value
/// below 1 means "optimal within tolerance").
double kkt_violation(const Eigen::MatrixXd& G, const Eigen::VectorXd& f, const Eigen::VectorXd& x,
                     const std::vector<bool>& constrained, double relative_tolerance = 1e-11);

/// +1 when the response rises with the input (non-negative covariance), -1 when it falls: the
/// sign every identification constrains its densities or weights to when not told.
int response_direction(std::span<const double> input, std::span<const double> output);

}  // namespace scpkit
