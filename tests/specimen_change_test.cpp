// What changed between two tests: a reference record of a random Preisach truth, and a second
// record of the same truth changed in one known way (nothing, an offset, a scaled range, a shift
// along the input, another hysteresis), on its own protocol and noise. The comparison must name
// that change, recover its size, and name nothing when nothing changed.
#include "scpkit/diagnosis/specimen_change.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "scpkit/error.hpp"
#include "test_support.hpp"

namespace scpkit {
namespace {

constexpr double kLo = 20.0, kHi = 80.0;  // the input's span (e.g. temperature, C)

// A damped excursion from the bottom: turning points of random height, each ramp read in steps.
std::vector<double> protocol(std::mt19937& rng, int cycles) {
  std::uniform_real_distribution<double> top(0.55, 1.0), bottom(0.0, 0.35);
  std::vector<double> u = {kLo};
  double at = kLo;
  for (int k = 0; k < cycles; ++k) {
    for (double to : {kLo + (kHi - kLo) * (k == 0 ? 1.0 : top(rng)),
                      kLo + (kHi - kLo) * (k + 1 == cycles ? 0.0 : bottom(rng))}) {
      const int steps = 12;
      for (int s = 1; s <= steps; ++s) u.push_back(at + (to - at) * s / steps);
      at = to;
    }
  }
  return u;
}

struct Change {
  double g = 1.0, c = 0.0, d = 0.0;
};

// g Gamma[u - d] + c (Gamma from negative saturation, inputs clamped to its grid) plus white
// noise of `noise` times Gamma's range.
std::vector<double> respond(const PreisachModel& truth, const std::vector<double>& u, Change ch,
                            double noise, std::mt19937& rng) {
  std::vector<double> v(u);
  for (double& x : v) x -= ch.d;
  PreisachState st = PreisachState::negative_saturation(truth.grid());
  const Eigen::VectorXd gam = truth.simulate(st, v);
  const double range = gam.maxCoeff() - gam.minCoeff();
  std::normal_distribution<double> e(0.0, noise * range);
  std::vector<double> y(u.size());
  for (std::size_t t = 0; t < u.size(); ++t)
    y[t] = ch.g * gam[static_cast<Eigen::Index>(t)] + ch.c + e(rng);
  return y;
}

PreisachModel truth_for(std::uint32_t seed) {
  std::mt19937 rng(seed);
  return testing::random_model(rng, PreisachGrid{kLo, kHi, 10});
}

// Another hysteresis over the same span: narrow loops only (mass on the diagonal and the cells
// beside it), where the reference's loops are wide.
PreisachModel narrow_truth(std::uint32_t seed) {
  std::mt19937 rng(seed);
  const PreisachGrid grid{kLo, kHi, 10};
  std::uniform_real_distribution<double> mass(0.2, 1.0);
  Eigen::VectorXd w = Eigen::VectorXd::Zero(grid.cells());
  for (int i = 0; i < grid.levels; ++i) {
    for (int j = i; j < std::min(grid.levels, i + 2); ++j) w[grid.cell_index(i, j)] = mass(rng);
  }
  return PreisachModel(grid, w, 0.0);
}

struct Case {
  std::vector<double> ref_u, ref_y, u, y;
  double range = 0.0;  // of the truth's unchanged response on the second protocol
};

Case make_case(std::uint32_t seed, Change ch, double noise, bool other_truth = false) {
  std::mt19937 rng(seed * 7u + 3u);
  const PreisachModel truth = truth_for(seed);
  Case k;
  k.ref_u = protocol(rng, 6);
  k.ref_y = respond(truth, k.ref_u, {}, noise, rng);
  k.u = protocol(rng, 5);
  const PreisachModel second = other_truth ? narrow_truth(seed) : truth;
  k.y = respond(second, k.u, ch, noise, rng);
  std::mt19937 quiet(1);
  const std::vector<double> plain = respond(truth, k.u, {}, 0.0, quiet);
  k.range =
      *std::max_element(plain.begin(), plain.end()) - *std::min_element(plain.begin(), plain.end());
  return k;
}

SpecimenChange compare(const Case& k) {
  return diagnose_specimen_change(k.ref_u, k.ref_y, k.u, k.y);
}

TEST(SpecimenChange, TheSameSpecimenTestedTwiceNamesNothing) {
  for (std::uint32_t seed = 1; seed <= 12; ++seed) {
    const double noise = seed % 2 ? 0.005 : 0.015;
    const SpecimenChange d = compare(make_case(seed, {}, noise));
    EXPECT_EQ(d.change, "none") << "seed " << seed << ": " << d.candidates[1].evidence;
    // the unchanged model predicts the second test to a few noise levels
    EXPECT_LT(d.candidates.front().heldout_rms_pct, 100.0 * 4.0 * noise + 3.0) << "seed " << seed;
  }
}

TEST(SpecimenChange, AnOffsetIsNamedAndSized) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  for (std::uint32_t seed = 1; seed <= 8; ++seed) {
    const double size = 0.05 + 0.03 * (seed % 4);  // of the range
    Case k = make_case(seed, {}, 0.005);
    for (double& y : k.y) y += size * k.range;
    const SpecimenChange d = compare(k);
    EXPECT_EQ(d.change, "offset") << "seed " << seed;
    EXPECT_NEAR(d.candidates[1].c, size * k.range, 0.02 * k.range) << "seed " << seed;
  }
}

TEST(SpecimenChange, AScaledStrokeIsNamedRangeWithItsFactor) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  for (std::uint32_t seed = 1; seed <= 8; ++seed) {
    const double g = seed % 2 ? 1.25 + 0.1 * (seed % 8) : 0.8 - 0.03 * (seed % 8);  // 0.6-2
    const SpecimenChange d = compare(make_case(seed, {g, 0.0, 0.0}, 0.005));
    EXPECT_EQ(d.change, "range") << "seed " << seed << ", g " << g;
    EXPECT_NEAR(d.candidates[2].g, g, 0.05 * g) << "seed " << seed;
  }
}

TEST(SpecimenChange, ATransitionMovedAlongTheInputIsNamedWithItsShift) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  for (std::uint32_t seed = 1; seed <= 8; ++seed) {
    const double d_true = (seed % 2 ? 1.0 : -1.0) * (kHi - kLo) * (0.06 + 0.01 * (seed % 8));
    const SpecimenChange d = compare(make_case(seed, {1.0, 0.0, d_true}, 0.005));
    EXPECT_EQ(d.change, "input_shift") << "seed " << seed << ", d " << d_true;
    // the shift grid's step is 0.5 % of the reference's identified span
    EXPECT_NEAR(d.candidates[3].d, d_true, 0.03 * (kHi - kLo)) << "seed " << seed;
  }
}

TEST(SpecimenChange, AnotherHysteresisIsNamedShape) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  int named = 0;
  for (std::uint32_t seed = 1; seed <= 8; ++seed) {
    const SpecimenChange d = compare(make_case(seed, {}, 0.005, true));
    EXPECT_NE(d.change, "none") << "seed " << seed;
    named += d.change == "shape";
  }
  EXPECT_GE(named, 6);
}

TEST(SpecimenChange, BadInputIsRefusedWithAReason) {
  const Case k = make_case(1, {}, 0.005);
  const std::vector<double> short_u(k.u.begin(), k.u.begin() + 20),
      short_y(k.y.begin(), k.y.begin() + 20);
  EXPECT_THROW_MSG(diagnose_specimen_change(k.ref_u, k.ref_y, short_u, short_y),
                   IdentificationError, "too few");
  EXPECT_THROW_MSG(diagnose_specimen_change(k.ref_u, k.ref_y, k.u, short_y), InvalidArgument,
                   "differ in length");
  const std::vector<double> flat(k.y.size(), 0.25);
  EXPECT_THROW_MSG(diagnose_specimen_change(k.ref_u, k.ref_y, k.u, flat), IdentificationError,
                   "does not vary");
}

}  // namespace
}  // namespace scpkit
