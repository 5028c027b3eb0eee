// diagnose on rig data with an effect hidden in it: it must name the effect, and name nothing
// on clean data, over several seeds, magnitudes, noise levels and protocols (not one file).
// This version detects drift and outliers; creep and the lonely stroke on single-record load
// tests are not yet detected (docs/diagnose.md), so they are not asserted here.
#include "scpkit/diagnosis/diagnose.hpp"

#include <gtest/gtest.h>

#include "scpkit/io/measurement.hpp"
#include "scpkit/rig/rig.hpp"
#include "test_support.hpp"

namespace scpkit {
namespace {

struct Case {
  const char* effect;
  double magnitude;
  std::uint64_t seed;
  double noise_mm;
  int cycles;
};

Diagnosis run(const Case& c) {
  RigSpec spec;
  spec.specimen = "thread";
  spec.seed = c.seed;
  spec.noise_mm = c.noise_mm;
  spec.protocol.cycles = c.cycles;
  const std::string e = c.effect;
  if (e == "drift") spec.effects.drift = c.magnitude;
  if (e == "outliers") spec.effects.outliers = c.magnitude;
  static const Material card = find_material("nylon-110-34-dtex");
  const Measurement m = Measurement::parse(run_rig(spec, card).to_csv(), "rig.csv");
  DiagnoseOptions o;  // the defaults, as `scpkit diagnose` runs
  o.seed = c.seed;
  return diagnose(m.find(Quantity::kTime)->values, select_input(m).values,
                  select_response(m).values, {}, o);
}

TEST(Diagnose, NamesTheHiddenEffectAndNothingOnCleanData) {
  const std::vector<Case> cases = {
      {"none", 0.0, 21, 0.01, 8},      {"none", 0.0, 22, 0.03, 12},
      {"drift", 0.03, 21, 0.01, 8},    {"drift", 0.1, 22, 0.03, 12},
      {"outliers", 0.15, 21, 0.01, 8}, {"outliers", 0.5, 22, 0.03, 12},
  };
  for (const Case& c : cases) {
    const Diagnosis d = run(c);
    EXPECT_EQ(d.cause, c.effect) << c.effect << " " << c.magnitude << " seed " << c.seed
                                 << " noise " << c.noise_mm;
    // Every finding reports held-out errors; an untested effect says so.
    for (const Finding& f : d.findings) {
      EXPECT_GT(f.heldout_rms_before, 0.0);
      if (!f.tested) {
        EXPECT_FALSE(f.detected);
      }
    }
  }
}

TEST(Diagnose, TheDriftExtensionGainsOnHeldOutData) {
  const Diagnosis d = run({"drift", 0.1, 31, 0.01, 8});
  const auto it = std::find_if(d.findings.begin(), d.findings.end(),
                               [](const Finding& f) { return f.effect == "drift"; });
  ASSERT_NE(it, d.findings.end());
  EXPECT_TRUE(it->detected);
  EXPECT_LT(it->p_value, 0.01);
  EXPECT_GT(it->gain_pct, 10.0);
  EXPECT_LT(it->heldout_rms_after, it->heldout_rms_before);
}

}  // namespace
}  // namespace scpkit
