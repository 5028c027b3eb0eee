// diagnose on rig data with an effect hidden in it: it must name the effect, and name nothing
// on clean data, over several seeds, magnitudes, noise levels and protocols (not one file).
// The scenarios come from tests/diagnose_scenarios.cpp; the full confusion matrix over many
// more of them is tests/diagnose_confusion.cpp (docs/diagnose-confusion.md).
#include "scpkit/diagnosis/diagnose.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <tuple>
#include <utility>

#include "diagnose_scenarios.hpp"
#include "scpkit/error.hpp"
#include "test_support.hpp"

namespace scpkit {
namespace {

using testing::make_scenario;

using Adjust = std::function<void(RigSpec&)>;

using Check = std::function<void(const Diagnosis&)>;

void expect_named(const std::string& side, const std::string& effect,
                  const std::vector<int>& indices, const Adjust& adjust = {},
                  const Check& check = {}) {
  for (int i : indices) {
    testing::Scenario s = make_scenario(side, effect, i);
    if (adjust) adjust(s.spec);
    const Diagnosis d = testing::diagnose_scenario(s);
    if (check) check(d);
    std::string why;
    for (const Finding& f : d.findings) why += "\n  " + f.effect + ": " + f.evidence;
    EXPECT_EQ(d.cause, effect) << s.describe() << why;
    for (const Finding& f : d.findings) {
      EXPECT_GT(f.heldout_rms_before, 0.0) << f.effect;
      if (!f.tested) {
        EXPECT_FALSE(f.detected) << f.effect;
      }
      // A detected effect's extension gains on held-out data (but for a lonely stroke on one
      // record, named by its return-point offset: its gain cannot be measured there).
      if (f.detected && f.evidence.find("named by this signature alone") == std::string::npos) {
        EXPECT_LT(f.heldout_rms_after, f.heldout_rms_before) << f.effect;
      }
    }
  }
}

const Finding& finding(const Diagnosis& d, const std::string& effect) {
  return *std::find_if(d.findings.begin(), d.findings.end(),
                       [&](const Finding& f) { return f.effect == effect; });
}

// The per-fold trends a drift's extended_model lists ("... per fold, % of range: 2.4, 9.1 (k 3),
// ...)"), each fold's note in parentheses skipped; empty where it lists none.
std::vector<double> per_fold_trends(const std::string& m) {
  const std::string key = "per fold, % of range: ";
  std::vector<double> values;
  std::size_t at = m.find(key);
  if (at == std::string::npos) return values;
  for (at += key.size(); at < m.size() && m[at] != ')';) {
    std::size_t used = 0;
    values.push_back(std::stod(m.substr(at), &used));
    at += used;
    while (at < m.size() && m[at] == ' ') ++at;
    if (at < m.size() && m[at] == '(') at = m.find(')', at) + 1;  // the fold's note
    while (at < m.size() && (m[at] == ',' || m[at] == ' ')) ++at;
  }
  return values;
}

TEST(Diagnose, LoadTestsCleanDriftOutliersCreep) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  // On clean data the Kelvin creep extension may choose no creep, and does: it loses nothing
  // on held-out cycles (it lost 2-84 % when every fold was forced to creep).
  expect_named("load", "none", {0, 1, 2}, {},
               [](const Diagnosis& d) { EXPECT_GT(finding(d, "creep").gain_pct, -1.0); });
  expect_named("load", "drift", {1, 2});
  expect_named("load", "outliers", {0, 1});
  expect_named("load", "creep", {11});  // the largest creep level; the rest: the confusion matrix
}

// Readings during holds and loops between the same extrema from two histories give the
// model-free signatures something to test; on clean data they must still find nothing.
TEST(Diagnose, CleanDataWithHoldReadingsAndCongruencyLoopsIsNone) {
  expect_named("load", "none", {3}, [](RigSpec& r) {
    r.protocol.readings_per_hold = 3;
    r.protocol.congruency = true;
  });
}

// Noise-free clean records: the noise floor is nearly zero, so only the baseline's own
// approximation error (and on load tests the specimen's virgin first stroke) is left; neither
// is a finding.
TEST(Diagnose, NoiseFreeCleanDataIsNone) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  auto exact = [](RigSpec& r) {
    r.noise_mm = 0.0;
    r.resolution_mm = 0.0;
  };
  expect_named("load", "none", {0}, exact);
  expect_named("load", "none", {2}, [&](RigSpec& r) {
    exact(r);
    r.protocol.shape = "repeated";
  });
  expect_named("voltage", "none", {1}, exact);
}

// Sensor noise correlated in time, AR(1): e_t = rho e_{t-1} + sqrt(1 - rho^2) sigma w_t. Its first
// differences spread as sigma sqrt(1 - rho) only, so a floor taken from them alone is 0.63 sigma
// at rho 0.6, and a clean record's held-out error, at about sigma, passed 2 x floor as material:
// a third-generator clean record with AR(1) noise (rho 0.6) was `unexplained` that way
// (docs/diagnose-log.md, session 31). The floor now includes the noise's lag-one correlation from
// the spreads of its first and second differences. On noise-free rig records with AR(1) noise
// added: the records are `none`; with white noise the floor is sigma to within the estimate's
// spread; at rho 0.6 its median is near sigma, where the first differences alone give 0.63
// sigma. The misfit between neighbouring readings enters the ratio of spreads too: on these
// six records at rho 0.6 the floor was 0.60-1.46 sigma (median 0.94), low where the ratio read
// structure (a load record, eight readings per half cycle), high where the misfit added to
// the ratio (two voltage records, rho read at 0.76 and the 0.8 cap).
TEST(Diagnose, NoiseFloorIncludesTheNoiseCorrelationInTime) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  std::mt19937_64 rng(31);
  int i = 0;
  std::vector<double> correlated;
  for (const std::string side : {"load", "voltage"}) {
    for (const double rho : {0.0, 0.6, 0.6, 0.6}) {
      testing::Scenario s = make_scenario(side, "none", i++);
      s.spec.noise_mm = 0.0;
      s.spec.resolution_mm = 0.0;
      DiagnoseData data = testing::scenario_data(s);
      const auto [lo, hi] = std::minmax_element(data.output.begin(), data.output.end());
      const double sigma = std::uniform_real_distribution<double>(0.003, 0.008)(rng) * (*hi - *lo);
      std::normal_distribution<double> w(0.0, sigma * std::sqrt(1.0 - rho * rho));
      double e = std::normal_distribution<double>(0.0, sigma)(rng);
      for (double& y : data.output) {
        y += e;
        e = rho * e + w(rng);
      }
      const auto [nlo, nhi] = std::minmax_element(data.output.begin(), data.output.end());
      const double sigma_pct = 100.0 * sigma / (*nhi - *nlo);
      DiagnoseOptions o;
      o.seed = s.spec.seed;
      const Diagnosis d = diagnose(data, o);
      const double ratio = d.noise_floor_pct_range / sigma_pct;
      const std::string what = s.describe() + fmt::format(
                                                  ", AR(1) noise rho {} sigma {:.3f} % of range: "
                                                  "floor {:.3f} sigma",
                                                  rho, sigma_pct, ratio);
      EXPECT_EQ(d.cause, "none") << what << "; " << d.cause_note;
      if (rho == 0.0) {
        EXPECT_GT(ratio, 0.8) << what;
        EXPECT_LT(ratio, 1.35) << what;
      } else {
        EXPECT_LT(ratio, 1.6) << what;
        correlated.push_back(ratio);
      }
    }
  }
  std::sort(correlated.begin(), correlated.end());
  const double median = 0.5 * (correlated[2] + correlated[3]);
  EXPECT_GT(median, 0.85) << fmt::format("floors {} sigma", fmt::join(correlated, ", "));
}

// Creep read during holds: the readings move on in the direction of the last step. Found at
// the smallest magnitude (10 % of the strain viscous) on load tests with two noise levels and
// hold patterns, and at 20 % on voltage tests (more in the confusion matrix).
// (Two tests, so that ctest -j runs the two sides side by side: under the sanitizers this was
// the suite's longest test.)
TEST(Diagnose, CreepSeenDuringHoldsOnLoadTests) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  expect_named("load", "creep", {0, 3}, [](RigSpec& r) { r.protocol.readings_per_hold = 3; });
}

TEST(Diagnose, CreepSeenDuringHoldsOnVoltageTests) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  expect_named("voltage", "creep", {1}, [](RigSpec& r) { r.voltage.readings_per_hold = 3; });
}

// Creep ten and thirty holds slow (tau 100 and 300 s, 10 s holds read twice, a 0.04 mm sensor
// step): a held reading moves by less than the sensor resolves, so the readings during holds
// show nothing, while the lag carried from step to step builds up along the path. The Kelvin
// element fitted through the filter names it by its held-out gain (session 46; before, the
// Prony series of 0.3-3 holds gained -3.9 to 4.4 % on these and they were named unexplained,
// drift and none). The same protocols without creep are none.
TEST(Diagnose, CreepMuchSlowerThanTheHoldsReadDuringHolds) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  struct Case {
    std::uint64_t seed;
    double noise_mm, creep, tau_s;
  };
  for (const Case& c :
       {Case{502, 0.01, 0.3, 100.0}, Case{502, 0.01, 0.3, 300.0}, Case{506, 0.005, 0.1, 100.0},
        Case{502, 0.01, 0.0, 100.0}, Case{506, 0.005, 0.0, 100.0}}) {
    testing::Scenario s = make_scenario("load", "none", 0);
    RigSpec& r = s.spec;
    r.seed = c.seed;
    r.specimen = "thread";
    r.plies = 4;
    r.noise_mm = c.noise_mm;
    r.protocol = LoadProtocol{};
    r.protocol.cycles = 6;
    r.protocol.minor_loops = 2;
    r.protocol.readings_per_hold = 2;
    r.protocol.dwell_s = 10.0;
    r.effects = RigEffects{};
    r.effects.creep = c.creep;
    r.effects.creep_tau_s = c.tau_s;
    const Diagnosis d = testing::diagnose_scenario(s);
    EXPECT_EQ(d.cause, c.creep > 0.0 ? "creep" : "none")
        << "seed " << c.seed << " creep " << c.creep << " tau " << c.tau_s << " s";
  }
}

// Creep slower than the holds (PHYSICS.md: time constants 1-100 s against 10-180 s dwells),
// one reading per hold: the lag accumulates over several steps, which no loop width mimics.
TEST(Diagnose, CreepSlowerThanTheHolds) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  expect_named("load", "creep", {2, 5},
               [](RigSpec& r) { r.effects.creep_tau_s = 5.0 * r.protocol.dwell_s; });
}

// One reading per hold, holds of different lengths: a creep fraction of 0.1 at 0.01 and 0.02 mm
// noise (indices 0 and 3) leaves the baseline at the noise floor, where neither the Kelvin
// nor the Prony extension gains; its residuals follow the hold times (the permutation test of
// dwell_signature) and name it. Clean records with holds of different lengths, on both
// sides, are `none`: their residuals cannot follow the hold times.
TEST(Diagnose, CreepFollowingTheHoldTimesIsNamedWithOneReadingPerHold) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  expect_named("load", "creep", {0, 3}, [](RigSpec& r) { r.protocol.dwell_spread = 0.5; });
  expect_named("load", "none", {0, 1, 2}, [](RigSpec& r) {
    r.protocol.dwell_spread = 1.0;
    r.protocol.readings_per_hold = 1;
  });
  expect_named("voltage", "none", {0, 1}, [](RigSpec& r) {
    r.voltage.dwell_spread = 1.0;
    r.voltage.readings_per_hold = 1;
  });
}

// Voltage tests: a drift with the loads tested in increasing order (the offset map cannot
// separate it from f1; the trend inside each segment can), and spikes where the screen used
// to miss them: on rows never held out (the extreme loads, screened on in-sample residuals)
// and at an input reversal (index 8: the spike is the peak reading of a cycle).
// (Index 2, the same protocol on a Preisach truth, is now named lonely_stroke: its baseline is
// already at the noise floor, and the one-sign running-maximum term gains 5.5 % there against
// the trend's 2.5 %; docs/diagnose.md.)
TEST(Diagnose, VoltageDriftInLoadOrderAndSpikesAnywhere) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  expect_named("voltage", "drift", {5});
  expect_named("voltage", "outliers", {0, 8});
}

// Non-congruent minor loops (the rig's output-dependent loop height) between the same
// extrema from two histories, read by a sensor that resolves the difference (0.004 mm steps):
// named, and the extension gains on held-out cycles, at the largest magnitude on damped and
// repeated protocols (indices 2, 5, 8). At 0.4-0.7 with this sensor it is found in 1 of 6
// (measured); with the 0.04 mm sensor rarely (the confusion matrix, docs/diagnose.md).
TEST(Diagnose, NoncongruenceFoundWhereTheSensorResolvesIt) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  expect_named("load", "minor_loop_noncongruence", {2, 5, 8}, [](RigSpec& r) {
    r.resolution_mm = 0.004;
    r.noise_mm = 0.005;
  });
}

// With the rig's 0.04 mm sensor the output-map extension does not gain on this scenario
// (+0.3 %), but the congruency test, F-calibrated, is far beyond what clean records give
// (p = 4e-4; the smallest on 15 clean load records 0.0073): named by the signature alone.
TEST(Diagnose, NoncongruenceNamedByItsSignatureAlone) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  expect_named("load", "minor_loop_noncongruence", {7}, {}, [](const Diagnosis& d) {
    const Finding& f = finding(d, "minor_loop_noncongruence");
    EXPECT_LT(f.p_value, 0.001);
    EXPECT_NE(f.evidence.find("named by this signature alone"), std::string::npos);
  });
}

// The output map x + c x (x - 1), its candidates symmetric about c = 0 (session 24), models
// this scenario's loops, which the one-sided map w + c w^2 (c in -0.2 .. 0.8) did not: it
// lost 2.7 % on held-out cycles and the record was named by its signature alone (p = 4e-5);
// the symmetric map gains 15.4 % (sign-flip p = 0.001).
TEST(Diagnose, NoncongruenceModelledByTheSymmetricOutputMap) {
  expect_named("load", "minor_loop_noncongruence", {20}, {}, [](const Diagnosis& d) {
    const Finding& f = finding(d, "minor_loop_noncongruence");
    EXPECT_GE(f.gain_pct, 5.0);
    EXPECT_LT(f.heldout_rms_after, f.heldout_rms_before);
    EXPECT_EQ(f.evidence.find("named by this signature alone"), std::string::npos);
  });
}

// Under the rig's 0.04 mm step, over twice the white noise, the output map's gain alone is not
// trusted (rounding repeats in every cycle); confirmed by the congruency signature at
// gain_alpha it names the effect although it gains under 5 %, which no other route names
// (session 38: indices 4 and 11, a = 0.7 and 1 at 0.005 and 0.01 mm noise, gains 4.4 and 4.8 %
// at p = 0.002 and 0.006, signatures at p = 0.018 and 0.014, were `none`). Since session 72
// the signature reads its pairs' shared readings, and those two are at p = 0.33 and 0.084
// (docs/diagnose-log.md, "Session 72"); index 30 (a = 0.4, 0.02 mm noise) is named this way:
// the map gains 2.1 % at p = 0.001, the signature at p = 0.0063.
TEST(Diagnose, NoncongruenceGainConfirmedByItsSignature) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  expect_named("load", "minor_loop_noncongruence", {30}, {}, [](const Diagnosis& d) {
    const Finding& f = finding(d, "minor_loop_noncongruence");
    EXPECT_LT(f.p_value, 0.05);  // the signature, at gain_alpha
    EXPECT_GT(f.gain_pct, 0.0);
    EXPECT_LT(f.gain_pct, 5.0);  // under the 5 % every other route needs
  });
}

// Paper 001's protocol: one load change (100 -> 50 g, and 50 -> 100 g), a damped voltage
// oscillation at each load. The lonely stroke happens once per segment; the two segments'
// first cycles sit in different folds, so every fold trains on one of them. Clean records of
// the same protocol, and at one constant load (the file's single segment id is no fold), are
// `none`.
TEST(Diagnose, LonelyStrokeAfterOneLoadChange) {
  for (const std::vector<double>& loads : {std::vector<double>{100, 50}, {50, 100}}) {
    const auto protocol = [&](RigSpec& r) {
      r.voltage.loads_g = loads;
      r.voltage.cycles = 3;
      // Paper 001's sign: with one load change each fold holds out one of the two first
      // rises, so the sign after the increase cannot be learned and its pattern is assumed.
      r.effects.lonely_sign_after_increase = -1.0;
    };
    expect_named("voltage", "lonely_stroke", {2}, protocol);
    expect_named("voltage", "none", {1}, protocol);
  }
  expect_named("voltage", "none", {2}, [](RigSpec& r) { r.voltage.loads_g = {100}; });
}

// One voltage record at one constant load, full cycles 0 -> v_max -> 0 V (paper 001's
// training cycles): readings in the same memory state before and after the first rise (0 V
// resets every hysteron of a plane on the tested voltages) differ by the lonely stroke, and
// the running-maximum term gains on held-out cycles, or, where the first rise's fold cannot
// train it, the offset alone names it in place of `unexplained`. Clean records: `none`.
// (Index 0 at 70 g, a 3 % stroke, is left out since session 28: its offset's p went from
// 8e-5 to 0.0045 once the test credits the readings its pairs share and the noise's lag-one
// correlation, 0.37 on its plain pairs; short of alpha / 10, it is `none`.)
TEST(Diagnose, LonelyStrokeOnOneLoadIsNamedByItsReturnPointOffset) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  for (const double load : {40.0, 70.0, 100.0}) {
    const auto one_load = [&](RigSpec& r) {
      r.voltage.loads_g = {load};
      r.voltage.shape = "repeated";
      r.voltage.cycles = 4;
    };
    expect_named("voltage", "lonely_stroke",
                 load == 70.0 ? std::vector<int>{1, 2} : std::vector<int>{0, 1, 2}, one_load);
    expect_named("voltage", "none", {0, 1, 2, 3, 4, 5, 6, 7}, one_load);
  }
}

// Paper 001 leaves the lonely stroke's sign after a load increase open (the rig's default
// flips it); with one sign after every load change it is found too, loads in increasing order
// (index 0) and shuffled (1): the extension chooses the pattern on each fold's training
// rows, the return-point test takes either sign per class. The baseline starts each segment
// preconditioned (PreisachState::after_cycle), so its shifted grids cannot absorb the stroke:
// from negative saturation they did, and no extension gained.
TEST(Diagnose, LonelyStrokeOfOneSignAfterEveryLoadChange) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  expect_named("voltage", "lonely_stroke", {0, 1},
               [](RigSpec& r) { r.effects.lonely_sign_after_increase = 1.0; });
}

// One load increase, the last of four loads: the fold that holds it out has no first rise
// after an increase to train, so the sign there is unknown, and that segment's first rise gets
// no term. The term is 0 once a segment's input has reached its top, so the offsets the maps
// predict for held-out loads carry no guessed sign. With lambda m they did: on these records
// the extension lost 168, 427 and 636 % of held-out E_RMS (a second-generator record: 212 %,
// and `creep` was named).
TEST(Diagnose, LonelyStrokeWithItsOnlyLoadIncreaseHeldOut) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  for (int i : {0, 1, 2}) {
    testing::Scenario s = make_scenario("voltage", "lonely_stroke", i);
    s.spec.voltage.loads_g = {120, 60, 30, 100};
    s.spec.effects.lonely_sign_after_increase = 1.0;
    const Diagnosis d = testing::diagnose_scenario(s);
    EXPECT_GT(finding(d, "lonely_stroke").gain_pct, -10.0) << s.describe();
  }
}

// Paper 001's pattern at six and eight loads: the rig's later cycles keep the first rise's
// offset (the running-maximum term lambda m), with the opposite sign after a load increase, so
// the offsets of the repeatable loops zigzag with the order of the loads. The term written as
// the first rise's departure alone, lambda (m - m_top), left that zigzag to the offset map,
// which cannot follow it: 5 of the confusion matrix's 12 rig lonely strokes were named (these
// two `none` and `unexplained`), 11 once each fold takes the form whose trained offsets its
// quadratic map follows more closely.
TEST(Diagnose, LonelyStrokeWhoseLaterCyclesKeepTheOffset) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  expect_named("voltage", "lonely_stroke", {1, 11});
}

// Spikes of 6-12 % of the nominal range, a few times the baseline's own error: flagged at 6 robust
// sigmas (largest on records without spikes: 5.5) and named once the baseline identified
// afresh without them gains on the other readings (beyond 8 sigmas: anything; between 6 and
// 8: at least 5 %, significantly), or they stand beyond 10.
TEST(Diagnose, ModestSpikesAreNamed) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  expect_named("load", "outliers", {1, 2}, [](RigSpec& r) { r.effects.outliers = 0.06; });
  expect_named("voltage", "outliers", {2}, [](RigSpec& r) { r.effects.outliers = 0.06; });
}

// Spikes among the readings of one hold, where no other tier looks: in the first rise of a
// load test (never fitted, never scored: it sets the memory) and in the first segment of a
// test at several loads. A rate-independent response reads alike through a hold, and creep
// moves it along its step; 5 % of the range against the mates' scatter is a spike whatever
// the model (second independent generator: spikes of 12-25 noise sigmas there were named
// `none`). Clean records with the same holds stay `none`
// (CleanDataWithHoldReadingsAndCongruencyLoopsIsNone), and creep read during holds stays
// `creep` (CreepSeenDuringHoldsOnLoadTests, CreepSeenDuringHoldsOnVoltageTests).
TEST(Diagnose, SpikesAmongHoldMatesAreNamed) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  int named = 0, tried = 0;
  std::string missed;
  for (const std::string side : {"load", "voltage"}) {
    for (int index = 0; index < (side == "load" ? 4 : 2); ++index) {
      testing::Scenario s = make_scenario(side, "none", index);
      s.spec.protocol.readings_per_hold = 2 + index % 3;
      s.spec.voltage.readings_per_hold = 2 + index % 3;
      DiagnoseData data = testing::scenario_data(s);
      const std::vector<double>& u = data.input;
      // The holds' readings before the input first reaches its maximum (in the first segment).
      const auto first_max =
          static_cast<std::size_t>(std::max_element(u.begin(), u.end()) - u.begin());
      std::vector<std::size_t> held;
      for (std::size_t t = 1; t < first_max; ++t) {
        const bool same_segment = data.segments.empty() || data.segments[t] == data.segments[0];
        if (u[t] == u[t - 1] && same_segment) held.push_back(t);
      }
      ASSERT_GE(held.size(), 4U) << s.describe();
      DiagnoseOptions o;
      o.seed = s.spec.seed;
      const auto [lo, hi] = std::minmax_element(data.output.begin(), data.output.end());
      const double spike = 0.05 * (*hi - *lo);
      data.output[held[held.size() / 3]] += spike;
      data.output[held[2 * held.size() / 3]] -= spike;
      const Diagnosis d = diagnose(data, o);
      ++tried;
      if (d.cause == "outliers") {
        ++named;
      } else {
        missed += "\n" + s.describe() + ": " + d.cause + "; " + finding(d, "outliers").evidence;
      }
    }
  }
  EXPECT_GE(named, tried - 1) << missed;
}

// Spikes at turning values (the trough reading of a cycle), where the model's own error may
// kink and a spike must stand twice as far off its neighbours: 5 % of the range, two per
// record, on clean records of both sides whose protocols repeat their turning values (repeated
// load cycles; every load's segment). Removing one or two readings barely moves the other
// readings' fit, so their gain shows little; what names them is that the readings at the same
// point of the protocol (the same memory state) in other cycles and segments do not repeat
// them. Without that comparison both load records here were named `none` (as were three fresh
// records of the independent generator, scripts/independent_cases.py). Not named, measured:
// the same spikes on damped protocols, whose troughs inside the loops are each met once
// (indices 5, 6), and on a repeated one at 0.02 mm noise, where 5 % is six noise sigmas (3).
TEST(Diagnose, SpikesAtTurningValuesAreNamed) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  for (const auto& [side, index] :
       std::vector<std::pair<std::string, int>>{{"load", 1}, {"load", 4}, {"voltage", 3}}) {
    const testing::Scenario s = make_scenario(side, "none", index);
    DiagnoseData data = testing::scenario_data(s);
    const std::vector<double>& u = data.input;
    const std::size_t n = u.size();
    // Turning values at the lowest input after the first maximum (load tests fit nothing
    // before it), away from segment changes: the input before and after lies above.
    const auto first_max =
        static_cast<std::size_t>(std::max_element(u.begin(), u.end()) - u.begin());
    std::vector<std::size_t> turning;
    for (std::size_t t = first_max + 2; t + 2 < n; ++t) {
      if (!data.segments.empty() &&
          (data.segments[t - 1] != data.segments[t] || data.segments[t + 1] != data.segments[t]))
        continue;
      if (u[t - 1] > u[t] && u[t + 1] > u[t]) turning.push_back(t);
    }
    ASSERT_GE(turning.size(), 3U) << s.describe();
    const auto [lo, hi] = std::minmax_element(data.output.begin(), data.output.end());
    const double spike = 0.05 * (*hi - *lo);
    data.output[turning[turning.size() / 3]] += spike;
    data.output[turning[2 * turning.size() / 3]] -= spike;
    DiagnoseOptions o;
    o.seed = s.spec.seed;
    const Diagnosis d = diagnose(data, o);
    EXPECT_EQ(d.cause, "outliers") << s.describe() << "\n  " << finding(d, "outliers").evidence;
  }
}

// A clean rig load scenario on the load sequence `loads` (g), read once per hold, no sensor step.
testing::Scenario protocol_scenario(const std::vector<double>& loads, int index, double noise) {
  testing::Scenario s = make_scenario("load", "none", index);
  s.spec.load_sequence_g = loads;
  s.spec.noise_mm = noise;
  s.spec.resolution_mm = 0.0;
  s.spec.protocol.readings_per_hold = 1;
  return s;
}

// A record of protocol_scenario, its options seeded from the scenario, checked `none` as
// generated (before a test adds its effect); `context` goes into the failure message.
struct ProtocolRecord {
  testing::Scenario scenario;
  DiagnoseData data;
  DiagnoseOptions options;
};
ProtocolRecord clean_protocol_record(const std::vector<double>& loads, int index, double noise,
                                     const std::string& context) {
  ProtocolRecord r{protocol_scenario(loads, index, noise), {}, {}};
  r.data = testing::scenario_data(r.scenario);
  r.options.seed = r.scenario.spec.seed;
  EXPECT_EQ(diagnose(r.data, r.options).cause, "none") << r.scenario.describe() << context;
  return r;
}

// Spikes on the last rise of a protocol whose only repeated rise is the first: cycles from 0 g
// to ever lower tops on step grids of their own (nothing else meets the same memory state),
// then the first cycle again. At 0 g every hysteron is off, so the last rise repeats the first
// reading for reading; the first rise is never scored (it sets the memory), but it is a
// measurement, and a spike on the last rise stands alone against it. Two 5 % spikes per
// record, three seeds at two noise levels; the same records without them stay `none`.
// (Measured on the independent generator's damped protocols: such spikes, 4.9 and 6.8 robust
// sigmas off their neighbours behind a coarse baseline, had no other reading at their protocol
// point and were named `none`. Without the first rise, or with the scale of the deviations
// taken without their largest 5 % only, none of these records is named.)
TEST(Diagnose, SpikesOnTheLastRiseAreComparedWithTheFirst) {
  std::vector<double> loads{0.0};
  const std::vector<std::pair<double, int>> cycles{{250, 8}, {226, 7}, {197, 6},
                                                   {163, 5}, {131, 4}, {250, 8}};
  for (const auto& [top, k] : cycles) {
    for (int j = 1; j <= k; ++j) loads.push_back(top * j / k);
    for (int j = k - 1; j >= 0; --j) loads.push_back(top * j / k);
  }
  const std::size_t last_rise = loads.size() - 16;  // the last cycle's first reading above 20 g
  for (int index = 0; index < 3; ++index) {
    for (const double noise : {0.005, 0.01}) {
      auto [s, data, o] =
          clean_protocol_record(loads, index, noise, " noise " + std::to_string(noise));
      ASSERT_EQ(data.input.size(), loads.size()) << s.describe();
      const auto [lo, hi] = std::minmax_element(data.output.begin(), data.output.end());
      const double spike = 0.05 * (*hi - *lo);
      data.output[last_rise + 1 + static_cast<std::size_t>(index)] += spike;
      data.output[last_rise + 4 + static_cast<std::size_t>(index)] -= spike;
      const Diagnosis d = diagnose(data, o);
      EXPECT_EQ(d.cause, "outliers")
          << s.describe() << " noise " << noise << "\n  " << finding(d, "outliers").evidence;
    }
  }
}

// Bursts: one to three consecutive readings off together (a sensor glitch that lasts a few
// readings), on a protocol of plain triangles read at the same loads each time, 0 to 250 g.
// The middle of a burst is level with its neighbours, so the neighbour statistic misses it,
// and the first rise (never scored) holds it as often as any other; the readings at the same
// point of the other passes do not repeat it. Two passes (a burst then mirrors in the other
// pass's deviations, and the rougher pass holds it) and four; bursts of 6 and 9 % of the range
// in the first rise and in the last descent; the same records without them stay `none`.
// (Measured on the fourth independent generator's bursts: such runs were named `none` and
// `unexplained` before this tier.)
TEST(Diagnose, BurstsOfReadingsAreNamed) {
  for (const int passes : {2, 4}) {
    std::vector<double> loads;
    for (int c = 0; c < passes; ++c) {
      for (int j = 0; j <= 10; ++j) loads.push_back(25.0 * j);
      for (int j = 9; j >= 1; --j) loads.push_back(25.0 * j);
    }
    loads.push_back(0.0);
    for (int index = 0; index < 4; ++index) {
      auto [s, data, o] = clean_protocol_record(loads, index, index % 2 == 0 ? 0.005 : 0.01,
                                                " passes " + std::to_string(passes));
      ASSERT_EQ(data.input.size(), loads.size()) << s.describe();
      const auto [lo, hi] = std::minmax_element(data.output.begin(), data.output.end());
      const double size = (index < 2 ? 0.06 : 0.09) * (*hi - *lo) * (index % 2 == 0 ? 1 : -1);
      const std::size_t length = 1 + static_cast<std::size_t>(index) % 3;
      // In the first rise (index even) or the last descent (odd).
      const std::size_t start = index % 2 == 0 ? 4 : loads.size() - 7;
      for (std::size_t t = start; t < start + length; ++t) data.output[t] += size;
      const Diagnosis d = diagnose(data, o);
      EXPECT_EQ(d.cause, "outliers")
          << s.describe() << " passes " << passes << " burst of " << length << " at " << start
          << "\n  " << finding(d, "outliers").evidence;
    }
  }
}

// A Preisach model on `grid` whose density at (a, b) is `density(a, b)`, taken at each cell's
// centre.
PreisachModel density_model(const PreisachGrid& grid,
                            const std::function<double(double, double)>& density) {
  Eigen::VectorXd w(grid.cells());
  for (int i = 0; i < grid.levels; ++i) {
    for (int j = i; j < grid.levels; ++j) {
      const double b = grid.lo + (i + 0.5) * grid.step(), a = grid.lo + (j + 0.5) * grid.step();
      w[grid.cell_index(i, j)] = density(a, b) * PreisachGrid::relative_area(i, j);
    }
  }
  return PreisachModel(grid, w, 0.0);
}

// First-order reversal curves of a steep phase transformation (the shape of the SMA wire in
// ../shared/datasets), steeper than the baseline's grid follows. Each segment rises from 0 V
// along the major branch, so the readings at one voltage on that branch repeat in every
// segment, alike: the response, not spikes (the real record's four copies of 2.7 V were named
// `outliers`). The falls from the reversal curves' turning values are not repeated, but a
// monotone branch passes through their readings, whose misfit is small against the drop the
// branch takes there. The inputs are written to 4 decimals, as a file holds them, so that the
// rises of different segments meet at the same voltages. Spikes of 5 % added to the same
// records, on the falls, are still named.
DiagnoseData steep_forcs(double width_a, double width_b, unsigned seed) {
  const PreisachGrid grid{0.0, 3.6, 72};
  const PreisachModel model = density_model(grid, [&](double a, double b) {
    return std::exp(-std::pow((a - 2.75) / width_a, 2) - std::pow((b - 2.2) / width_b, 2));
  });
  DiagnoseData data;
  auto ramp = [&](double from, double to, int s) {
    const auto steps = std::lround(std::abs(to - from) / 0.1);
    for (long k = 1; k <= steps; ++k) {
      const double u = from + (to - from) * static_cast<double>(k) / static_cast<double>(steps);
      data.input.push_back(std::round(u * 1e4) / 1e4);
      data.segments.push_back(s);
    }
  };
  data.input.push_back(0.0);
  data.segments.push_back(0);
  ramp(0.0, 3.5, 0);
  ramp(3.5, 0.0, 0);
  int s = 1;
  for (int turn = 31; turn >= 23; --turn, ++s) {
    ramp(0.0, turn / 10.0, s);
    ramp(turn / 10.0, 0.0, s);
  }
  PreisachState state = PreisachState::negative_saturation(grid);
  const Eigen::VectorXd raw = model.simulate(state, data.input);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.005);
  for (Eigen::Index t = 0; t < raw.size(); ++t)
    data.output.push_back(16.0 * (raw[t] - raw.minCoeff()) / (raw.maxCoeff() - raw.minCoeff()) +
                          noise(rng));
  return data;
}

TEST(Diagnose, SteepTransitionsAreNotSpikes) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  // Ridge widths across a and b, V: a steep rise and a smooth fall (the SMA record's shape),
  // both steep, and the rise narrower than the reading step. (A fall narrower than the step,
  // {0.12, 0.06}, is still named `outliers`: docs/diagnose.md.)
  const std::vector<std::pair<double, double>> widths{{0.05, 0.3}, {0.09, 0.12}, {0.06, 0.12}};
  unsigned seed = 5;
  for (const auto& [wa, wb] : widths) {
    DiagnoseData data = steep_forcs(wa, wb, ++seed);
    const Diagnosis clean = diagnose(data, DiagnoseOptions{});
    EXPECT_NE(clean.cause, "outliers")
        << "widths " << wa << ", " << wb << ": " << finding(clean, "outliers").evidence;
    // Two 5 % spikes on the falling branches of two reversal curves (no other segment passes
    // there in the same memory state).
    std::mt19937_64 rng(seed);
    for (int k = 0; k < 2; ++k) {
      std::size_t t = 0;
      do {
        t = std::uniform_int_distribution<std::size_t>(40, data.output.size() - 3)(rng);
      } while (data.input[t] >= data.input[t - 1] || data.input[t + 1] >= data.input[t]);
      data.output[t] += (k == 0 ? 0.05 : -0.05) * 16.0;
    }
    const Diagnosis spiked = diagnose(data, DiagnoseOptions{});
    EXPECT_EQ(spiked.cause, "outliers")
        << "widths " << wa << ", " << wb << ": " << finding(spiked, "outliers").evidence;
  }
}

// A load test whose turning points are drawn at random on the load grid (not cycles between
// fixed extrema): a held-out cycle then crosses parts of the Preisach plane that the other
// folds never traversed, and the baseline's guess there misses by several times the noise. The
// readings whose every Everett pair the training observed are predicted to the noise, so
// the record is `none`, not `unexplained` (3 of these 13 clean records were `unexplained`
// before identified_readings, and one `outliers`: a descent read once, guessed 11 robust
// sigmas off its neighbours). A ripple of 8 % of the range with a period of 30 readings, which
// no effect of the vocabulary models, is still named.
DiagnoseData random_turns(unsigned seed, double ripple, std::size_t min_readings = 40,
                          int min_turns = 5) {
  std::mt19937_64 rng(seed);
  const PreisachGrid grid{0.0, 300.0, 40};
  const PreisachModel model = density_model(grid, [](double a, double b) {
    return std::exp(-std::pow((a - b) / 80.0, 2) - std::pow(((a + b) / 2 - 140.0) / 150.0, 2)) +
           0.15;
  });
  DiagnoseData data;
  const int top = 8;  // steps of 37.5 g
  auto go = [&](int from, int to) {
    for (int k = from; k != to;) {
      k += to > from ? 1 : -1;
      data.input.push_back(37.5 * k);
    }
  };
  data.input.push_back(0.0);
  int k = 0;
  const int turns = std::uniform_int_distribution<int>(min_turns, min_turns + 4)(rng);
  for (int r = 0; r < turns || data.input.size() < min_readings; ++r) {
    const int next = r % 2 == 0 ? std::uniform_int_distribution<int>(std::min(k + 2, top), top)(rng)
                                : std::uniform_int_distribution<int>(0, std::max(k - 2, 0))(rng);
    go(k, next);
    k = next;
  }
  go(k, 0);
  PreisachState state = PreisachState::negative_saturation(grid);
  const Eigen::VectorXd raw = model.simulate(state, data.input);
  const double range = raw.maxCoeff() - raw.minCoeff();
  std::normal_distribution<double> noise(0.0, 0.004);
  for (Eigen::Index t = 0; t < raw.size(); ++t) {
    const double alt = ripple * std::sin(2.0 * std::numbers::pi * static_cast<double>(t) / 30.0);
    data.output.push_back(3.0 * ((raw[t] - raw.minCoeff()) / range + alt) +
                          0.003 * data.input[static_cast<std::size_t>(t)] + noise(rng));
  }
  return data;
}

TEST(Diagnose, RandomTurningPointsAreNotUnexplained) {
  for (unsigned seed = 1; seed <= 13; ++seed) {
    const Diagnosis d = diagnose(random_turns(seed, 0.0), DiagnoseOptions{});
    EXPECT_EQ(d.cause, "none") << "seed " << seed << ": held-out " << d.sustained_rms_pct_range
                               << " %, floor " << d.noise_floor_pct_range << " %; " << d.cause_note;
  }
  // The ripple: wherever it is material on the held-out readings and at least 10 of them are
  // identified, it is not `none` (fewer identified readings cannot tell it from the
  // baseline's guesses).
  int checked = 0;
  for (unsigned seed = 1; seed <= 13; ++seed) {
    const Diagnosis d = diagnose(random_turns(seed, 0.08), DiagnoseOptions{});
    if (d.identified_rows < 10 ||
        d.sustained_rms_pct_range <= std::max(2.0 * d.noise_floor_pct_range, 1.0))
      continue;
    ++checked;
    EXPECT_NE(d.cause, "none") << "seed " << seed << ": " << d.cause_note;
  }
  EXPECT_GE(checked, 8);
}

// A response half of which is reversible (linear in the load): the baseline with the reversible
// term, which cross-validation takes (DiagnoseOptions::baseline.reversible, kChosen by
// default), misses the held-out readings by less than the operator alone, whose diagonal cells
// follow the line only as steps, and says so in its name.
TEST(Diagnose, ReversibleTermLowersTheBaselinesHeldOutError) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    DiagnoseData data = random_turns(seed, 0.0);
    for (std::size_t t = 0; t < data.input.size(); ++t) data.output[t] += 0.01 * data.input[t];
    DiagnoseOptions operator_alone;
    operator_alone.baseline.reversible = PreisachFitOptions::Reversible::kOff;
    const Diagnosis plain = diagnose(data, operator_alone);
    const Diagnosis d = diagnose(data, DiagnoseOptions{});
    EXPECT_EQ(plain.baseline_model.find("reversible"), std::string::npos);
    EXPECT_NE(d.baseline_model.find("reversible term"), std::string::npos) << d.baseline_model;
    EXPECT_LT(d.rms_pct_range, plain.rms_pct_range) << "seed " << seed;
  }
}

// Without a clock (no time_s or dwell_s) the time is the reading index, and creep, a dependence
// on the time held, is not tested: a lag per reading is a memory of the path. The same readings
// with a clock are tested. Seed 76 of ShortRecordsAreCutIntoMoreFolds, clean, was named `creep`
// with the reversible term in its baseline (a Kelvin element in reading time gained 16.6 %).
TEST(Diagnose, CreepIsNotTestedWithoutAClock) {
  auto creep_of = [](const Diagnosis& d) {
    for (const Finding& f : d.findings) {
      if (f.effect == "creep") return f;
    }
    return Finding{};
  };
  for (unsigned seed = 1; seed <= 4; ++seed) {
    DiagnoseData data = random_turns(seed, 0.0);
    const Finding without = creep_of(diagnose(data, DiagnoseOptions{}));
    EXPECT_FALSE(without.tested) << "seed " << seed;
    EXPECT_NE(without.evidence.find("no time"), std::string::npos) << without.evidence;
    for (std::size_t t = 0; t < data.input.size(); ++t)
      data.time_s.push_back(10.0 * static_cast<double>(t));
    EXPECT_TRUE(creep_of(diagnose(data, DiagnoseOptions{})).tested) << "seed " << seed;
  }
  const Diagnosis d = diagnose(random_turns(76, 0.0, 24, 3), DiagnoseOptions{});
  EXPECT_EQ(d.cause, "none") << d.cause_note;
}

// A short record whose extreme inputs occur in few cycles leaves few held-out readings within
// the inputs their folds trained on: it is cut into more, shorter folds rather than refused
// (a fresh independent-generator load record of 43 readings was refused with 16 scorable in
// 5 folds), and records of 24 readings are diagnosed (the second independent generator's random
// protocols make records of 29). Clean, they stay `none`; refused only when no cut leaves 20
// scorable readings.
TEST(Diagnose, ShortRecordsAreCutIntoMoreFolds) {
  int diagnosed = 0, refined = 0, under_30 = 0;
  for (unsigned seed = 1; seed <= 100; ++seed) {
    const DiagnoseData data = random_turns(seed, 0.0, 24, 3);
    try {
      const Diagnosis d = diagnose(data, DiagnoseOptions{});
      ++diagnosed;
      refined += d.heldout_folds > DiagnoseOptions{}.folds;
      under_30 += data.input.size() < 30;
      EXPECT_GE(d.heldout_rows, 20u);
      EXPECT_EQ(d.cause, "none") << "seed " << seed << ", " << data.input.size() << " readings, "
                                 << d.heldout_folds << " folds: " << d.cause_note;
    } catch (const IdentificationError& e) {
      EXPECT_NE(std::string(e.what()).find("in one cycle only"), std::string::npos) << e.what();
    }
  }
  // Measured: 80 diagnosed, 12 in more folds, 34 of fewer than 30 readings; 68 without the
  // refinement, 46 when fewer than 30 readings were refused.
  EXPECT_GE(diagnosed, 75);
  EXPECT_GE(refined, 8);
  EXPECT_GE(under_30, 25);
}

// A damped protocol returns to its lowest load only at its very end (index 17): that reading,
// held out, lies beyond every input its fold trained on. Scored, it was predicted 250 % of the
// range off and the drift was named `outliers`; it is not scored.
TEST(Diagnose, ExtrapolatedReadingsAreNotScored) { expect_named("load", "drift", {17}); }

// The record seen through one first-order lag of the whole record, y = (1 - c) y0 + c v with v
// relaxing towards y0, its state carried across the load changes; tau `readings` median
// reading intervals. Returns tau (s).
double carry_lag(DiagnoseData& data, double c, double readings) {
  std::vector<double> dt;
  for (std::size_t t = 1; t < data.time_s.size(); ++t)
    dt.push_back(data.time_s[t] - data.time_s[t - 1]);
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
  const double tau = readings * dt[dt.size() / 2];
  double v = data.output.front();
  for (std::size_t t = 0; t < data.output.size(); ++t) {
    const double d = t == 0 ? 0.0 : std::exp(-(data.time_s[t] - data.time_s[t - 1]) / tau);
    v = data.output[t] + (v - data.output[t]) * d;
    data.output[t] = (1.0 - c) * data.output[t] + c * v;
  }
  return tau;
}

// A lag between the Kelvin grid's points (c 0.3, tau 3.3 and 7.1 readings; the grid has c 0.2
// and 0.4, tau 2, 5 and 10) on clean random turning points read every second (noise 0.1 % of
// the range): the element refined between the points (refine_kelvin) is named, and takes most
// of the misfit on held-out cycles. On the grid's points alone the folds chose elements up to a
// factor of 2 off, whose weights bend each fold's held-out prediction its own way (measured:
// held-out gains 43-67 %, mean 56.5 %, on the grid alone; 52-81 %, mean 68.8 %, refined).
TEST(Diagnose, CreepBetweenTheKelvinGridsPointsIsFitted) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  double sum = 0.0;
  int cases = 0;
  for (unsigned seed = 1; seed <= 4; ++seed) {
    for (double readings : {3.3, 7.1}) {
      DiagnoseData data = random_turns(seed, 0.0, 150, 12);
      for (std::size_t t = 0; t < data.input.size(); ++t)
        data.time_s.push_back(static_cast<double>(t));
      carry_lag(data, 0.3, readings);
      const Diagnosis d = diagnose(data);
      const Finding& f = finding(d, "creep");
      EXPECT_EQ(d.cause, "creep") << "seed " << seed << " tau " << readings << ": " << f.evidence;
      EXPECT_GT(f.gain_pct, 50.0) << "seed " << seed << " tau " << readings << ": "
                                  << f.extended_model;
      sum += f.gain_pct;
      ++cases;
    }
  }
  EXPECT_GT(sum / cases, 65.0);
}

// Creep that runs on through the load changes: the rig's clean voltage tests (damped
// cycles at several loads, one reading per hold) seen through one first-order lag of the whole
// record, y = (1 - c) y0 + c v with v relaxing towards y0 (its state carried from one load's
// segment into the next, as a specimen's is). A Kelvin element restarted at each load cannot
// follow the offset this leaves on each segment's first readings, nor can the lonely stroke's
// term take it (the third independent generator's creep: 0 of 14 found before the carried
// element, two named `lonely_stroke`). Lag fractions 0.2-0.3, time constants of 2-3 readings
// (with one reading, c = 0.2, the lag offsets each segment's first reading alone:
// ReadingsThatADetectedExtensionPredictsAreNotOutliers).
TEST(Diagnose, CreepCarriedAcrossLoadChanges) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  for (const auto& [index, c, readings] :
       {std::tuple{0, 0.3, 2.0}, std::tuple{1, 0.2, 2.0}, std::tuple{2, 0.3, 3.0}}) {
    const testing::Scenario s = make_scenario("voltage", "none", index);
    DiagnoseData data = testing::scenario_data(s);
    ASSERT_EQ(data.time_s.size(), data.output.size());
    const double tau = carry_lag(data, c, readings);
    const Diagnosis d = diagnose(data);
    EXPECT_EQ(d.cause, "creep") << s.describe() << " c " << c << " tau " << tau << " s\n"
                                << finding(d, "creep").evidence << "\n"
                                << finding(d, "lonely_stroke").evidence;
    EXPECT_LT(finding(d, "creep").heldout_rms_after, finding(d, "creep").heldout_rms_before);
  }
}

// What the outliers' screen flags on the baseline's residuals must stand out of the residuals
// of the detected extension that gains most too (diagnose.cpp, recheck_outliers). A lag of one
// reading carried across the load changes offsets each segment's first reading alone, off its
// neighbours and off the readings at its protocol point in the other segments; the creep
// extension predicts it, so it is creep (scenario 0 was named `outliers` without the recheck:
// session 27 left it open). Spikes on top of the same creep stand off that extension too, and
// are named.
TEST(Diagnose, ReadingsThatADetectedExtensionPredictsAreNotOutliers) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  for (int index : {0, 1}) {
    const testing::Scenario s = make_scenario("voltage", "none", index);
    DiagnoseData data = testing::scenario_data(s);
    carry_lag(data, 0.2, 1.0);
    const Diagnosis d = diagnose(data);
    EXPECT_EQ(d.cause, "creep") << s.describe() << "\n"
                                << finding(d, "creep").evidence << "\n"
                                << finding(d, "outliers").evidence;
    // Three spikes of 8 % of the range, away from the segments' edges.
    const auto [lo, hi] = std::minmax_element(data.output.begin(), data.output.end());
    for (std::size_t k = 1; k <= 3; ++k) {
      const std::size_t t = k * data.output.size() / 4 + 3;
      data.output[t] += (k % 2 ? 0.08 : -0.08) * (*hi - *lo);
    }
    const Diagnosis spiked = diagnose(data);
    EXPECT_EQ(spiked.cause, "outliers") << s.describe() << "\n"
                                        << finding(spiked, "outliers").evidence;
  }
}

TEST(Diagnose, VoltageTestsCleanKneeLonelyStroke) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  expect_named("voltage", "none", {0});
  expect_named("voltage", "offset_nonlinearity", {2});
  expect_named("voltage", "lonely_stroke", {2});
}

// Five loads leave four in each fold's training (the end loads always train): the knee's width
// cannot be chosen there, and the cubic maps, exactly determined, predict the held-out loads
// (before, offset_nonlinearity was not tested below six loads and these were `unexplained`).
// Clean records at five loads stay `none`.
TEST(Diagnose, OffsetNonlinearityAtFiveLoadsByCubicMaps) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  for (const std::vector<double>& loads :
       {std::vector<double>{30, 50, 65, 80, 100}, {60, 30, 100, 45, 75}}) {
    const auto five = [&](RigSpec& r) { r.voltage.loads_g = loads; };
    expect_named("voltage", "offset_nonlinearity", {2, 5}, five, [](const Diagnosis& d) {
      EXPECT_NE(finding(d, "offset_nonlinearity").extended_model.find("cubic"), std::string::npos);
    });
    expect_named("voltage", "none", {0, 1, 2}, five);
  }
}

// Below five loads the training loads determine the quadratic maps exactly, so no map beyond
// them can be held out; what the maps miss at a held-out load is then an affine map of H
// within its segment, and offset_nonlinearity is named by that signature when the residuals
// are material (before, these were `unexplained`). Clean records at four loads stay `none`.
TEST(Diagnose, OffsetNonlinearityAtFourLoadsBySignature) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  for (const std::vector<double>& loads :
       {std::vector<double>{30, 55, 80, 100}, {80, 30, 100, 50}}) {
    const auto four = [&](RigSpec& r) { r.voltage.loads_g = loads; };
    expect_named("voltage", "offset_nonlinearity", {2, 5}, four, [](const Diagnosis& d) {
      const Finding& f = finding(d, "offset_nonlinearity");
      EXPECT_TRUE(f.tested);
      EXPECT_GT(f.score, 0.6);
      EXPECT_NE(f.evidence.find("named by this signature alone"), std::string::npos);
    });
    expect_named("voltage", "none", {0, 1, 2}, four);
  }
}

// Three loads, each tested once, are held out by blocks of cycles inside every segment: held
// out by load, the middle load was predicted by maps through the two end loads, which cannot
// bend, and every clean rig record at three loads was named offset_nonlinearity (18 of 18 over
// three load sets, seeds 1-3, GPI and Preisach truths). What three loads hide is said in the
// report's protocol limits: a map beyond quadratic (offset_nonlinearity is not tested) and a
// drift across segments (the maps fit each segment's offset). Clean records and load-shape
// couplings are named; lonely strokes and drifts are no longer offset_nonlinearity, though
// most are `none` (docs/diagnose-log.md, session 44).
TEST(Diagnose, ThreeLoadsAreHeldOutByCyclesWithinTheSegments) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  const auto limited = [](const Diagnosis& d, const std::string& effect) {
    return std::any_of(d.protocol_limits.begin(), d.protocol_limits.end(),
                       [&](const ProtocolLimit& l) { return l.effect == effect; });
  };
  const auto held_out_by_cycles = [&](const Diagnosis& d) {
    EXPECT_EQ(d.heldout_by, "cycles");
    EXPECT_FALSE(finding(d, "offset_nonlinearity").tested);
    EXPECT_TRUE(limited(d, "offset_nonlinearity"));
    EXPECT_TRUE(limited(d, "drift"));
    // The rig runs one protocol at every load, so a coupling is not the baseline's misfit of
    // protocols of their own (protocol_limits_test).
    EXPECT_FALSE(limited(d, "load_shape_coupling"));
  };
  for (const std::vector<double>& loads : {std::vector<double>{30, 65, 100}, {100, 40, 70}}) {
    const auto three = [&](RigSpec& r) { r.voltage.loads_g = loads; };
    expect_named("voltage", "none", {0, 1, 2, 3, 4, 5}, three, held_out_by_cycles);
    expect_named("voltage", "load_shape_coupling", {0, 1, 2, 3, 4, 5}, three, held_out_by_cycles);
    for (const std::string effect : {"lonely_stroke", "drift"}) {
      for (int i = 0; i < 6; ++i) {
        testing::Scenario s = make_scenario("voltage", effect, i);
        three(s.spec);
        const Diagnosis d = testing::diagnose_scenario(s);
        held_out_by_cycles(d);
        EXPECT_TRUE(d.cause == effect || d.cause == "none") << s.describe() << ": " << d.cause;
      }
    }
  }
}

// Five loads leave four offsets in each fold's training: a quadratic f1 and a trend in time
// are then exactly determined by them, as the cubic maps are (above), and predict the held-out
// loads' offsets; loads in a shuffled order separate the trend from f1. Before, the offset
// map's trend asked for five training offsets, and these nine drifts (3-12 % of the range)
// were named `none` (6), `lonely_stroke` (2) and `unexplained`; now 7 of 9 are `drift` (the
// two missed are at 6 %, indices 1 and 7). Clean records of this protocol stay `none` (the
// test above, and six more seeds here).
TEST(Diagnose, DriftAtFiveLoadsInTheOffsetMap) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  const auto five = [](RigSpec& r) { r.voltage.loads_g = {60, 30, 100, 45, 75}; };
  expect_named("voltage", "drift", {0, 2, 3, 4, 5, 6, 8}, five, [](const Diagnosis& d) {
    EXPECT_NE(finding(d, "drift").extended_model.find("offset map"), std::string::npos);
  });
  expect_named("voltage", "none", {3, 4, 5, 6, 7, 8}, five);
}

TEST(Diagnose, TheDriftExtensionGainsOnHeldOutData) {
  const testing::Scenario s = make_scenario("load", "drift", 2);
  const Diagnosis d = testing::diagnose_scenario(s);
  // The first rise, before the load first reaches its maximum, sets the memory only: every
  // other reading is scored once, and those are not.
  const Measurement m = Measurement::parse(testing::scenario_csv(s), "rig.csv");
  const std::vector<double>& load = select_input(m).values;
  const auto first_max =
      static_cast<std::size_t>(std::max_element(load.begin(), load.end()) - load.begin());
  EXPECT_GT(first_max, 0U);
  EXPECT_EQ(d.heldout_rows, load.size() - first_max);
  const auto it = std::find_if(d.findings.begin(), d.findings.end(),
                               [](const Finding& f) { return f.effect == "drift"; });
  ASSERT_NE(it, d.findings.end());
  EXPECT_TRUE(it->detected);
  EXPECT_LT(it->p_value, 0.01);
  EXPECT_GT(it->gain_pct, 5.0);
  EXPECT_LT(it->heldout_rms_after, it->heldout_rms_before);
  // Every effect of the vocabulary is reported once, in SPEC order.
  ASSERT_EQ(d.findings.size(), effect_names().size());
  for (std::size_t i = 0; i < d.findings.size(); ++i)
    EXPECT_EQ(d.findings[i].effect, effect_names()[i]);
  EXPECT_EQ(d.heldout_by, "cycles");
}

// On a load test the trend is fitted with the baseline (each fold's baseline refitted on the
// readings less the trend, in turn, to the limit), not to the residuals of a baseline that has
// already taken up part of it: each fold's trend over the record is the hidden drift's, read
// here off the rig run with and without it (same seed, so the same noise: their difference is
// the drift, up to the sensor's rounding). 3 % drifts at 0.01 and 0.02 mm noise. Session 39:
// the two-stage trend gained 6.2-18.8 % on these, the backfitted one 21-40 %; three plain
// rounds of backfitting, without the extrapolation to the limit, left 1.1-1.2 % in one fold.
TEST(Diagnose, TheTrendFittedWithTheBaselineIsTheHiddenDrift) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  for (int i : {0, 6, 9}) {
    const testing::Scenario s = make_scenario("load", "drift", i);
    testing::Scenario clean = s;
    clean.spec.effects.drift = 0.0;
    const Measurement with = Measurement::parse(testing::scenario_csv(s), "drift.csv");
    const Measurement without = Measurement::parse(testing::scenario_csv(clean), "clean.csv");
    const std::vector<double> y = select_response(with).values;
    const std::vector<double> y0 = select_response(without).values;
    const std::vector<double>& time = with.find(Quantity::kTime)->values;
    // The drift's least-squares slope, times the record's duration, in % of the output range.
    double st = 0, sd = 0, stt = 0, std_ = 0;
    const auto n = static_cast<double>(y.size());
    for (std::size_t k = 0; k < y.size(); ++k) {
      st += time[k];
      sd += y[k] - y0[k];
      stt += time[k] * time[k];
      std_ += time[k] * (y[k] - y0[k]);
    }
    const double slope = (std_ - st * sd / n) / (stt - st * st / n);
    const auto [lo, hi] = std::minmax_element(y.begin(), y.end());
    const double truth = 100.0 * slope * (time.back() - time.front()) / (*hi - *lo);
    EXPECT_NEAR(truth, 2.5, 1.0) << s.describe();  // 3 % of the rig's nominal range

    const Diagnosis d = testing::diagnose_scenario(s);
    EXPECT_EQ(d.cause, "drift") << s.describe();
    const Finding& f = finding(d, "drift");
    const std::string& m = f.extended_model;
    const std::vector<double> trends = per_fold_trends(m);
    ASSERT_EQ(trends.size(), static_cast<std::size_t>(d.heldout_folds)) << m;
    for (double t : trends) EXPECT_NEAR(t, truth, 0.35 * truth) << s.describe() << ": " << m;
  }
}

// A drift that settles (a warm-up, 1 - exp(-k t / T) over the record's duration T) is fitted
// as one: the trend fitted with the baseline in the shape exp(-k t / T), k chosen in-fold, is
// the drift's extension on at least half the rig records of such a drift (a line takes it up
// only in part), and sizes its change over the record: the median over the folds within 35 % of
// the truth (the fold holding the record's start extrapolates the steepest part of the
// warm-up). It was four of the six until session 57; since the line fitted with the baseline is
// fitted also where the line's signature is at alpha, it out-gains the settling trend on seed
// 1085 (25.9 against 19.8 %) and is reported there; every cause is the same as before.
TEST(Diagnose, ADriftThatSettlesIsFittedAsOne) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  const struct {
    int index;
    double size, rate;
  } cases[] = {{0, 0.10, 4.0}, {1, 0.15, 6.0}, {2, 0.08, 3.0},
               {3, 0.12, 5.0}, {4, 0.10, 3.0}, {5, 0.15, 4.0}};
  int settling = 0;
  std::string report;
  for (const auto& c : cases) {
    const testing::Scenario s = make_scenario("load", "none", c.index);
    DiagnoseData data = testing::scenario_data(s);
    ASSERT_EQ(data.time_s.size(), data.output.size()) << s.describe();
    const auto [lo, hi] = std::minmax_element(data.output.begin(), data.output.end());
    const double range = *hi - *lo;
    const double t0 = data.time_s.front(), span = data.time_s.back() - t0;
    for (std::size_t t = 0; t < data.output.size(); ++t)
      data.output[t] += c.size * range * (1.0 - std::exp(-c.rate * (data.time_s[t] - t0) / span));
    DiagnoseOptions o;
    o.seed = s.spec.seed;
    const Diagnosis d = diagnose(data, o);
    const Finding& f = finding(d, "drift");
    const std::string& m = f.extended_model;
    const std::string what = fmt::format("{} + settling drift {} (k {}): {}; {}", s.describe(),
                                         c.size, c.rate, d.cause, m);
    report += "\n" + what;
    EXPECT_TRUE(f.detected) << what;
    if (m.find("settling trend") == std::string::npos) continue;
    ++settling;
    // The change over the record per fold, in % of the output range (the drifted record's).
    const auto [dlo, dhi] = std::minmax_element(data.output.begin(), data.output.end());
    const double truth = 100.0 * c.size * range * (1.0 - std::exp(-c.rate)) / (*dhi - *dlo);
    std::vector<double> changes = per_fold_trends(m);
    ASSERT_EQ(changes.size(), static_cast<std::size_t>(d.heldout_folds)) << m;
    std::nth_element(changes.begin(),
                     changes.begin() + static_cast<std::ptrdiff_t>(changes.size() / 2),
                     changes.end());
    EXPECT_NEAR(changes[changes.size() / 2], truth, 0.35 * truth) << what;
  }
  EXPECT_GE(2 * settling, static_cast<int>(std::size(cases))) << report;
}

// Where the model fails, per reading (Diagnosis::baseline_prediction, heldout_fold,
// identified; what `scpkit diagnose --residuals` writes): the readings with a prediction are
// the scored ones, each in a fold that was held out, and their RMS residual, recomputed here
// over the output's range, is the reported held-out E_RMS. On a drift the named extension's
// per-reading prediction gives its reported E_RMS after on the same readings. A load test held
// out by cycles and a voltage test held out by load segment.
TEST(Diagnose, PerReadingPredictionsGiveTheReportedErrors) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  for (const auto& [side, effect, index] :
       {std::tuple{"load", "drift", 1}, std::tuple{"voltage", "none", 0}}) {
    const testing::Scenario s = make_scenario(side, effect, index);
    const DiagnoseData data = testing::scenario_data(s);
    DiagnoseOptions o;
    o.seed = s.spec.seed;
    const Diagnosis d = diagnose(data, o);
    const std::size_t n = data.output.size();
    ASSERT_EQ(d.baseline_prediction.size(), n) << s.describe();
    ASSERT_EQ(d.heldout_fold.size(), n) << s.describe();
    ASSERT_EQ(d.identified.size(), n) << s.describe();
    const auto [lo, hi] = std::minmax_element(data.output.begin(), data.output.end());
    const double range = *hi - *lo;
    auto rms_pct = [&](const std::vector<double>& pred) {
      double ss = 0.0;
      std::size_t count = 0;
      for (std::size_t t = 0; t < n; ++t) {
        if (!std::isfinite(d.baseline_prediction[t])) continue;
        ss += (data.output[t] - pred[t]) * (data.output[t] - pred[t]);
        ++count;
      }
      return 100.0 * std::sqrt(ss / static_cast<double>(count)) / range;
    };
    std::size_t scored = 0;
    for (std::size_t t = 0; t < n; ++t) {
      if (!std::isfinite(d.baseline_prediction[t])) continue;
      ++scored;
      EXPECT_GE(d.heldout_fold[t], 0) << t;
      EXPECT_LT(d.heldout_fold[t], d.heldout_folds) << t;
    }
    EXPECT_EQ(scored, d.heldout_rows) << s.describe();
    EXPECT_NEAR(rms_pct(d.baseline_prediction), d.rms_pct_range, 1e-9 * d.rms_pct_range)
        << s.describe();
    EXPECT_EQ(d.cause, effect) << s.describe();
    if (d.cause == "drift") {
      const Finding& f = finding(d, "drift");
      ASSERT_EQ(f.heldout_prediction.size(), n);
      EXPECT_NEAR(rms_pct(f.heldout_prediction), f.heldout_rms_after, 1e-9 * f.heldout_rms_after)
          << s.describe();
      EXPECT_LT(f.heldout_rms_after, d.rms_pct_range) << s.describe();
    }
  }
}

// A file without a clock: the readings' times come from dwell_s (time held at the input before
// the reading). On rig files, which hold both, they reproduce time_s exactly, with readings
// during holds, varied holds, and load changes on voltage tests.
TEST(Diagnose, ReadingTimesFromDwellReproduceTheClock) {
  for (const std::string side : {"load", "voltage"}) {
    testing::Scenario s = make_scenario(side, "none", 0);
    s.spec.protocol.readings_per_hold = s.spec.voltage.readings_per_hold = 3;
    s.spec.protocol.dwell_spread = s.spec.voltage.dwell_spread = 1.0;
    const Measurement m = Measurement::parse(testing::scenario_csv(s), "rig.csv");
    DiagnoseData d;
    d.dwell_s = m.find(Quantity::kDwell)->values;
    if (side == "voltage") {
      d.input = select_input(m, "voltage_V").values;
      d.load_N = m.find(Quantity::kLoad)->values;
    } else {
      d.input = select_input(m).values;
    }
    const std::vector<double>& clock = m.find(Quantity::kTime)->values;
    const std::vector<double> t = reading_times_from_dwell(d);
    ASSERT_EQ(t.size(), clock.size());
    for (std::size_t k = 0; k < t.size(); ++k)
      ASSERT_NEAR(t[k], clock[k], 1e-6 * clock.back()) << side << " row " << k;
  }
  DiagnoseData bad;
  bad.dwell_s = {1.0, 2.0};
  bad.input = {1.0};
  EXPECT_THROW_MSG(reading_times_from_dwell(bad), InvalidArgument, "different lengths");
}

// What diagnose decides is a property of the data's shape, not of the response's unit, sign
// convention or zero: SPEC.md writes contraction as negative and allows mm, um, strain or %,
// so y -> k y + c (k of either sign) must name the same cause with the same findings and the
// same numbers. Read upside down (k = -1) they must agree to round-off: they did not until
// session 24 (an even count's median was its upper middle value, and the non-congruence map
// was not closed under y -> -y). Rescaled or shifted, to 1e-6 of themselves (gains to 1e-3
// points): they did not until session 25, while the baseline's cross-validation offered
// smoothness 0, whose ill-conditioned fits have held-out errors that follow round-off
// (docs/diagnose-log.md, session 24: a clean record chose L = 12 unregularised or L = 16 at 1e-4
// with its response shifted by 1e-9 of itself).
TEST(Diagnose, TheCauseDoesNotDependOnTheResponsesUnitSignOrZero) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  // Scenario 0 of the load side has minor loops between the same extrema (the non-congruence
  // extension is fitted), 1 not; the others are the shorter 1 to keep the suite's time.
  const std::vector<std::tuple<std::string, std::string, int>> cases = {
      {"load", "none", 0},  {"load", "none", 1},     {"load", "drift", 1},
      {"load", "creep", 1}, {"load", "outliers", 1}, {"voltage", "lonely_stroke", 0}};
  for (const auto& [side, effect, i] : cases) {
    const testing::Scenario s = make_scenario(side, effect, i);
    const DiagnoseData data = testing::scenario_data(s);
    DiagnoseOptions o;
    o.seed = s.spec.seed;
    const Diagnosis d0 = diagnose(data, o);
    std::vector<std::pair<double, double>> maps = {{-1.0, 0.0}};
    if (side == "load") maps.insert(maps.end(), {{1000.0, 3.5}, {-0.0254, -1.25}});
    for (const auto& [k, c] : maps) {
      DiagnoseData t = data;
      for (double& y : t.output) y = k * y + c;
      const Diagnosis d1 = diagnose(t, o);
      const std::string what = s.describe() + fmt::format(", y -> {} y + {}", k, c);
      // Read upside down every operation is mirrored exactly; rescaled and shifted, the
      // response's last digits round differently (-0.0254 y - 1.25 keeps about 14 of them).
      const bool flipped = k == -1.0 && c == 0.0;
      const double relative = flipped ? 1e-9 : 1e-6;
      EXPECT_EQ(d1.cause, d0.cause) << what;
      ASSERT_EQ(d1.findings.size(), d0.findings.size());
      for (std::size_t f = 0; f < d0.findings.size(); ++f) {
        EXPECT_EQ(d1.findings[f].detected, d0.findings[f].detected)
            << what << " " << d0.findings[f].effect;
        EXPECT_NEAR(d1.findings[f].gain_pct, d0.findings[f].gain_pct, flipped ? 1e-6 : 1e-3)
            << what << " " << d0.findings[f].effect;
      }
      EXPECT_NEAR(d1.rms_pct_range, d0.rms_pct_range, relative * d0.rms_pct_range) << what;
      EXPECT_NEAR(d1.noise_floor_pct_range, d0.noise_floor_pct_range,
                  relative * d0.noise_floor_pct_range)
          << what;
    }
  }
}

TEST(Diagnose, RefusesWhatCannotBeDiagnosed) {
  DiagnoseData d;
  d.input.assign(20, 1.0);
  d.output.assign(20, 1.0);
  EXPECT_THROW_MSG(diagnose(d), IdentificationError, "too few");
  d.input.resize(60);
  d.output.assign(60, 2.0);
  for (std::size_t t = 0; t < 60; ++t) d.input[t] = static_cast<double>(t % 10);
  EXPECT_THROW_MSG(diagnose(d), IdentificationError, "never changes");
  d.output[3] = 1.0;
  d.time_s.assign(5, 0.0);
  EXPECT_THROW_MSG(diagnose(d), InvalidArgument, "different lengths");
}

}  // namespace
}  // namespace scpkit
