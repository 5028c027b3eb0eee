// The virtual test rig: deterministic, faithful to its stated ground truth, and each effect
// leaves the signature PHYSICS.md section 5 describes, in proportion to its magnitude.
#include "scpkit/rig/rig.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "scpkit/error.hpp"
#include "scpkit/identification/preisach_fit.hpp"
#include "scpkit/io/measurement.hpp"
#include "scpkit/mechanics/ply_mapping.hpp"
#include "test_support.hpp"

namespace scpkit {
namespace {

const Material& card() {
  static const Material m = find_material("nylon-110-34-dtex");
  return m;
}

RigSpec clean_spec(int plies = 2, const std::string& specimen = "pair") {
  RigSpec s;
  s.plies = plies;
  s.specimen = specimen;
  s.resolution_mm = 0.0;
  s.noise_mm = 0.0;
  return s;
}

std::vector<double> column(const RigRun& r, const std::string& name) {
  const auto it = std::find(r.columns.begin(), r.columns.end(), name);
  EXPECT_NE(it, r.columns.end()) << name;
  const auto c = static_cast<std::size_t>(it - r.columns.begin());
  std::vector<double> v;
  for (const auto& row : r.rows) v.push_back(row[c]);
  return v;
}

TEST(Rig, IsDeterministicAndWritesTheSpecFormat) {
  RigSpec s;
  const std::string a = run_rig(s, card()).to_csv();
  EXPECT_EQ(a, run_rig(s, card()).to_csv());
  s.seed = 2;
  EXPECT_NE(a, run_rig(s, card()).to_csv());
  const Measurement m = Measurement::parse(a, "rig.csv");
  EXPECT_EQ(*m.meta_positive_int("plies"), 2);
  EXPECT_TRUE(m.meta("truth_gain").has_value());
  EXPECT_TRUE(m.find(Quantity::kThreadStrain) && m.find(Quantity::kScpStrain));
  // Sensor: readings are whole multiples of 0.04 mm on 100 mm (0.04 strain-%).
  for (double v : column(run_rig(RigSpec{}, card()), "thread_strain_pct")) {
    ASSERT_NEAR(v / 0.04, std::round(v / 0.04), 1e-6);
  }
}

TEST(Rig, ReadingsDuringHoldsShowCreepStillMovingAndNothingElse) {
  // k readings per hold: the input repeats k times, dwell_s counts the time held so far, and a
  // rate-independent specimen reads the same value throughout the hold, while creep keeps
  // moving in the direction of the last load step, by less at each reading (Kelvin element).
  for (const double creep : {0.0, 0.3}) {
    RigSpec s = clean_spec(2, "thread");
    s.protocol.readings_per_hold = 4;
    s.effects.creep = creep;
    const RigRun run = run_rig(s, card());
    const std::vector<double> load = column(run, "load_g"), held = column(run, "dwell_s");
    const std::vector<double> y = column(run, "disp_mm");
    ASSERT_EQ(load.size(), 4 * rig_load_protocol(s).size());
    for (std::size_t i = 4; i + 4 <= load.size(); i += 4) {
      const double step = load[i] - load[i - 1];
      for (std::size_t j = 1; j < 4; ++j) {
        ASSERT_EQ(load[i + j], load[i]);
        ASSERT_NEAR(held[i + j], s.protocol.dwell_s * static_cast<double>(j + 1) / 4.0, 1e-9);
        const double move = y[i + j] - y[i + j - 1];
        if (creep == 0.0) {
          ASSERT_NEAR(move, 0.0, 1e-12);
        } else if (step != 0.0) {
          ASSERT_GT(move * step, 0.0) << "reading " << i + j;
          if (j > 1) {
            ASSERT_LT(std::abs(move), std::abs(y[i + j - 1] - y[i + j - 2]));
          }
        }
      }
    }
  }
}

TEST(Rig, RepeatedCyclesAndCongruencyLoopsFollowTheirDefinition) {
  RigSpec s = clean_spec(2, "thread");
  s.protocol.shape = "repeated";
  s.protocol.cycles = 3;
  s.protocol.steps_per_half = 5;
  s.protocol.minor_loops = 0;
  const std::vector<double> loads = rig_load_protocol(s);
  ASSERT_EQ(loads.size(), 1u + 2 * 3 * 5 + 5);
  for (int c = 0; c < 3; ++c) {
    EXPECT_DOUBLE_EQ(loads[static_cast<std::size_t>(10 * c)], 20.0);
    EXPECT_DOUBLE_EQ(loads[static_cast<std::size_t>(10 * c + 5)], 250.0);
  }
  // With congruency each minor loop a <-> b is run twice more after a different history
  // (from the minimum instead of from the maximum).
  s.protocol.minor_loops = 2;
  s.protocol.congruency = true;
  const std::vector<double> with = rig_load_protocol(s);
  s.protocol.congruency = false;
  const std::vector<double> without = rig_load_protocol(s);
  // per loop: down to the minimum, then the loop twice (4 ramps), 5 readings each
  EXPECT_EQ(with.size() - without.size(), 2u * (1 + 4) * 5);
  s.protocol.shape = "sawtooth";
  EXPECT_THROW(s.validate(), InvalidArgument);
}

TEST(Rig, ProtocolScalesLoadsWithPlyCount) {
  for (int p : {2, 4, 6}) {
    const auto loads = rig_load_protocol(clean_spec(p));
    const auto [lo, hi] = std::minmax_element(loads.begin(), loads.end());
    EXPECT_NEAR(*lo, 20.0 * p / 2, 1e-9);
    EXPECT_NEAR(*hi, 250.0 * p / 2, 1e-9);
  }
}

TEST(Rig, ThreadStrainsFollowThePerPlyLoadAndTheGainIsTheStiffnessRatio) {
  const RigRun r2 = run_rig(clean_spec(2), card()), r6 = run_rig(clean_spec(6), card());
  // Same per-ply protocol -> the same thread strains, whatever the ply count.
  const auto t2 = column(r2, "thread_strain_pct"), t6 = column(r6, "thread_strain_pct");
  ASSERT_EQ(t2.size(), t6.size());
  for (std::size_t k = 0; k < t2.size(); ++k) ASSERT_NEAR(t2[k], t6[k], 1e-9);
  // Elastic scale: the first rise to 125 g per ply strains the thread by about F / (E A).
  const double expect = 125 * 9.80665e-3 / (card().tensile_modulus_Pa.value * card().ply_area_m2());
  const double rise = *std::max_element(t2.begin(), t2.end()) / 100.0;
  EXPECT_NEAR(rise, expect, 0.1 * expect);
  // SCP = g thread + offset, g = K_thr / K_SCP of the card and Table 1 coil.
  const GainFit g = fit_scp_gain(t6, column(r6, "scp_strain_pct"));
  CoilGeometry c = card().geometry_for(6)->coil;
  const double truth =
      card().thread_stiffness(6, 0.1) / spring_stiffness(card().shear_modulus_Pa.value, c);
  EXPECT_NEAR(g.gain, truth, 1e-9 * truth);
  EXPECT_NEAR(g.offset, 0.2, 1e-9);
}

TEST(Rig, IdentificationRecoversTheTruthOnHeldOutLoads) {
  RigSpec s = clean_spec(2, "thread");
  s.noise_mm = 0.005;
  const RigRun run = run_rig(s, card());
  const Measurement m = Measurement::parse(run.to_csv(), "rig.csv");
  const Signal u = select_input(m), y = select_response(m);
  const PreisachFit fit = fit_preisach(u.values, y.values, {}, PreisachFitOptions{});
  // A different protocol (other seed: other minor loops) predicted against the truth.
  RigSpec other = clean_spec(2, "thread");
  other.seed = 99;
  const auto loads = rig_load_protocol(other);
  const PreisachModel truth = rig_thread_truth(card());
  PreisachState a = PreisachState::negative_saturation(truth.grid());
  PreisachState b = PreisachState::negative_saturation(fit.model.grid());
  std::vector<double> yt, yf;
  for (double g : loads) {
    yt.push_back(truth.step(a, g * 9.80665e-3 / 2));
    yf.push_back(fit.model.step(b, g * 9.80665e-3));
  }
  EXPECT_LT(error_metrics(yt, yf).rms_pct_range, 1.0);
}

// Effects: the difference to the clean run carries the stated signature.
std::vector<double> effect_delta(const RigEffects& e) {
  RigSpec clean = clean_spec(2, "thread"), with = clean;
  with.effects = e;
  const auto a = column(run_rig(clean, card()), "disp_mm"),
             b = column(run_rig(with, card()), "disp_mm");
  std::vector<double> d(a.size());
  for (std::size_t k = 0; k < a.size(); ++k) d[k] = b[k] - a[k];
  return d;
}

TEST(Rig, DriftIsALinearTrendInTimeScaledByItsMagnitude) {
  for (double mag : {0.02, 0.1}) {
    RigEffects e;
    e.drift = mag;
    const auto d = effect_delta(e);
    // Ends at mag * range (range ~ thread strain range * 100 mm), linear in between.
    const std::size_t mid = d.size() / 2;  // reading k is taken at (k + 1) dwells
    EXPECT_NEAR(d.back() / d[mid], static_cast<double>(d.size()) / static_cast<double>(mid + 1),
                1e-6);
    EXPECT_GT(d.back(), 0.0);
  }
}

TEST(Rig, CreepLagsBehindTheLoadAndGrowsWithMagnitude) {
  RigEffects small, large;
  small.creep = 0.1;
  large.creep = 0.3;
  small.creep_tau_s = large.creep_tau_s = 300.0;
  const auto ds = effect_delta(small), dl = effect_delta(large);
  const auto clean = column(run_rig(clean_spec(2, "thread"), card()), "disp_mm");
  double against = 0, ss = 0, sl = 0;
  for (std::size_t k = 1; k < clean.size(); ++k) {
    against += dl[k] * (clean[k] - clean[k - 1]);  // the lag opposes each change
    ss += std::abs(ds[k]);
    sl += std::abs(dl[k]);
  }
  EXPECT_LT(against, 0.0);
  EXPECT_NEAR(sl / ss, 3.0, 1e-6);  // linear in the magnitude
}

TEST(Rig, OutliersAreRareAndLarge) {
  RigEffects e;
  e.outliers = 0.2;
  RigSpec s = clean_spec(2, "thread");
  s.protocol.cycles = 60;  // many readings, ~1 % of them spiked
  s.effects = e;
  RigSpec c = clean_spec(2, "thread");
  c.protocol.cycles = 60;
  const auto a = column(run_rig(c, card()), "disp_mm"), b = column(run_rig(s, card()), "disp_mm");
  int spikes = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    const double d = std::abs(b[k] - a[k]);
    if (d > 1e-12) {
      ++spikes;
      EXPECT_GT(d, 0.2 * 2.5);  // >= magnitude * range (range ~3 mm)
    }
  }
  EXPECT_GT(spikes, 0);
  EXPECT_LT(spikes, static_cast<int>(a.size()) / 30);
}

TEST(Rig, LonelyStrokeOffsetsEverythingAfterTheFirstRise) {
  RigEffects e;
  e.lonely_stroke = 0.05;
  const auto d = effect_delta(e);
  EXPECT_NEAR(d.front(), 0.0, 1e-9);             // before the first rise
  EXPECT_NEAR(d.back(), d[d.size() / 2], 1e-9);  // constant once the maximum was reached
  EXPECT_GT(d.back(), 0.0);
}

TEST(Rig, NonCongruenceMakesRepeatedMinorLoopsHistoryDependent) {
  // The loop 100 <-> 200 g visited after two different histories (each with a maximum above
  // 200 g and a reversal at 100 g) at two output levels: congruent for the clean Preisach
  // truth, not once the loop height depends on the output, and more so for a larger magnitude.
  RigSpec s = clean_spec(2, "thread");
  s.load_sequence_g = {20, 250, 100, 200, 100, 200, 20, 250, 20, 200, 100, 200, 100, 200};
  auto mismatch = [&](double a) {
    s.effects.minor_loop_noncongruence = a;
    const auto y = column(run_rig(s, card()), "disp_mm");
    return std::abs((y[5] - y[4]) - (y[13] - y[12]));
  };
  EXPECT_LT(mismatch(0.0), 1e-9);
  EXPECT_GT(mismatch(0.2), 5e-4);  // mm; the clean loops agree to 1e-9
  EXPECT_GT(mismatch(0.2), 1.5 * mismatch(0.1));
}

TEST(Rig, BadSpecsAreRejectedWithTheReason) {
  RigSpec s;
  s.specimen = "rope";
  EXPECT_THROW_MSG(s.validate(), InvalidArgument, "specimen must be");
  s = RigSpec{};
  s.protocol.max_g = 5000;
  EXPECT_THROW_MSG(s.validate(), InvalidArgument, "per ply");
  s = RigSpec{};
  s.effects.creep = 2.0;
  EXPECT_THROW_MSG(s.validate(), InvalidArgument, "creep");
  s = RigSpec{};
  s.effects.minor_loop_noncongruence = 1.5;
  EXPECT_THROW_MSG(s.validate(), InvalidArgument, "<= 1");
  s = RigSpec{};
  s.effects.offset_nonlinearity = 0.1;  // a load test has one load sequence, no maps
  EXPECT_THROW_MSG(s.validate(), InvalidArgument, "voltage tests");
}

// Voltage tests, noise-free: column 5 of each row is disp_mm, column 3 the load in g.
std::vector<std::vector<double>> voltage_rows(const RigEffects& e, double spread = 0.0) {
  RigSpec s = clean_spec(2, "scp");
  s.test = "voltage";
  s.length_mm = 70.0;
  s.voltage.dwell_spread = spread;
  s.effects = e;
  return run_rig(s, card()).rows;
}

// The repeated voltage protocol: full cycles 0 -> v_max -> 0 V at each load, nothing appended;
// its response returns to the same value at every 0 V reading after the first cycle (clean
// truth, wiping-out), and with a lonely stroke every later 0 V reading sits off the first.
TEST(Rig, RepeatedVoltageCyclesReturnToZeroVolts) {
  RigSpec s = clean_spec(2, "scp");
  s.test = "voltage";
  s.length_mm = 70.0;
  s.voltage.loads_g = {60.0};
  s.voltage.shape = "repeated";
  s.voltage.cycles = 3;
  s.voltage.steps_per_half = 4;
  const auto disp_at_zero = [&](const RigEffects& e) {
    s.effects = e;
    const RigRun run = run_rig(s, card());
    const std::vector<double> v = column(run, "voltage_V"), d = column(run, "disp_mm");
    EXPECT_EQ(v.size(), 1u + 2 * 3 * 4);
    std::vector<double> out;
    for (std::size_t k = 0; k < v.size(); ++k) {
      if (k % 8 == 4) {
        EXPECT_DOUBLE_EQ(v[k], s.voltage.v_max);
      }
      if (k % 8 == 0) {
        EXPECT_DOUBLE_EQ(v[k], 0.0);
        out.push_back(d[k]);
      }
    }
    return out;
  };
  const std::vector<double> clean = disp_at_zero({});
  RigEffects lonely;
  lonely.lonely_stroke = 0.1;
  const std::vector<double> with = disp_at_zero(lonely);
  ASSERT_EQ(clean.size(), 4u);
  for (std::size_t c = 1; c < clean.size(); ++c) {
    EXPECT_NEAR(clean[c], clean[0], 1e-12);
    EXPECT_GT(std::abs(with[c] - with[0]), 1e-3);
    EXPECT_NEAR(with[c], with[1], 1e-12);
  }
  s.voltage.shape = "sawtooth";
  EXPECT_THROW_MSG(s.validate(), InvalidArgument, "shape");
}

TEST(Rig, OffsetNonlinearityIsAKneeAtLowLoad) {
  // f1 += m R k(F) and f2 *= 1 - m k(F), k = exp(-(F - F_lo) / (0.2 dF)): at the lowest load
  // the first reading (H = 0) moves by exactly m R; far from it, the change decays as k.
  const RigSpec probe = [] {
    RigSpec s;
    s.test = "voltage";
    return s;
  }();
  const VoltageTruth truth = rig_voltage_truth(probe);
  double R = 0.0;
  for (double g : probe.voltage.loads_g) R = std::max(R, std::abs(truth.f2(g * 9.80665e-3)));
  for (double m : {0.05, 0.2}) {
    RigEffects e;
    e.offset_nonlinearity = m;
    const auto with = voltage_rows(e), without = voltage_rows({});
    ASSERT_EQ(with.size(), without.size());
    const double shift = (with[0][5] - without[0][5]) / 70.0;  // strain
    EXPECT_NEAR(shift, m * R, 1e-9 * R);
    const double k_last = std::exp(-1.0 / 0.2);
    EXPECT_NEAR((with.back()[5] - without.back()[5]) / 70.0, m * R * k_last, 1e-9 * R);
  }
}

TEST(Rig, LoadShapeCouplingLeavesTheLowestLoadAndReshapesTheHighest) {
  RigEffects e;
  e.load_shape_coupling = 0.8;
  const auto with = voltage_rows(e), without = voltage_rows({});
  double low = 0.0, high = 0.0;
  for (std::size_t i = 0; i < with.size(); ++i) {
    const double d = std::abs(with[i][5] - without[i][5]);
    (with[i][3] == with.front()[3] ? low : high) =
        std::max(d, with[i][3] == with.front()[3] ? low : high);
  }
  EXPECT_EQ(low, 0.0);
  EXPECT_GT(high, 1e-3);  // mm: the shape at the other loads changed
  // Offsets (H = 0 at each segment's first reading) are untouched: only the shape moves.
  for (std::size_t i = 0; i < with.size(); ++i) {
    if (i == 0 || with[i][2] != with[i - 1][2]) {
      EXPECT_NEAR(with[i][5], without[i][5], 1e-12);
    }
  }
}

TEST(Rig, DwellSpreadVariesTheHoldsWithinItsBounds) {
  const auto constant = voltage_rows({});
  for (const auto& row : constant) EXPECT_EQ(row[1], 60.0);
  const auto varied = voltage_rows({}, 1.0);
  double lo = 1e9, hi = 0.0;
  for (std::size_t i = 0; i < varied.size(); ++i) {
    lo = std::min(lo, varied[i][1]);
    hi = std::max(hi, varied[i][1]);
    if (i > 0) {
      EXPECT_NEAR(varied[i][0] - varied[i - 1][0], varied[i][1], 1e-6);
    }
  }
  EXPECT_GE(lo, 30.0 - 1e-9);
  EXPECT_LE(hi, 120.0 + 1e-9);
  EXPECT_LT(lo, 40.0);  // the spread is used, not just allowed
  EXPECT_GT(hi, 90.0);
}

}  // namespace
}  // namespace scpkit
