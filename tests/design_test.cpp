// Design evaluation and sweeps: a design equal to the characterised actuator reproduces its
// own measured loop; every constraint filters what it says; output is identical for any thread
// count; shards merge into exactly the unsharded result.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "scpkit/design/sweep.hpp"
#include "scpkit/error.hpp"
#include "scpkit/io/atomic_file.hpp"
#include "scpkit/io/measurement.hpp"
#include "scpkit/metrics.hpp"
#include "test_support.hpp"

namespace scpkit {
namespace {

namespace fs = std::filesystem;
const fs::path kExamples = fs::path(SCPKIT_SOURCE_DIR) / "examples";

SweepSpec bicep() { return load_sweep_spec(kExamples / "design" / "bicep-sweep.toml"); }

std::vector<std::string> split(const std::string& row) {
  std::vector<std::string> f;
  std::stringstream ss(row);
  std::string x;
  while (std::getline(ss, x, ',')) f.push_back(x);
  if (!row.empty() && row.back() == ',') f.push_back("");
  return f;
}

TEST(Design, TheCharacterisedActuatorReproducesItsOwnMeasuredLoop) {
  SweepSpec spec = bicep();
  spec.voltage_model.clear();
  const SweepContext ctx = prepare_sweep(spec);
  const Measurement m = Measurement::read(kExamples / "data" / "pair-2ply.csv");
  DesignSpec d;
  d.plies = 2;
  d.coil = ctx.characterisation.coil;
  d.coil.length_m = 0.1;
  d.protocol_N = select_input(m, "load").values;
  DesignWorkspace ws;
  const DesignResult r = evaluate_design(ctx.characterisation, ctx.material, d, ws, true);
  ASSERT_TRUE(r.feasible) << r.reason;
  EXPECT_NEAR(r.gain.value, ctx.characterisation.scp_gain.gain, 1e-9);  // same coil, same gain
  std::vector<double> measured;
  for (double v : m.find(Quantity::kScpStrain)->values) measured.push_back(100.0 * v);
  // Within the fit error: the thread fit (about 0.5 % of range RMS) times the gain, plus the
  // scatter of the SCP/thread line.
  EXPECT_LT(error_metrics(measured, r.strain_pct).rms_pct_range, 1.0);
}

// The rows are written with std::to_chars (twice as fast as fmt); every field must read as the
// printf-style "%.6g" the sweep's format has always had, recomputed here with fmt.
TEST(Design, SweepRowsWriteNumbersAsPrintfG6) {
  SweepSpec spec = bicep();
  spec.random_samples = 3000;
  const SweepContext ctx = prepare_sweep(spec);
  DesignWorkspace ws;
  int infeasible = 0;
  for (std::size_t i = 0; i < spec.candidate_count(); i += 7) {
    const DesignSpec d = sweep_candidate(ctx, i);
    const DesignResult r = evaluate_design(ctx.characterisation, ctx.material, d, ws);
    const std::vector<std::string> f = split(sweep_row(ctx, i, d, r));
    ASSERT_EQ(f.size(), 22U);
    const std::vector<double> g6{d.coil.wire_d_m * 1e3,
                                 d.coil.mean_D_m * 1e3,
                                 d.coil.coils,
                                 d.coil.length_m * 1e3,
                                 r.spring_index,
                                 r.pitch_mm,
                                 r.stiffness_N_per_m.value,
                                 r.stiffness_N_per_m.sigma,
                                 r.gain.value,
                                 r.gain.sigma,
                                 r.stroke_mm,
                                 r.stroke_sigma_mm,
                                 r.stroke_pct,
                                 r.hysteresis_pct,
                                 r.thermal_stroke_mm,
                                 r.voltage_for_target_V};
    const std::vector<std::size_t> at{2, 3, 4, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18};
    EXPECT_EQ(f[0], std::to_string(i));
    EXPECT_EQ(f[1], std::to_string(d.plies));
    EXPECT_EQ(f[5], std::to_string(d.coil.legs));
    for (std::size_t k = 0; k < at.size(); ++k)
      EXPECT_EQ(f[at[k]], fmt::format("{:.6g}", g6[k])) << "row " << i << ", field " << at[k];
    infeasible += f[20] == "0" ? 1 : 0;
  }
  EXPECT_GT(infeasible, 0);  // the reasons' path is exercised too
}

TEST(Design, FeasibilityChecksNameTheFailure) {
  SweepSpec spec = bicep();
  const SweepContext ctx = prepare_sweep(spec);
  DesignWorkspace ws;
  DesignSpec d = sweep_candidate(ctx, 0);
  d.coil.mean_D_m = 0.5 * d.coil.wire_d_m;
  EXPECT_NE(evaluate_design(ctx.characterisation, ctx.material, d, ws).reason.find("spring index"),
            std::string::npos);
  d = sweep_candidate(ctx, 0);
  d.coil.coils = 1000;
  EXPECT_NE(evaluate_design(ctx.characterisation, ctx.material, d, ws).reason.find("pitch"),
            std::string::npos);
  d = sweep_candidate(ctx, 0);
  d.load_max_N = 10.0;  // far beyond the identified loads
  EXPECT_NE(evaluate_design(ctx.characterisation, ctx.material, d, ws)
                .reason.find("outside the identified"),
            std::string::npos);
  // Stiffness is the helical-spring formula with the card's shear modulus.
  d = sweep_candidate(ctx, 0);
  const DesignResult r = evaluate_design(ctx.characterisation, ctx.material, d, ws);
  EXPECT_NEAR(r.stiffness_N_per_m.value,
              spring_stiffness(ctx.material.shear_modulus_Pa.value, d.coil), 1e-9);
}

TEST(Sweep, EveryConstraintFiltersWhatItSays) {
  const SweepSpec spec = bicep();
  const SweepContext ctx = prepare_sweep(spec);
  const auto rows = run_sweep(ctx, 0, 1, 2);
  ASSERT_EQ(rows.size(), spec.candidate_count());
  const std::vector<std::string> names = split(sweep_header());
  auto col = [&](const std::string& n) {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), n) - names.begin());
  };
  int feasible = 0;
  std::set<std::string> reasons;
  for (const auto& row : rows) {
    const auto f = split(row);
    ASSERT_EQ(f.size(), names.size()) << row;
    const bool ok = f[col("feasible")] == "1";
    const double thermal = std::stod(f[col("thermal_stroke_mm")]),
                 volts = std::stod(f[col("voltage_for_target_V")]);
    const double stiff = std::stod(f[col("stiffness_N_per_m")]),
                 C = std::stod(f[col("spring_index")]);
    const double pitch = std::stod(f[col("pitch_mm")]), d = std::stod(f[col("d_mm")]);
    const std::string& why = f[col("reason")];
    if (ok) {
      ++feasible;
      EXPECT_TRUE(why.empty());
      EXPECT_GE(thermal, spec.min_thermal_stroke_mm);
      EXPECT_GE(volts, 0.0);
      EXPECT_LE(volts, spec.max_voltage_V);
      EXPECT_LE(stiff, spec.max_stiffness_N_per_m);
      EXPECT_GE(C, 1.0);
      EXPECT_GE(pitch, d);
    } else {
      EXPECT_FALSE(why.empty());
      reasons.insert(why.substr(0, why.find(' ')));
      if (why.rfind("thermal stroke", 0) == 0) {
        EXPECT_LT(thermal, spec.min_thermal_stroke_mm);
      }
      if (why.rfind("stiffness", 0) == 0) {
        EXPECT_GT(stiff, spec.max_stiffness_N_per_m);
      }
      if (why.rfind("pitch", 0) == 0) {
        EXPECT_LT(pitch, d);
      }
    }
  }
  EXPECT_GT(feasible, 0);
  EXPECT_LT(feasible, static_cast<int>(rows.size()));
  EXPECT_GE(reasons.size(), 3u);  // several different constraints bite
}

TEST(Sweep, SameBytesForAnyThreadCountAndShardsMergeToTheWhole) {
  const SweepSpec spec = bicep();
  const SweepContext ctx = prepare_sweep(spec);
  const std::string one = sweep_file(spec, "bicep-sweep.toml", run_sweep(ctx, 0, 1, 1));
  const std::string two = sweep_file(spec, "bicep-sweep.toml", run_sweep(ctx, 0, 1, 2));
  const std::string five = sweep_file(spec, "bicep-sweep.toml", run_sweep(ctx, 0, 1, 5));
  EXPECT_EQ(one, two);
  EXPECT_EQ(one, five);
  const fs::path dir = fs::temp_directory_path() / ("scpkit_sweep_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::vector<fs::path> files;
  for (int k = 0; k < 3; ++k) {
    files.push_back(dir / fmt::format("shard{}.csv", k));
    write_file_atomically(files.back(),
                          sweep_file(spec, "bicep-sweep.toml", run_sweep(ctx, k, 3, 2), k, 3));
  }
  EXPECT_EQ(merge_sweep_files({files[2], files[0], files[1]}), one);
  EXPECT_THROW_MSG(merge_sweep_files({files[0], files[1]}), InputError, "shards missing: 2");
  EXPECT_THROW_MSG(merge_sweep_files({files[0], files[0], files[1]}), InputError, "given twice");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace scpkit
