// Real data nobody on this project made (../shared/datasets, read in place, never copied):
// the SMA wire's first-order reversal curves, identified on segments 0,1,3,5,7,9 and predicted
// on 2,4,6,8,10. The seeds' recipe (L = 10, NNLS + bias, one grid) gets 0.97 % RMS and
// 3.8 % max of range there; the defaults must beat it. Skipped when the folder is absent.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "scpkit/diagnosis/specimen_change.hpp"
#include "scpkit/hysteresis/operator.hpp"
#include "scpkit/identification/preisach_fit.hpp"
#include "scpkit/io/measurement.hpp"
#include "test_support.hpp"

namespace scpkit {
namespace {

struct Split {
  std::vector<double> u, y;
  std::vector<int> seg;
};

Split segments(const Measurement& m, const std::set<int>& keep) {
  Split s;
  const auto& u = select_input(m).values;
  const auto& y = select_response(m).values;
  const auto& g = m.find(Quantity::kSegment)->values;
  for (std::size_t t = 0; t < u.size(); ++t) {
    if (keep.count(static_cast<int>(g[t]))) {
      s.u.push_back(u[t]);
      s.y.push_back(y[t]);
      s.seg.push_back(static_cast<int>(g[t]));
    }
  }
  return s;
}

ErrorMetrics heldout(const PreisachModel& model, const Split& test) {
  PreisachState s = PreisachState::negative_saturation(model.grid());
  const Eigen::VectorXd p = model.simulate(s, test.u);
  return error_metrics(test.y, std::span<const double>(p.data(), test.y.size()));
}

TEST(Datasets, SmaReversalCurvesHeldOutBeatTheSeedsRecipe) {
  const auto dir = testing::shared_dir();
  if (dir.empty()) GTEST_SKIP() << "../shared/datasets not found: skipping the real-data check";
  const Measurement m = Measurement::read(dir / "datasets" / "sma-wire-forc.csv");
  const Split train = segments(m, {0, 1, 3, 5, 7, 9}), test = segments(m, {2, 4, 6, 8, 10});

  PreisachFitOptions seeds;  // the papers' recipe
  seeds.levels = 10;
  seeds.smoothness = 0.0;
  seeds.grid_shifts = 1;
  const ErrorMetrics e_seeds =
      heldout(fit_preisach(train.u, train.y, train.seg, seeds).model, test);
  EXPECT_NEAR(e_seeds.rms_pct_range, 0.97, 0.01);  // reproduces the number quoted in the issue
  EXPECT_NEAR(e_seeds.max_pct_range, 3.8, 0.05);

  const PreisachFit fit = fit_preisach(train.u, train.y, train.seg, PreisachFitOptions{});
  const ErrorMetrics e = heldout(fit.model, test);
  EXPECT_LT(e.rms_pct_range, 0.85);
  EXPECT_LT(e.max_pct_range, 3.5);

  // The inverse on the held-out measured response: voltages that, fed back through the model,
  // reproduce every reachable target.
  const HysteresisOperator op(fit.model, fit.input_min, fit.input_max);
  const std::vector<InverseStep> inv = op.invert(test.y);
  std::vector<double> u;
  u.reserve(inv.size());
  for (const auto& s : inv) u.push_back(s.input);
  const std::vector<double> again = op.simulate(u);
  int reached = 0;
  for (std::size_t t = 0; t < inv.size(); ++t) {
    if (!inv[t].reached) continue;
    ++reached;
    ASSERT_NEAR(again[t], test.y[t], 1e-9) << t;
    ASSERT_GE(u[t], fit.input_min);
    ASSERT_LE(u[t], fit.input_max);
  }
  EXPECT_EQ(reached, static_cast<int>(inv.size()));
}

// The precursor fibre dry and after 1 and 4 days of moisture (one heating/cooling loop each):
// compared with the dry test, the moist ones change (water makes the fibre contract more), the
// range factor grows with the days, and it agrees with the ratio of the files' own contraction
// ranges, computed here from the readings alone. The dry test against itself names nothing.
TEST(Datasets, MoistFibreAgainstDryNamesAGrowingStroke) {
  const auto dir = testing::shared_dir();
  if (dir.empty()) GTEST_SKIP() << "../shared/datasets not found: skipping the real-data check";
  auto read = [&](const char* name) {
    const Measurement m = Measurement::read(dir / "datasets" / name);
    return std::pair{select_input(m).values, select_response(m).values};
  };
  const auto [ud, yd] = read("tcp-precursor-fibre-dry.csv");
  const auto span = [](const std::vector<double>& y) {
    return *std::max_element(y.begin(), y.end()) - *std::min_element(y.begin(), y.end());
  };
  EXPECT_EQ(diagnose_specimen_change(ud, yd, ud, yd).change, "none");
  double last_g = 1.0;
  for (const char* name :
       {"tcp-precursor-fibre-moist-1d.csv", "tcp-precursor-fibre-moist-4d.csv"}) {
    const auto [u, y] = read(name);
    const SpecimenChange d = diagnose_specimen_change(ud, yd, u, y);
    EXPECT_NE(d.change, "none") << name;
    EXPECT_NE(d.change, "offset") << name;
    const double g = d.candidates[2].g, ratio = span(y) / span(yd);
    EXPECT_GT(g, 1.5 * last_g) << name;
    EXPECT_NEAR(g, ratio, 0.2 * ratio) << name;
    last_g = g;
  }
}

}  // namespace
}  // namespace scpkit
