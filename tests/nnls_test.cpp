// The Lawson-Hanson solver against the KKT conditions, against brute-force enumeration of
// active sets on small problems, and on exactly representable solutions.
#include "scpkit/identification/nnls.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <limits>
#include <random>

namespace scpkit {
namespace {

double objective(const Eigen::MatrixXd& G, const Eigen::VectorXd& f, const Eigen::VectorXd& x) {
  return 0.5 * x.dot(G * x) - f.dot(x);
}

// Best objective over all 2^n active sets (small n): an independent exact reference.
double brute_force_minimum(const Eigen::MatrixXd& G, const Eigen::VectorXd& f,
                           const std::vector<bool>& constrained) {
  const int n = static_cast<int>(f.size());
  double best = std::numeric_limits<double>::infinity();
  for (int mask = 0; mask < (1 << n); ++mask) {
    std::vector<int> P;
    for (int i = 0; i < n; ++i) {
      if (!constrained[i] || (mask >> i & 1)) P.push_back(i);
    }
    Eigen::MatrixXd Gp(P.size(), P.size());
    Eigen::VectorXd fp(P.size());
    for (std::size_t a = 0; a < P.size(); ++a) {
      fp[a] = f[P[a]];
      for (std::size_t b = 0; b < P.size(); ++b) Gp(a, b) = G(P[a], P[b]);
    }
    const Eigen::VectorXd zp = Gp.ldlt().solve(fp);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
    bool feasible = true;
    for (std::size_t a = 0; a < P.size(); ++a) {
      x[P[a]] = zp[a];
      if (constrained[P[a]] && zp[a] < 0.0) feasible = false;
    }
    if (feasible) best = std::min(best, objective(G, f, x));
  }
  return best;
}

TEST(Nnls, MatchesBruteForceOverActiveSetsAndMeetsKkt) {
  std::mt19937 rng(21);
  std::normal_distribution<double> N(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 2 + trial % 8, m = n + 3 + trial % 5;
    Eigen::MatrixXd A(m, n);
    for (Eigen::Index i = 0; i < A.size(); ++i) A.data()[i] = N(rng);
    Eigen::VectorXd b(m);
    for (Eigen::Index i = 0; i < m; ++i) b[i] = N(rng);
    std::vector<bool> constrained(n, true);
    if (trial % 3 == 0) constrained[n - 1] = false;  // a free bias
    const Eigen::MatrixXd G = A.transpose() * A;
    const Eigen::VectorXd f = A.transpose() * b;
    const NnlsResult r = solve_nnls(G, f, constrained);
    ASSERT_TRUE(r.converged) << r.message;
    EXPECT_LT(r.kkt_violation, 1e3) << "trial " << trial;
    for (int i = 0; i < n; ++i) {
      if (constrained[i]) {
        ASSERT_GE(r.x[i], 0.0);
      }
    }
    EXPECT_NEAR(objective(G, f, r.x), brute_force_minimum(G, f, constrained),
                1e-9 * (1.0 + std::abs(objective(G, f, r.x))));
  }
}

TEST(Nnls, RecoversANonNegativeSolutionExactly) {
  std::mt19937 rng(22);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const int n = 60, m = 200;
  Eigen::MatrixXd A(m, n);
  for (Eigen::Index i = 0; i < A.size(); ++i) A.data()[i] = U(rng);
  Eigen::VectorXd x_true(n);
  for (int i = 0; i < n; ++i) x_true[i] = (i % 3 == 0) ? 0.0 : U(rng);
  const Eigen::VectorXd b = A * x_true;
  const NnlsResult r = solve_nnls(A.transpose() * A, A.transpose() * b, std::vector<bool>(n, true));
  ASSERT_TRUE(r.converged);
  EXPECT_LT((r.x - x_true).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(Nnls, DetectsViolatedKktConditions) {
  // The check itself must fail on a wrong answer, or it proves nothing.
  const Eigen::MatrixXd G = Eigen::MatrixXd::Identity(2, 2);
  const Eigen::VectorXd f = Eigen::Vector2d(1.0, -1.0);
  std::vector<bool> c(2, true);
  EXPECT_LT(kkt_violation(G, f, Eigen::Vector2d(1.0, 0.0), c), 1.0);
  EXPECT_GT(kkt_violation(G, f, Eigen::Vector2d(0.5, 0.0), c), 1.0);   // gradient not zero
  EXPECT_GT(kkt_violation(G, f, Eigen::Vector2d(1.0, -0.5), c), 1.0);  // infeasible
  EXPECT_GT(kkt_violation(G, f, Eigen::Vector2d(0.0, 0.0), c), 1.0);   // should enter
}

}  // namespace
}  // namespace scpkit
