// Exact inverses: forward(inverse(target)) reproduces every reachable target, over many
// random models and histories; unreachable targets saturate and are flagged.
#include "scpkit/hysteresis/inverse.hpp"

#include <gtest/gtest.h>

#include <random>

#include "test_support.hpp"

namespace scpkit {
namespace {

TEST(PreisachInverse, ReproducesEveryReachableTargetAlongRandomHistories) {
  std::mt19937 rng(61);
  for (int trial = 0; trial < 60; ++trial) {
    const PreisachGrid grid{-1.0, 3.0, 3 + trial % 18};
    PreisachModel model = testing::random_model(rng, grid);
    if (trial % 3 == 1) model = model.with_output_affine(-1.0, 0.5);  // a falling response
    // Targets: the outputs of a random input history, so every one is reachable.
    PreisachState plant = PreisachState::negative_saturation(grid);
    const auto u = testing::random_history(rng, grid, 200);
    std::vector<double> targets;
    targets.reserve(u.size());
    for (double v : u) targets.push_back(model.step(plant, v));
    PreisachInverter inverter(model);
    PreisachState memory = PreisachState::negative_saturation(grid);
    const double tol = 1e-9 * (std::abs(model.total_mass()) + 1.0);
    for (std::size_t t = 0; t < targets.size(); ++t) {
      const InverseStep s = inverter.step(memory, targets[t]);
      ASSERT_TRUE(s.reached) << "trial " << trial << " step " << t;
      ASSERT_NEAR(s.output, targets[t], tol) << "trial " << trial << " step " << t;
      ASSERT_GE(s.input, grid.lo);
      ASSERT_LE(s.input, grid.hi);
      // The returned output is what the model gives for that input from that memory.
      ASSERT_NEAR(model.output(memory), s.output, 1e-12);
    }
  }
}

TEST(PreisachInverse, InvertsTheForwardInputWhereTheOutputIsStrictlyMonotone) {
  // With every mass positive the output is strictly monotone along any path, so the input
  // itself is recovered.
  std::mt19937 rng(62);
  const PreisachGrid grid{0.0, 1.0, 12};
  Eigen::VectorXd w = Eigen::VectorXd::Constant(grid.cells(), 0.1);
  const PreisachModel model(grid, w, 0.0);
  PreisachState plant = PreisachState::negative_saturation(grid), memory = plant;
  PreisachInverter inverter(model);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  for (int t = 0; t < 500; ++t) {
    const double v = U(rng);
    const InverseStep s = inverter.step(memory, model.step(plant, v));
    ASSERT_NEAR(s.input, v, 1e-9);
  }
}

TEST(PreisachInverse, SaturatesAndFlagsUnreachableTargets) {
  std::mt19937 rng(63);
  const PreisachGrid grid{0.0, 5.0, 8};
  const PreisachModel model = testing::random_model(rng, grid);
  PreisachState s = PreisachState::negative_saturation(grid);
  PreisachInverter inverter(model, 1.0, 4.0);
  const InverseStep high = inverter.step(s, model.bias() + 10.0 * model.total_mass());
  EXPECT_FALSE(high.reached);
  EXPECT_DOUBLE_EQ(high.input, 4.0);
  const InverseStep low = inverter.step(s, model.bias() - 10.0 * model.total_mass());
  EXPECT_FALSE(low.reached);
  EXPECT_DOUBLE_EQ(low.input, 1.0);
}

}  // namespace
}  // namespace scpkit

namespace scpkit {
namespace {

// Classical play operator, zero initial state.
struct Play {
  double r, w = 0.0;
  double operator()(double x) { return w = std::min(x + r, std::max(x - r, w)); }
};

std::vector<double> pi_operator(const std::vector<double>& r, const std::vector<double>& p,
                                const std::vector<double>& x) {
  std::vector<Play> ops;
  ops.reserve(r.size());
  for (double ri : r) ops.push_back({ri});
  std::vector<double> y;
  for (double xi : x) {
    double s = p[0] * xi;
    for (std::size_t k = 1; k < r.size(); ++k) s += p[k] * ops[k](xi);
    y.push_back(s);
  }
  return y;
}

TEST(PaperGpiInverse, Eq11InvertsAPositiveWeightPiOperatorAndFailsForNegativeWeights) {
  std::mt19937 rng(64);
  std::uniform_real_distribution<double> U(-3.0, 3.0), W(0.05, 0.5);
  std::vector<double> r, p;
  for (int j = 0; j <= 10; ++j) {
    r.push_back(j / 10.0);
    p.push_back(W(rng));
  }
  std::vector<double> x{0.0};
  for (int t = 0; t < 300; ++t) x.push_back(U(rng));
  const std::vector<double> y = pi_operator(r, p, x);
  const PaperPiInverse inv = paper_pi_inverse(r, p);
  for (std::size_t j = 2; j < r.size(); ++j) ASSERT_GT(inv.radii[j], inv.radii[j - 1]);
  const std::vector<double> x_back = pi_operator(inv.radii, inv.weights, y);
  for (std::size_t t = 0; t < x.size(); ++t) ASSERT_NEAR(x_back[t], x[t], 1e-9) << t;

  // The paper's weights are all negative: the printed radii come out negative.
  std::vector<double> neg = p;
  for (double& v : neg) v = -v;
  const PaperPiInverse bad = paper_pi_inverse(r, neg);
  EXPECT_LT(bad.radii[1], 0.0);
  // The correction: Pi = -Pi+, so invert Pi+ on -y.
  const std::vector<double> y_neg = pi_operator(r, neg, x);
  std::vector<double> minus_y;
  minus_y.reserve(y_neg.size());
  for (double v : y_neg) minus_y.push_back(-v);
  const std::vector<double> x_fixed = pi_operator(inv.radii, inv.weights, minus_y);
  for (std::size_t t = 0; t < x.size(); ++t) ASSERT_NEAR(x_fixed[t], x[t], 1e-9) << t;
}

TEST(PaperIterativeInverse, CorrectedAlgorithm1ConvergesToTheExactAnswerMoreSlowly) {
  std::mt19937 rng(65);
  const PreisachGrid grid{0.0, 11.5, 13};
  const PreisachModel model = testing::random_model(rng, grid).with_output_affine(-1.0, 0.0);
  PreisachState plant = PreisachState::negative_saturation(grid);
  PreisachState a = plant, b = plant;
  PreisachInverter exact(model);
  std::uniform_real_distribution<double> U(0.0, 11.5);
  const double tol = 1e-6 * std::abs(model.total_mass());
  int total_iterations = 0;
  for (int t = 0; t < 200; ++t) {
    const double target = model.step(plant, U(rng));
    const InverseStep e = exact.step(a, target);
    const IterativeInverseResult it =
        iterative_inverse_step(model, b, target, 0.0, 11.5, 0.23, tol);
    ASSERT_TRUE(it.step.reached) << t;
    ASSERT_NEAR(it.step.output, e.output, 2 * tol) << t;
    total_iterations += it.iterations;
  }
  EXPECT_GT(total_iterations,
            200 * 5);  // many model evaluations per step; the exact one needs a few
  PreisachState c = PreisachState::negative_saturation(grid);
  const IterativeInverseResult out = iterative_inverse_step(model, c, 1e9, 0.0, 11.5, 0.23, tol);
  EXPECT_FALSE(out.step.reached);
}

}  // namespace
}  // namespace scpkit
