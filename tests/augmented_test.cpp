// The augmented model on the rig's voltage tests: paper 000's findings in kind, the refusal of
// an f2 that crosses zero, and open-loop tracking of sinusoidal targets at several loads.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "scpkit/error.hpp"
#include "scpkit/identification/augmented_fit.hpp"
#include "scpkit/io/measurement.hpp"
#include "scpkit/rig/rig.hpp"
#include "test_support.hpp"

namespace scpkit {
namespace {

struct VoltageData {
  std::vector<double> load, v, y;
  std::vector<int> seg;
};

VoltageData voltage_test(RigSpec spec) {
  spec.test = "voltage";
  spec.length_mm = 70.0;
  const RigRun run = run_rig(spec, Material{});
  const Measurement m = Measurement::parse(run.to_csv(), "rig.csv");
  VoltageData d{m.find(Quantity::kLoad)->values,
                m.find(Quantity::kVoltage)->values,
                select_response(m).values,
                {}};
  for (double s : m.find(Quantity::kSegment)->values) d.seg.push_back(static_cast<int>(s));
  return d;
}

std::vector<char> starts_of(const std::vector<int>& seg) {
  std::vector<char> s(seg.size(), 0);
  for (std::size_t t = 0; t < seg.size(); ++t) s[t] = t == 0 || seg[t] != seg[t - 1];
  return s;
}

TEST(Augmented, ReproducesPaper000FindingsInKind) {
  for (const char* truth : {"gpi", "preisach"}) {
    RigSpec spec;
    spec.voltage.truth = truth;
    const VoltageData id = voltage_test(spec);
    RigSpec other = spec;  // verification: other loads and another protocol
    other.seed = 9;
    other.voltage.loads_g = {35, 55, 75, 95};
    other.voltage.cycles = 3;
    other.voltage.steps_per_half = 7;
    const VoltageData ver = voltage_test(other);
    std::map<std::string, double> verify_rms;
    for (const char* family : {"gpi", "preisach", "linear"}) {
      AugmentedFitOptions o;
      o.family = family;
      const AugmentedFit fit = fit_augmented(id.load, id.v, id.y, id.seg, o);
      const auto y = fit.model.simulate(ver.load, ver.v, starts_of(ver.seg));
      verify_rms[family] = error_metrics(ver.y, y).rms_pct_range;
    }
    // Paper 000 (verification RMS 3.2 / 2.8 / 7.7 %): GPI ~ Preisach << linear. On a GPI
    // truth both hysteretic models get there; on a Preisach truth with a smooth density the
    // GPI's linear envelopes fit less well, but still beat the linear model.
    EXPECT_LT(verify_rms["preisach"], 0.4 * verify_rms["linear"]) << truth;
    if (std::string(truth) == "gpi") {
      EXPECT_LT(verify_rms["gpi"], 0.4 * verify_rms["linear"]) << truth;
      EXPECT_LT(std::abs(verify_rms["gpi"] - verify_rms["preisach"]), 0.25 * verify_rms["linear"])
          << truth;
    } else {
      EXPECT_LT(verify_rms["gpi"], 0.75 * verify_rms["linear"]) << truth;
    }
  }
}

TEST(Augmented, RecoversTheLoadMaps) {
  RigSpec spec;
  spec.noise_mm = 0.0;
  spec.resolution_mm = 0.0;
  const VoltageData d = voltage_test(spec);
  AugmentedFitOptions o;
  const AugmentedFit fit = fit_augmented(d.load, d.v, d.y, d.seg, o);
  const VoltageTruth truth = rig_voltage_truth(spec);
  for (double F : {0.3, 0.5, 0.7, 0.95}) {
    EXPECT_NEAR(fit.model.f1(F), truth.f1(F), 1e-9);
    EXPECT_NEAR(fit.model.f2(F), truth.f2(F), 1e-9);
  }
}

TEST(Augmented, RefusesARangeMapThatCrossesZero) {
  // Two loads whose ranges have opposite signs: f2 must cross zero between them.
  std::vector<double> load, v, y;
  std::vector<int> seg;
  for (int k = 0; k < 2; ++k) {
    for (int i = 0; i <= 20; ++i) {
      const double x = 5.0 * (i <= 10 ? i : 20 - i) / 10.0;
      load.push_back(k == 0 ? 0.3 : 0.9);
      v.push_back(x);
      y.push_back((k == 0 ? -1.0 : 1.0) * 0.01 * x);
      seg.push_back(k);
    }
  }
  EXPECT_THROW_MSG(fit_augmented(load, v, y, seg, AugmentedFitOptions{}), IdentificationError,
                   "crosses zero");
  EXPECT_THROW_MSG(
      fit_augmented(std::vector<double>(21, 0.3), std::vector<double>(v.begin(), v.begin() + 21),
                    std::vector<double>(y.begin(), y.begin() + 21), {}, AugmentedFitOptions{}),
      IdentificationError, "two or more loads");
}

TEST(Augmented, TracksSinusoidalTargetsOpenLoopAtSeveralLoads) {
  // Paper 000 Fig. 12 in kind: the inverse of the identified model drives the rig's truth.
  RigSpec spec;
  const VoltageData d = voltage_test(spec);
  const VoltageTruth truth = rig_voltage_truth(spec);
  for (const char* family : {"gpi", "preisach"}) {
    AugmentedFitOptions o;
    o.family = family;
    const AugmentedFit fit = fit_augmented(d.load, d.v, d.y, d.seg, o);
    for (double grams : {40.0, 70.0, 95.0}) {
      const double F = grams * 9.80665e-3;
      std::vector<double> load(200, F), target(200);
      for (int t = 0; t < 200; ++t) {  // between 15 % and 85 % of the stroke
        target[t] = truth.f1(F) - truth.f2(F) * (0.5 - 0.35 * std::cos(2 * M_PI * t / 50.0));
      }
      std::vector<char> starts(200, 0);
      starts[0] = 1;
      const auto steps = fit.model.invert(load, target, starts);
      std::vector<double> u;
      u.reserve(steps.size());
      for (const auto& s : steps) u.push_back(s.input);
      AugmentedModel plant;  // the truth
      plant.f1 = truth.f1;
      plant.f2 = truth.f2;
      plant.h = truth.h;
      plant.load_min = 0.29;
      plant.load_max = 0.99;
      const auto y = plant.simulate(load, u, starts);
      double worst = 0.0;
      for (int t = 0; t < 200; ++t) worst = std::max(worst, std::abs(y[t] - target[t]));
      EXPECT_LT(worst / truth.f2(F), 0.06) << family << " at " << grams << " g";
    }
  }
}

TEST(Augmented, LonelyBeatsPreisachBeatsPoly2OnALonelyStrokeForBothLoadChanges) {
  // Paper 001 in kind (identification 0.09 < 0.59 < 1.36 %), for the load decrease of the
  // paper and the load increase it leaves open.
  for (const std::vector<double>& loads :
       {std::vector<double>{100, 50}, std::vector<double>{50, 100}}) {
    RigSpec spec;
    spec.seed = 11;
    spec.voltage.loads_g = loads;
    spec.voltage.cycles = 3;
    spec.voltage.steps_per_half = 12;
    spec.voltage.dwell_s = 10;
    spec.voltage.truth = "preisach";
    spec.resolution_mm = 0.0;
    spec.noise_mm = 0.002;
    spec.effects.lonely_stroke = 0.08;
    const VoltageData id = voltage_test(spec);
    spec.seed = 12;
    spec.voltage.cycles = 2;
    const VoltageData ver = voltage_test(spec);
    std::map<std::string, std::pair<double, double>> err;  // identification, validation
    for (const char* family : {"lonely", "preisach", "poly2"}) {
      AugmentedFitOptions o;
      o.family = family;
      const AugmentedFit fit = fit_augmented(id.load, id.v, id.y, id.seg, o);
      std::vector<char> starts(ver.seg.size(), kContinue);
      for (std::size_t t = 0; t < starts.size(); ++t) {
        if (t == 0 || ver.seg[t] != ver.seg[t - 1]) {
          starts[t] = t > 0 && ver.load[t] > ver.load[t - 1] ? kRestartAfterLoadIncrease : kRestart;
        }
      }
      err[family] = {
          fit.train.rms_pct_range,
          error_metrics(ver.y, fit.model.simulate(ver.load, ver.v, starts)).rms_pct_range};
    }
    EXPECT_LT(err["lonely"].first, err["preisach"].first) << loads[0];
    EXPECT_LT(err["preisach"].first, err["poly2"].first) << loads[0];
    EXPECT_LT(err["lonely"].second, err["preisach"].second) << loads[0];
    EXPECT_LT(err["preisach"].second, err["poly2"].second) << loads[0];
  }
}

TEST(Augmented, InverseFollowsLoadChangesWithoutRestartingTheMemory) {
  RigSpec spec;
  const VoltageData d = voltage_test(spec);
  const AugmentedFit fit = fit_augmented(d.load, d.v, d.y, d.seg, AugmentedFitOptions{});
  // A record with the load switched mid-way (paper 001: 400 g -> 200 g style), one segment.
  std::vector<double> load, v;
  for (int t = 0; t < 120; ++t) {
    load.push_back(t < 60 ? 0.9 : 0.45);
    v.push_back(2.5 + 2.4 * std::sin(t / 7.0));
  }
  std::vector<char> starts(120, 0);
  starts[0] = 1;
  const auto y = fit.model.simulate(load, v, starts);
  const auto steps = fit.model.invert(load, y, starts);
  for (int t = 0; t < 120; ++t) {
    ASSERT_TRUE(steps[t].reached);
    ASSERT_NEAR(steps[t].output, y[t], 1e-9) << t;
  }
}

}  // namespace
}  // namespace scpkit
