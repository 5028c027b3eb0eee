// diagnose on rig data with an effect hidden in it: it must name the effect, and name nothing
// on clean data, over several seeds, magnitudes, noise levels and protocols (not one file).
// The scenarios come from tests/diagnose_scenarios.cpp; the full confusion matrix over many
// more of them is tests/diagnose_confusion.cpp (docs/diagnose-confusion.md).
#include "scpkit/diagnosis/diagnose.hpp"

#include <gtest/gtest.h>

#include "diagnose_scenarios.hpp"
#include "test_support.hpp"

namespace scpkit {
namespace {

using testing::make_scenario;

void expect_named(const std::string& side, const std::string& effect,
                  const std::vector<int>& indices) {
  for (int i : indices) {
    const testing::Scenario s = make_scenario(side, effect, i);
    const Diagnosis d = testing::diagnose_scenario(s);
    EXPECT_EQ(d.cause, effect) << s.describe();
    for (const Finding& f : d.findings) {
      EXPECT_GT(f.heldout_rms_before, 0.0) << f.effect;
      if (!f.tested) {
        EXPECT_FALSE(f.detected) << f.effect;
      }
      if (f.detected) {
        EXPECT_LT(f.heldout_rms_after, f.heldout_rms_before) << f.effect;
      }
    }
  }
}


TEST(Diagnose, LoadTestsCleanDriftOutliers) {
  expect_named("load", "none", {0, 1, 2});
  expect_named("load", "drift", {0, 1});
  expect_named("load", "outliers", {0, 1});
}

}  // namespace
}  // namespace scpkit
