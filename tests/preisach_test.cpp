// Properties of the discretised Preisach operator over many random models and histories.
#include "scpkit/hysteresis/preisach.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "scpkit/error.hpp"
#include "test_support.hpp"

namespace scpkit {
namespace {

using testing::random_history;
using testing::random_model;

// Brute force: a fine grid of individual relay hysterons, N sub-levels per level. Every
// sub-square carries its cell's density times its area; diagonal sub-triangles carry half.
class RelayGrid {
 public:
  RelayGrid(const PreisachModel& m, int sub) : lo_(m.grid().lo), bias_(m.bias()) {
    const PreisachGrid& g = m.grid();
    const int L = g.levels;
    n_ = L * sub;
    delta_ = g.step() / sub;
    const Eigen::VectorXd mu = m.density();
    for (int b = 0; b < n_; ++b) {
      for (int a = b; a < n_; ++a) {
        const int i = b / sub, j = a / sub;
        const double area = (a == b ? 0.5 : 1.0) * delta_ * delta_;
        // Thresholds: sub-cell centre, or the centroid of a diagonal sub-triangle.
        const double beta = lo_ + (a == b ? b + 1.0 / 3.0 : b + 0.5) * delta_;
        const double alpha = lo_ + (a == b ? a + 2.0 / 3.0 : a + 0.5) * delta_;
        relays_.push_back({beta, alpha, mu[g.cell_index(i, j)] * area, -1});
      }
    }
  }
  double step(double u) {
    double y = bias_;
    for (auto& r : relays_) {
      if (u > r.alpha) r.state = 1;
      if (u < r.beta) r.state = -1;
      y += r.weight * r.state;
    }
    return y;
  }
  double node(int k) const { return lo_ + k * delta_; }
  int nodes() const { return n_ + 1; }

 private:
  struct Relay {
    double beta, alpha, weight;
    int state;
  };
  double lo_, bias_, delta_;
  int n_;
  std::vector<Relay> relays_;
};

TEST(Preisach, AgreesExactlyWithBruteForceRelaysOnSubGridInputs) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const PreisachGrid grid{-1.0 + trial * 0.1, 2.0 + trial * 0.3, 2 + trial % 7};
    const PreisachModel model = random_model(rng, grid);
    RelayGrid relays(model, 6);
    PreisachState state = PreisachState::negative_saturation(grid);
    std::uniform_int_distribution<int> node(0, relays.nodes() - 1);
    for (int t = 0; t < 300; ++t) {
      const double u = relays.node(node(rng));
      const double expect = relays.step(u);
      ASSERT_NEAR(model.step(state, u), expect, 1e-9 * (1.0 + model.total_mass()))
          << "trial " << trial << " step " << t;
    }
  }
}

TEST(Preisach, ConvergesToBruteForceRelaysOnArbitraryInputs) {
  std::mt19937 rng(12);
  const PreisachGrid grid{0.0, 1.0, 5};
  const PreisachModel model = random_model(rng, grid);
  for (int sub : {8, 32}) {
    RelayGrid relays(model, sub);
    PreisachState state = PreisachState::negative_saturation(grid);
    double worst = 0.0;
    for (double u : random_history(rng, grid, 200)) {
      worst = std::max(worst, std::abs(model.step(state, u) - relays.step(u)));
    }
    // Each relay misplaces at most one sub-cell band along the memory curve.
    EXPECT_LT(worst, 8.0 * model.total_mass() / sub) << "sub " << sub;
  }
}

TEST(Preisach, OutputEqualsBiasPlusWeightsTimesSignedAreas) {
  std::mt19937 rng(13);
  for (int trial = 0; trial < 30; ++trial) {
    const PreisachGrid grid{0.0, 5.0, 1 + trial % 12};
    const PreisachModel model = random_model(rng, grid);
    PreisachState state = PreisachState::negative_saturation(grid);
    Eigen::VectorXd row(grid.cells());
    for (double u : random_history(rng, grid, 60)) {
      const double y = model.step(state, u);
      signed_area_fractions(grid, state, row);
      ASSERT_NEAR(y, model.bias() + model.weights().dot(row), 1e-10);
      ASSERT_LE(row.maxCoeff(), 1.0);
      ASSERT_GE(row.minCoeff(), -1.0);
    }
  }
}

TEST(Preisach, SaturationOutputsAreBiasMinusAndPlusTotalMass) {
  std::mt19937 rng(14);
  const PreisachGrid grid{20.0, 250.0, 10};
  const PreisachModel model = random_model(rng, grid);
  const double total = model.weights().sum();
  EXPECT_NEAR(model.total_mass(), total, 1e-12);
  EXPECT_NEAR(model.output(PreisachState::negative_saturation(grid)), model.bias() - total, 1e-12);
  EXPECT_NEAR(model.output(PreisachState::positive_saturation(grid)), model.bias() + total, 1e-12);
  PreisachState s = PreisachState::negative_saturation(grid);
  EXPECT_NEAR(model.step(s, 1e9), model.bias() + total, 1e-12);  // clamped to hi
}

// A grid reaching below the inputs has hysterons (beta below the smallest input) that switch
// on the first rise and never back: from negative saturation the first stroke differs from
// every later one (the virgin stroke, PHYSICS.md section 4). After one cycle lo -> hi -> lo
// they are up from the start, and the response at the lowest input is the same before and
// after any history inside [lo, hi]; on a grid starting at lo the state is negative saturation.
TEST(Preisach, AfterACycleNoHysteronIsLeftForAFirstStroke) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> inside(0.3, 1.0);
  int virgin_differs = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const PreisachGrid grid{0.0, 1.0, 10};
    const PreisachModel model = random_model(rng, grid);
    PreisachState fresh = PreisachState::negative_saturation(grid);
    PreisachState cycled = PreisachState::after_cycle(grid, 0.3, 1.0);
    const double fresh_at_lo = model.step(fresh, 0.3), cycled_at_lo = model.step(cycled, 0.3);
    for (int k = 0; k < 12; ++k) {
      const double v = inside(rng);
      model.step(fresh, v);
      model.step(cycled, v);
    }
    model.step(fresh, 1.0);
    model.step(cycled, 1.0);
    // Back at the lowest input: the cycled state reads as it started; the fresh one does not
    // (unless the random density left the strip below 0.3 empty).
    ASSERT_NEAR(model.step(cycled, 0.3), cycled_at_lo, 1e-12);
    const double fresh_back = model.step(fresh, 0.3);
    ASSERT_NEAR(fresh_back, cycled_at_lo, 1e-12);  // both now hold the strip up
    if (std::abs(fresh_back - fresh_at_lo) > 1e-9) ++virgin_differs;
    // On a grid that starts at the lowest input, the cycle changes nothing.
    const PreisachGrid tight{0.3, 1.0, 7};
    const PreisachModel m2 = random_model(rng, tight);
    PreisachState a = PreisachState::negative_saturation(tight);
    PreisachState b = PreisachState::after_cycle(tight, 0.3, 1.0);
    for (double v : random_history(rng, tight, 30))
      ASSERT_NEAR(m2.step(a, v), m2.step(b, v), 1e-12);
  }
  EXPECT_GT(virgin_differs, 30);
  EXPECT_THROW(PreisachState::after_cycle(PreisachGrid{0.0, 1.0, 4}, 0.5, 0.5), InvalidArgument);
}

TEST(Preisach, WipingOutErasesDominatedExtrema) {
  std::mt19937 rng(15);
  const PreisachGrid grid{0.0, 10.0, 8};
  for (int trial = 0; trial < 50; ++trial) {
    const PreisachModel model = random_model(rng, grid);
    PreisachState a = PreisachState::negative_saturation(grid);
    PreisachState b = PreisachState::negative_saturation(grid);
    // a: a common prefix, then an excursion inside (m, M), then a new maximum above M.
    std::uniform_real_distribution<double> u(0.0, 10.0);
    for (int k = 0; k < 5; ++k) {
      const double v = u(rng);
      a.apply(v);
      b.apply(v);
    }
    const double M = 9.0 + 0.5 * u(rng) / 10.0, m = 0.5 * u(rng) / 10.0;
    a.apply(M);
    b.apply(M);
    a.apply(m);
    b.apply(m);
    std::uniform_real_distribution<double> inner(m, M);
    for (int k = 0; k < 9; ++k) a.apply(inner(rng));  // wiped out by what follows
    const double top = M + 0.3;
    a.apply(top);
    b.apply(top);
    ASSERT_EQ(std::vector<double>(a.turning_points().begin(), a.turning_points().end()),
              std::vector<double>(b.turning_points().begin(), b.turning_points().end()));
    ASSERT_NEAR(model.output(a), model.output(b), 1e-12);
    // The memory stays alternating and dominant.
    const auto p = a.turning_points();
    for (std::size_t i = 3; i + 1 < p.size(); ++i) {
      ASSERT_TRUE(i % 2 == 1 ? p[i] < p[i - 2] : p[i] > p[i - 2]);
    }
  }
}

TEST(Preisach, MinorLoopsBetweenTheSameExtremaAreCongruent) {
  std::mt19937 rng(16);
  const PreisachGrid grid{0.0, 1.0, 9};
  for (int trial = 0; trial < 40; ++trial) {
    const PreisachModel model = random_model(rng, grid);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double u1 = u(rng), u2 = u(rng);
    if (u1 > u2) std::swap(u1, u2);
    // Two different histories, each with a maximum above u2 and then a minimum at u1: the
    // loop u1 -> u2 -> u1 that follows must have the same increments.
    std::vector<double> loop;
    for (int k = 0; k <= 10; ++k) loop.push_back(u1 + (u2 - u1) * k / 10.0);
    for (int k = 9; k >= 0; --k) loop.push_back(u1 + (u2 - u1) * k / 10.0);
    std::vector<std::vector<double>> increments;
    for (int h = 0; h < 2; ++h) {
      PreisachState s = PreisachState::negative_saturation(grid);
      for (int k = 0; k < 6; ++k) s.apply(u(rng));      // different pasts
      s.apply(u2 + (1.0 - u2) * (0.1 + 0.9 * u(rng)));  // a maximum above u2
      s.apply(u1);                                      // reversal at u1
      const double y0 = model.output(s);
      std::vector<double> inc;
      inc.reserve(loop.size());
      for (double v : loop) inc.push_back(model.step(s, v) - y0);
      increments.push_back(inc);
    }
    for (std::size_t k = 0; k < loop.size(); ++k) {
      ASSERT_NEAR(increments[0][k], increments[1][k], 1e-10) << "trial " << trial;
    }
  }
}

TEST(Preisach, IsRateIndependent) {
  std::mt19937 rng(17);
  const PreisachGrid grid{-2.0, 2.0, 12};
  for (int trial = 0; trial < 30; ++trial) {
    const PreisachModel model = random_model(rng, grid);
    const auto turning = random_history(rng, grid, 25);
    PreisachState coarse = PreisachState::negative_saturation(grid);
    PreisachState fine = PreisachState::negative_saturation(grid);
    double prev = grid.lo;
    std::uniform_int_distribution<int> substeps(1, 12);
    for (double v : turning) {
      const int k = substeps(rng);
      double y_fine = 0.0;
      for (int s = 1; s <= k; ++s) y_fine = model.step(fine, prev + (v - prev) * s / k);
      ASSERT_NEAR(model.step(coarse, v), y_fine, 1e-10);
      prev = v;
    }
  }
}

TEST(Preisach, OutputIsLipschitzContinuousInTheInput) {
  std::mt19937 rng(18);
  const PreisachGrid grid{0.0, 3.0, 10};
  const PreisachModel model = random_model(rng, grid);
  // |dy/du| <= 2 * (largest column mass per unit input) <= 2 * max cell mass * L / h.
  const double bound = 2.0 * model.weights().maxCoeff() * grid.levels / grid.step();
  PreisachState s = PreisachState::negative_saturation(grid);
  std::uniform_real_distribution<double> u(0.0, 3.0), du(-1e-4, 1e-4);
  for (int t = 0; t < 2000; ++t) {
    const double y0 = model.step(s, u(rng));
    const double d = du(rng);
    const double y1 = model.step(s, s.input() + d);
    ASSERT_LE(std::abs(y1 - y0), bound * std::abs(d) + 1e-12);
  }
}

TEST(Preisach, InputScalingIsExact) {
  std::mt19937 rng(19);
  const PreisachGrid grid{0.2, 2.45, 10};
  const PreisachModel model = random_model(rng, grid);
  const PreisachModel scaled = model.with_input_scale(0.5);  // G[u] = model[u / 2]
  PreisachState a = PreisachState::negative_saturation(grid);
  PreisachState b = PreisachState::negative_saturation(scaled.grid());
  for (double u : random_history(rng, scaled.grid(), 200)) {
    ASSERT_NEAR(scaled.step(b, u), model.step(a, 0.5 * u), 1e-12);
  }
}

TEST(Preisach, RejectsBadParametersWithAReason) {
  EXPECT_THROW_MSG(PreisachModel(PreisachGrid{1.0, 1.0, 4}, Eigen::VectorXd::Zero(10), 0.0),
                   InvalidArgument, "lo < hi");
  EXPECT_THROW_MSG(PreisachModel(PreisachGrid{0.0, 1.0, 4}, Eigen::VectorXd::Zero(9), 0.0),
                   InvalidArgument, "needs 10 weights");
  const PreisachGrid g{0.0, 1.0, 4};
  EXPECT_THROW_MSG(PreisachState::from_turning_points(g, {0.0, 0.5, 0.7}), InvalidArgument,
                   "alternate");
  const PreisachState s = PreisachState::from_turning_points(g, {0.0, 0.9, 0.1, 0.5});
  EXPECT_EQ(s.depth(), 3);
}

}  // namespace
}  // namespace scpkit

namespace scpkit {
namespace {

TEST(Preisach, CachedStepsAgreeWithAFreshEvaluationAcrossModels) {
  std::mt19937 rng(20);
  const PreisachGrid grid{0.0, 1.0, 15};
  const PreisachModel a = random_model(rng, grid), b = random_model(rng, grid);
  PreisachState s = PreisachState::negative_saturation(grid);
  for (double u : random_history(rng, grid, 500)) {
    s.apply(u);
    // The same state read by two models in turn, and a cache-free copy rebuilt from points.
    const auto pts = s.turning_points();
    const PreisachState fresh =
        PreisachState::from_turning_points(grid, std::vector<double>(pts.begin(), pts.end()));
    ASSERT_NEAR(a.output(s), a.output(fresh), 1e-12);
    ASSERT_NEAR(b.output(s), b.output(fresh), 1e-12);
  }
}

}  // namespace
}  // namespace scpkit

namespace scpkit {
namespace {

TEST(Preisach, AverageOfShiftedGridsIsOnePreisachOperator) {
  std::mt19937 rng(22);
  const int L = 6, S = 3;
  const double lo = 0.0, hi = 1.2, h = (hi - lo) / L;
  std::vector<PreisachModel> models;
  for (int k = 0; k < S; ++k) {
    const double lk = lo - k * h / S;
    const int levels = L + (k > 0 ? 1 : 0);
    models.push_back(random_model(rng, PreisachGrid{lk, lk + levels * h, levels}));
  }
  const PreisachGrid fine{lo - (S - 1) * h / S, lo + (L + 1) * h, (L + 1) * S + S - 1};
  const PreisachModel mean = average_on_fine_grid(models, fine);
  std::vector<PreisachState> states;
  states.reserve(models.size());
  for (const auto& m : models) states.push_back(PreisachState::negative_saturation(m.grid()));
  PreisachState fs = PreisachState::negative_saturation(fine);
  std::uniform_real_distribution<double> U(lo, hi);
  for (int t = 0; t < 400; ++t) {
    const double u = U(rng);
    double expect = 0.0;
    for (int k = 0; k < S; ++k) expect += models[k].step(states[k], u) / S;
    ASSERT_NEAR(mean.step(fs, u), expect, 1e-10);
  }
  EXPECT_THROW_MSG(average_on_fine_grid(models, PreisachGrid{lo + 0.01, hi, 7}), InvalidArgument,
                   "not a node");
}

}  // namespace
}  // namespace scpkit
