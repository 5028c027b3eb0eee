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
