// Diagnose's private statistics (lib/src/diagnosis): the least-squares line and the one-sided
// sign-flip test of the per-block held-out gains (stats.hpp), the calibration of the congruency
// signature and of the return-point signature (signatures.hpp), and the outliers' ramp scores
// (detectors.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <random>
#include <utility>
#include <vector>

#include "diagnosis/baseline.hpp"
#include "diagnosis/detectors.hpp"
#include "diagnosis/signatures.hpp"
#include "diagnosis/stats.hpp"
#include "test_support.hpp"

namespace scpkit::diagnosis {
namespace {

TEST(RobustStatistics, MedianAndMadAreOddUnderNegationAndExact) {
  EXPECT_DOUBLE_EQ(median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_DOUBLE_EQ(median({4.0, 1.0, 3.0, 2.0}), 2.5);
  EXPECT_DOUBLE_EQ(median({5.0, 7.0}), 6.0);  // two hold-mates: between them, not the higher
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.3, 2.0);
  for (int n = 1; n <= 40; ++n) {
    std::vector<double> v(static_cast<std::size_t>(n)), neg(v.size()), shifted(v.size());
    for (double& x : v) x = g(rng);
    for (std::size_t i = 0; i < v.size(); ++i) {
      neg[i] = -v[i];
      shifted[i] = 2.5 * v[i] + 7.0;
    }
    // Independently: sort, and take the middle one or the mean of the middle two.
    std::vector<double> s = v;
    std::sort(s.begin(), s.end());
    const std::size_t h = s.size() / 2;
    const double expect = s.size() % 2 ? s[h] : 0.5 * (s[h - 1] + s[h]);
    EXPECT_DOUBLE_EQ(median(v), expect) << n;
    EXPECT_DOUBLE_EQ(median(neg), -median(v)) << n;
    EXPECT_NEAR(median(shifted), 2.5 * median(v) + 7.0, 1e-12) << n;
    EXPECT_DOUBLE_EQ(mad(neg), mad(v)) << n;
    EXPECT_NEAR(mad(shifted), 2.5 * mad(v), 1e-12) << n;
  }
}

// The least-squares line from running sums: exact on points on a line; on scattered points the
// slope and intercept zero the normal equations' residual moments and the SSE is the residuals'
// sum of squares, both computed here from the returned coefficients.
TEST(LineSums, TheLeastSquaresLineAndItsResidualSumOfSquares) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int n = 2; n <= 40; ++n) {
    std::vector<double> x(static_cast<std::size_t>(n)), y(x.size());
    LineSums exact, noisy;
    for (std::size_t i = 0; i < x.size(); ++i) {
      x[i] = 3.0 * g(rng) + 1.0;
      exact.add(x[i], -0.75 * x[i] + 2.0);
      y[i] = 0.4 * x[i] - 1.0 + g(rng);
      noisy.add(x[i], y[i]);
    }
    EXPECT_NEAR(exact.slope(), -0.75, 1e-12) << n;
    EXPECT_NEAR(exact.intercept(exact.slope()), 2.0, 1e-12) << n;
    EXPECT_NEAR(exact.sse(), 0.0, 1e-10) << n;
    const double b = noisy.slope(), c = noisy.intercept(b);
    double m0 = 0.0, m1 = 0.0, sse = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double e = y[i] - c - b * x[i];
      m0 += e;
      m1 += e * x[i];
      sse += e * e;
    }
    EXPECT_NEAR(m0, 0.0, 1e-9) << n;
    EXPECT_NEAR(m1, 0.0, 1e-9) << n;
    EXPECT_NEAR(noisy.sse(), sse, 1e-9 * (1.0 + sse)) << n;
  }
  LineSums flat;  // x does not vary: no slope, the intercept is the mean
  for (double y : {1.0, 2.0, 6.0}) flat.add(5.0, y);
  EXPECT_EQ(flat.slope(), 0.0);
  EXPECT_DOUBLE_EQ(flat.intercept(0.0), 3.0);
  EXPECT_DOUBLE_EQ(flat.sse(), 14.0);
}

TEST(SignFlip, ExactWhenFewBlocks) {
  std::mt19937_64 rng(1);
  // Five blocks that all gain: only the observed signs reach the observed rank sum: 1 / 2^5.
  EXPECT_DOUBLE_EQ(sign_flip_p({1.0, 2.0, 3.0, 4.0, 5.0}, 199, rng), 1.0 / 32.0);
  // The second block loses: sum 11, reached or passed by flipping nothing, the loss, or the
  // loss and the first block (13); every other pattern sums to less.
  EXPECT_DOUBLE_EQ(sign_flip_p({1.0, -2.0, 3.0, 4.0, 5.0}, 199, rng), 3.0 / 32.0);
}

TEST(SignFlip, NoGainIsNeverSignificant) {
  std::mt19937_64 rng(2);
  EXPECT_EQ(sign_flip_p({}, 199, rng), 1.0);
  EXPECT_EQ(sign_flip_p({-1.0, -2.0, 0.5}, 199, rng), 1.0);
  // A positive total carried by one block while the others lose: the sign of that one block
  // decides, so about one half.
  std::vector<double> one_block(20, -1.0);
  one_block[7] = 100.0;
  EXPECT_GT(sign_flip_p(one_block, 199, rng), 0.3);
}

TEST(SignFlip, ConsistentGainsAreSignificant) {
  std::mt19937_64 data(3), rng(3);
  std::normal_distribution<double> N(1.0, 1.0);  // every block gains 1 on average
  std::vector<double> d(24);
  for (double& x : d) x = N(data);
  EXPECT_LT(sign_flip_p(d, 199, rng), 0.01);
}

TEST(SignFlip, UniformUnderTheNull) {
  // Gains symmetric about zero (heavy-tailed, several block counts): about 5 % of p-values
  // fall below 0.05.
  std::mt19937_64 data(4), rng(5);
  std::student_t_distribution<double> T(2.0);
  int below = 0, trials = 0;
  for (int n : {8, 24, 40}) {
    for (int i = 0; i < 300; ++i) {
      std::vector<double> d(static_cast<std::size_t>(n));
      for (double& x : d) x = T(data);
      below += sign_flip_p(d, 199, rng) < 0.05 ? 1 : 0;
      ++trials;
    }
  }
  const double rate = static_cast<double>(below) / trials;
  EXPECT_GT(rate, 0.025);
  EXPECT_LT(rate, 0.075);
}

// A load record of a Preisach truth on a coarse relay grid (8-24 levels, or `grid_levels`: its
// response steps irregularly between readings) plus a linear term, read once per step (`fewest`
// to `most` steps per unit of the input) along ramps between turning values drawn at random,
// with white noise of `noise` times the range.
Record monotone_branches(std::mt19937& rng, double noise, int fewest, int most,
                         std::pair<int, int> grid_levels = {8, 24}) {
  std::uniform_int_distribution<int> levels(grid_levels.first, grid_levels.second);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const PreisachGrid grid{0.0, 1.0, levels(rng)};
  const PreisachModel model = testing::random_model(rng, grid);
  const double linear = 5.0 * U(rng);
  const int steps = std::uniform_int_distribution<int>(fewest, most)(rng);
  std::vector<double> u{0.0};
  for (int turn = 0; turn < 12; ++turn) {
    const double from = u.back(), to = turn % 2 == 0 ? 0.5 + 0.5 * U(rng) : 0.5 * U(rng);
    const int n = std::max(2, static_cast<int>(std::lround(std::abs(to - from) * steps)));
    for (int k = 1; k <= n; ++k) u.push_back(from + (to - from) * k / n);
  }
  PreisachState state = PreisachState::negative_saturation(grid);
  std::vector<double> clean;
  clean.reserve(u.size());
  for (double v : u) clean.push_back(model.step(state, v) + linear * v);
  const auto [lo, hi] = std::minmax_element(clean.begin(), clean.end());
  std::normal_distribution<double> N(0.0, noise * (*hi - *lo));
  DiagnoseData data;
  data.input = u;
  for (double y : clean) data.output.push_back(y + N(rng));
  return make_record(data, DiagnoseOptions{});
}

// ramp_scores judges readings by how far they break a monotone branch. Without spikes a reading
// of a monotone truth seldom reaches kRamp (6, outliers.cpp), however coarse the reading step
// against the grid's (8-30 readings per unit, or 40-80); where the readings are fine (40-80 per
// unit), so that the noise dominates the grid's steps between them, a reading moved 15 noise sigmas
// against the branch (inside a ramp, at a turning value, or two in a row) must; and the scores do
// not depend on the response's sign or unit.
TEST(RampScores, MonotoneBranchesScoreUnderTheNoiseAndBrokenOnesAbove) {
  constexpr double kRamp = 6.0, kMove = 15.0;
  std::mt19937 rng(62);
  std::uniform_real_distribution<double> noise_of(0.002, 0.02);
  int alarms = 0;  // clean records with a reading at kRamp or above
  for (int trial = 0; trial < 400; ++trial) {
    const std::vector<double> s = ramp_scores(monotone_branches(rng, noise_of(rng), 8, 30), 0.0);
    alarms += *std::max_element(s.begin(), s.end()) >= kRamp;
  }
  int single = 0, turning = 0, pairs = 0, outward = 0, outward_tried = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const double noise = noise_of(rng);
    const Record rec = monotone_branches(rng, noise, 40, 80);
    const std::vector<double> clean = ramp_scores(rec, 0.0);
    alarms += *std::max_element(clean.begin(), clean.end()) >= kRamp;
    // Sign and unit: the same scores on -3 times the response.
    Record flipped = rec;
    for (double& y : flipped.y) y *= -3.0;
    flipped.range *= 3.0;
    const std::vector<double> same = ramp_scores(flipped, 0.0);
    for (std::size_t t = 0; t < rec.size(); ++t) ASSERT_NEAR(same[t], clean[t], 1e-9) << trial;
    // The readings of a rising response; where the input turns or ramps.
    const std::size_t n = rec.size();
    const double move = kMove * noise * rec.range;
    auto up = [&](std::size_t t) { return rec.u[t + 1] > rec.u[t]; };
    std::vector<std::size_t> tops, ramps;
    for (std::size_t t = 2; t + 2 < n; ++t) {
      if (up(t - 1) && !up(t)) tops.push_back(t);
      if (up(t - 2) == up(t - 1) && up(t - 1) == up(t) && up(t) == up(t + 1)) ramps.push_back(t);
    }
    ASSERT_FALSE(tops.empty());
    ASSERT_GE(ramps.size(), 2U);
    // The readings `at` (consecutive) moved below the readings either side of them.
    auto broken = [&](const std::vector<std::size_t>& at) {
      Record spiked = rec;
      const double below = std::min(rec.y[at.front() - 1], rec.y[at.back() + 1]) - move;
      for (std::size_t t : at) spiked.y[t] = below;
      const std::vector<double> s = ramp_scores(spiked, 0.0);
      for (std::size_t t : at) {
        if (s[t] <= kRamp) return false;
      }
      return true;
    };
    const std::size_t top = tops[static_cast<std::size_t>(trial) % tops.size()];
    const std::size_t mid = ramps[static_cast<std::size_t>(trial) % (ramps.size() - 1)];
    single += broken({mid});
    turning += broken({top});
    pairs += broken({mid, mid + 1});
    // A top moved up, the way the input turns: still the highest of its neighbours, but both
    // its steps longer than any other pass makes over their inputs. Judged where some other
    // rise spans the step in and some other fall the step out (a pass: readings along which
    // the input moves one way; the input turns at every top and bottom).
    auto spanned = [&](double lo, double hi, bool rising) {
      for (std::size_t s = 0; s + 1 < n;) {
        std::size_t e = s;
        while (e + 1 < n && up(e) == rising) ++e;
        const bool other = !(s <= top && top <= e);
        if (e > s && other && std::min(rec.u[s], rec.u[e]) <= lo &&
            std::max(rec.u[s], rec.u[e]) >= hi)
          return true;
        s = std::max(e, s + 1);
      }
      return false;
    };
    if (spanned(rec.u[top - 1], rec.u[top], true) && spanned(rec.u[top + 1], rec.u[top], false)) {
      Record spiked = rec;
      spiked.y[top] += move;
      ++outward_tried;
      outward += ramp_scores(spiked, 0.0)[top] > kRamp;
    }
  }
  // Gaussian noise reaches kRamp now and then at a flat top (a reading 3 sigmas low beside one
  // 4 sigmas high after the turn): measured, 1 of the 5400 clean records of seeds 1-8 and 62.
  EXPECT_LE(alarms, 2);
  EXPECT_EQ(single, 200);
  EXPECT_EQ(turning, 200);
  EXPECT_EQ(pairs, 200);
  EXPECT_GE(outward_tried, 100);
  EXPECT_EQ(outward, outward_tried);
}

// A spike smaller than its ramp's step stays inside the interval of its neighbours and breaks
// no monotone branch; ramp_scores still scores it beyond kRamp where the branch is smooth
// between readings (a fine grid of 200-300 levels, read at 8-30 readings per unit) and the spike
// stands 20 noise sigmas or more off it (half the smaller of its two steps, or 60 sigmas,
// whichever is less), in the middle of seven readings along a ramp: its neighbours'
// interpolations then move the other way by its weights, which a relay's step between two
// readings or a kink does not (measured: 126 of 128 tried). The clean records of the test above,
// on coarse grids that make that pattern at many readings, keep it under kRamp.
TEST(RampScores, ASpikeInsideItsRampIsScoredWhereTheBranchIsSmooth) {
  constexpr double kRamp = 6.0;
  std::mt19937 rng(74);
  std::uniform_real_distribution<double> noise_of(0.0005, 0.003);
  int tried = 0, scored = 0, alarms = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const double noise = noise_of(rng);
    const Record rec = monotone_branches(rng, noise, 8, 30, {200, 300});
    const std::vector<double> clean = ramp_scores(rec, 0.0);
    alarms += *std::max_element(clean.begin(), clean.end()) >= kRamp;
    const std::size_t n = rec.size();
    auto up = [&](std::size_t t) { return rec.u[t + 1] > rec.u[t]; };
    std::vector<std::size_t> ramps;
    for (std::size_t t = 3; t + 3 < n; ++t) {  // seven readings along one ramp
      bool one_way = true;
      for (std::size_t k = t - 3; k < t + 3; ++k) one_way = one_way && up(k) == up(t);
      if (one_way) ramps.push_back(t);
    }
    if (ramps.size() < 11) continue;  // six outside the spike's footprint of five (ramp_scores.cpp)
    const std::size_t t = ramps[static_cast<std::size_t>(trial) % ramps.size()];
    const double sigma = noise * rec.range;
    const double step =
        std::min(std::abs(rec.y[t] - rec.y[t - 1]), std::abs(rec.y[t + 1] - rec.y[t]));
    const double move = std::min(0.5 * step, 60.0 * sigma);
    if (move < 20.0 * sigma) continue;
    Record spiked = rec;
    spiked.y[t] += trial % 2 == 0 ? move : -move;
    ++tried;
    scored += ramp_scores(spiked, 0.0)[t] > kRamp;
  }
  EXPECT_LE(alarms, 1);
  EXPECT_GE(tried, 100);
  EXPECT_GE(scored, tried * 95 / 100) << scored << " of " << tried;
}

// Appends a ramp from u's last value to `to` at `per_unit` readings per unit input.
void ramp(std::vector<double>& u, double to, double per_unit) {
  const double from = u.back();
  const int n = std::max(1, static_cast<int>(std::lround(std::abs(to - from) * per_unit)));
  for (int k = 1; k <= n; ++k) u.push_back(from + (to - from) * k / n);
}

// The input path `u` through a congruent truth (a classical Preisach model plus a linear term)
// read with Gaussian noise of `noise` times the range. `height` maps the clean output x (in
// units of its range) to x + height x (x - 1): loop heights that change with the output level,
// which no classical model makes (non-congruent).
Record loops_through(std::mt19937& rng, const std::vector<double>& u, double noise,
                     double height = 0.0) {
  const PreisachGrid grid{0.0, 1.0, 10};
  const PreisachModel model = testing::random_model(rng, grid);
  PreisachState state = PreisachState::negative_saturation(grid);
  std::normal_distribution<double> N(0.0, 1.0);
  DiagnoseData data;
  std::vector<double> clean;
  clean.reserve(u.size());
  for (double v : u) clean.push_back(model.step(state, v) + 5.0 * v);
  const auto [lo, hi] = std::minmax_element(clean.begin(), clean.end());
  const double low = *lo, range = *hi - *lo;
  for (double& y : clean) {
    const double x = (y - low) / range;
    y = low + range * (x + height * x * (x - 1.0));
  }
  for (std::size_t t = 0; t < u.size(); ++t) {
    data.input.push_back(u[t]);
    data.output.push_back(clean[t] + noise * range * N(rng));
  }
  return make_record(data, DiagnoseOptions{});
}

// Minor loops 0.35 <-> 0.7 from two histories (after the maximum, and from the minimum), twice.
// `second_grid` readings per unit input on the second pass (12 on the first): another grid
// makes the second pass's branches compare with the first's by interpolation.
Record congruent_loops(std::mt19937& rng, double noise, double second_grid = 12.0,
                       double height = 0.0) {
  std::vector<double> u{0.0};
  for (int rep = 0; rep < 2; ++rep) {
    for (double to : {1.0, 0.35, 0.7, 0.35, 0.0, 0.7, 0.35, 0.7, 0.0})
      ramp(u, to, rep == 0 ? 12.0 : second_grid);
  }
  return loops_through(rng, u, noise, height);
}

// How often the congruency signature falls below 0.01 and 0.05 (raw and spike-robust) over
// `per_noise` congruent records at each of three noise levels (0.3, 1 and 3 % of the range),
// `make(noise)` making each record.
struct Rates {
  int below_1 = 0, below_5 = 0, robust_below_1 = 0, robust_below_5 = 0, trials = 0;
};
template <class Make>
Rates congruent_rates(int per_noise, Make make) {
  Rates r;
  for (double noise : {0.003, 0.01, 0.03}) {
    for (int i = 0; i < per_noise; ++i) {
      const CongruencySignatures both = congruency_signatures(make(noise));
      EXPECT_TRUE(both.raw.available && both.robust.available);
      r.below_1 += both.raw.p_value < 0.01 ? 1 : 0;
      r.below_5 += both.raw.p_value < 0.05 ? 1 : 0;
      r.robust_below_1 += both.robust.p_value < 0.01 ? 1 : 0;
      r.robust_below_5 += both.robust.p_value < 0.05 ? 1 : 0;
      ++r.trials;
    }
  }
  return r;
}

TEST(CongruencySignature, InterpolationOnAnotherGridIsNotNonCongruence) {
  // The second pass read on another grid (7 to 17 readings per unit, not 12): its branches
  // compare with the first pass's through A interpolated between readings, which errs where
  // the plane's relays step, while pairs on one grid are exact. Nearly noise-free (none, or
  // 0.05 % of the range) congruent truths must rarely fall below 0.001, the level at which the
  // signature names non-congruence alone, and a loop height that follows the output level
  // (0.3) read the same way must still be found. Measured on these 300: 3 clean records below
  // 0.001 with each group of pairs (aligned, interpolated) on its own yardstick where both
  // have the degrees of freedom (session 60), 4 with the pairs pooled; 299 found. (The split
  // is pinned by the fourth-generator record of tests/independent_test.sh, where six aligned
  // pairs exact to 1e-15 set the pooled yardstick.)
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> grid(7.0, 17.0);
  int clean_below = 0, found = 0, trials = 0;
  for (int i = 0; i < 300; ++i) {
    double second = grid(rng);
    if (std::abs(second - 12.0) < 1.0) second += 3.0;
    const double noise = i % 2 == 0 ? 0.0 : 0.0005;
    const Signature c = congruency_signatures(congruent_loops(rng, noise, second)).raw;
    const Signature n = congruency_signatures(congruent_loops(rng, noise, second, 0.3)).raw;
    ASSERT_TRUE(c.available && n.available);
    clean_below += c.p_value < 0.001 ? 1 : 0;
    found += n.p_value < 0.01 ? 1 : 0;
    ++trials;
  }
  EXPECT_LE(clean_below, trials / 60) << "of " << trials;
  EXPECT_GE(found, trials * 9 / 10) << "of " << trials;
}

TEST(CongruencySignature, CalibratedOnCongruentLoops) {
  // Few comparisons (8 pairs of branches, about 15 residual degrees of freedom): the scatter
  // they estimate is itself uncertain, so the statistic is F, not chi-square. Measured on these
  // 450 records: read as chi-square, 4.4 % below 0.01 and 11 % below 0.05; as F, 1.1 % and 6 %;
  // as F with the differences whitened by their covariance (pairs share branches here too,
  // test CalibratedWhereBranchesEnterSeveralPairs), 0 % and 3.3 %.
  std::mt19937 rng(11);
  const Rates r = congruent_rates(150, [&](double noise) { return congruent_loops(rng, noise); });
  const double trials = r.trials;
  EXPECT_LT(r.below_1 / trials, 0.025);
  EXPECT_LT(r.below_5 / trials, 0.085);
  EXPECT_GT(r.below_5 / trials, 0.02);  // a test, not a switch that is off
  // The spike-robust reading is conservative too (measured: 1 of 450 below 0.01, 7 below 0.05).
  EXPECT_LT(r.robust_below_1 / trials, 0.01);
  EXPECT_LT(r.robust_below_5 / trials, 0.05);
}

TEST(CongruencySignature, CalibratedWhereBranchesEnterSeveralPairs) {
  // Minor loops 0.35 <-> 0.7 repeated five times from each of two histories: each branch of
  // the second history's five loops takes the first history's last loop as A, and the turning
  // reading that ends one pair's B starts the next pair's, against the same turning reading of
  // A. The pairs share readings; read as independent, their slopes count a shared branch's
  // noise more than once (measured on these 600 congruent records: 3.3 % below 0.01 and 9.2 %
  // below 0.05 so). Whitened by the differences' covariance the statistic is F exactly for
  // Gaussian noise: measured, 0.8 % and 4.3 %.
  std::mt19937 rng(14);
  std::vector<double> u{0.0};
  ramp(u, 1.0, 12.0);
  ramp(u, 0.35, 12.0);
  for (int k = 0; k < 5; ++k) {
    ramp(u, 0.7, 12.0);
    ramp(u, 0.35, 12.0);
  }
  ramp(u, 0.0, 12.0);
  for (int k = 0; k < 5; ++k) {
    ramp(u, 0.7, 12.0);
    ramp(u, 0.35, 12.0);
  }
  ramp(u, 0.0, 12.0);
  const Rates r = congruent_rates(200, [&](double noise) { return loops_through(rng, u, noise); });
  const double trials = r.trials;
  EXPECT_LT(r.below_1 / trials, 0.02);
  EXPECT_LT(r.below_5 / trials, 0.075);
  EXPECT_GT(r.below_5 / trials, 0.025);  // a test, not a switch that is off
  // And a loop height that follows the output level (0.3, as the other tests) is still found
  // at 0.2 % noise. Measured, these 100: 84 below 0.01 (99 read as independent, whose level is
  // over three times its nominal here).
  int found = 0;
  for (int i = 0; i < 100; ++i)
    found += congruency_signatures(loops_through(rng, u, 0.002, 0.3)).raw.p_value < 0.01 ? 1 : 0;
  EXPECT_GE(found, 75);
}

TEST(CongruencySignature, ASpikeAtATurningValueIsNotNonCongruence) {
  // A spike at a turning reading of a minor loop enters every pair of branches that starts or
  // ends there. What changes along a branch is read through a running median of three, so it
  // does not count as a change of loop shape in the robust reading (measured: a fresh
  // independent-generator record, 5 % spikes at 0.02 mm noise, p = 0.00059 and named
  // minor_loop_noncongruence before; 0.025 after). 150 congruent records, one spike of 8-15 noise
  // sigmas at a random turning reading.
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> size(8.0, 15.0);
  int below_01 = 0, below_1 = 0, trials = 0;
  for (int i = 0; i < 150; ++i) {
    const double noise = 0.01;
    Record rec = congruent_loops(rng, noise);
    std::vector<std::size_t> turns;
    for (std::size_t t = 1; t + 1 < rec.size(); ++t) {
      if ((rec.u[t] - rec.u[t - 1]) * (rec.u[t + 1] - rec.u[t]) < 0.0 && rec.u[t] > 0.3 &&
          rec.u[t] < 0.75)
        turns.push_back(t);
    }
    ASSERT_GE(turns.size(), 4U);
    const std::size_t t = turns[static_cast<std::size_t>(i) % turns.size()];
    rec.y[t] += (i % 2 == 0 ? 1.0 : -1.0) * size(rng) * noise * rec.range;
    const Signature s = congruency_signatures(rec).robust;
    ASSERT_TRUE(s.available);
    below_01 += s.p_value < 0.001 ? 1 : 0;
    below_1 += s.p_value < 0.01 ? 1 : 0;
    ++trials;
  }
  EXPECT_LE(below_01, 1) << "of " << trials;
  EXPECT_LT(static_cast<double>(below_1) / trials, 0.05) << below_1 << " of " << trials;
}

// A voltage test: eight constant-load segments of three full cycles 0 -> 1 -> 0 each, one
// reading per step and second. A classical Preisach truth plus a linear term and an offset per
// load, a linear drift of `drift` (in units of the range over the record) and sensor noise that
// is AR(1) with lag-one correlation `rho` (white at 0). `nested`: the three cycles go to 1, 3/4
// and 1/2 in steps of 1/8, 3/32 and 1/16, so readings of one memory state (rising from 0 to an
// input the cycles share) are few and never next to each other in two cycles.
Record cycles_with_noise(std::mt19937& rng, double noise, double rho, double drift,
                         bool nested = false) {
  const PreisachGrid grid{0.0, 1.0, 10};
  const PreisachModel model = testing::random_model(rng, grid);
  std::normal_distribution<double> N(0.0, 1.0);
  DiagnoseData data;
  data.input_is_load = false;
  std::vector<double> clean;
  for (int s = 0; s < 8; ++s) {
    PreisachState state = PreisachState::negative_saturation(grid);
    std::vector<double> u{0.0};
    for (int c = 0; c < 3; ++c) {
      const double step =
          nested ? std::array{4.0, 3.0, 2.0}[static_cast<std::size_t>(c)] / 32.0 : 1.0 / 8.0;
      for (int k = 1; k <= 8; ++k) u.push_back(k * step);
      for (int k = 7; k >= 0; --k) u.push_back(k * step);
    }
    for (double v : u) {
      clean.push_back(model.step(state, v) + 5.0 * v + 0.5 * s);
      data.input.push_back(v);
      data.segments.push_back(s);
      data.load_N.push_back(0.3 + 0.1 * s);
    }
  }
  const auto [lo, hi] = std::minmax_element(clean.begin(), clean.end());
  const double range = *hi - *lo;
  double e = N(rng);
  for (std::size_t t = 0; t < clean.size(); ++t) {
    e = rho * e + std::sqrt(1.0 - rho * rho) * N(rng);
    const double trend = drift * static_cast<double>(t) / static_cast<double>(clean.size() - 1);
    data.time_s.push_back(static_cast<double>(t));
    data.output.push_back(clean[t] + range * (trend + noise * e));
  }
  return make_record(data, DiagnoseOptions{});
}

// How often a signature drawn on 300 records (`draw(rng)`; those where it is not available
// skipped) falls below `level`.
template <class Draw>
double rate_below(double level, unsigned seed, Draw draw) {
  std::mt19937 rng(seed);
  int below = 0, trials = 0;
  for (int i = 0; i < 300; ++i) {
    const Signature s = draw(rng);
    if (!s.available) continue;
    below += s.p_value < level ? 1 : 0;
    ++trials;
  }
  EXPECT_GT(trials, 250);
  return static_cast<double>(below) / std::max(trials, 1);
}

// How the records of return_point_rate are drawn and read.
struct ReturnPointDraw {
  bool running_max = false;  ///< the running-maximum signature (else the time signature)
  bool nested = false;       ///< cycles_with_noise's nested loops
  bool told_rho = false;     ///< the noise's lag-one correlation given to the test
};

// How often the return-point time signature (readings in the same memory state, apart in time:
// the drift's model-free evidence), or with `running_max` the running-maximum signature (the
// lonely stroke's), falls below `level` on 300 records.
double return_point_rate(double rho, double drift, double level, unsigned seed,
                         ReturnPointDraw how = {}) {
  return rate_below(level, seed, [&](std::mt19937& rng) {
    const double noise = 0.01;
    const Record rec = cycles_with_noise(rng, noise, rho, drift * noise, how.nested);
    const ReturnPointSignatures both =
        return_point_signatures(rec, noise * rec.range, how.told_rho ? rho : 0.0);
    return how.running_max ? both.running_max : both.time;
  });
}

TEST(ReturnPointSignature, CalibratedOnWhiteNoise) {
  // Conservative (measured: 3 of 300 below 0.05, none below 0.01): consecutive pairs of one
  // memory state share readings, which the regression does not credit.
  EXPECT_LT(return_point_rate(0.0, 0.0, 0.01, 22), 0.025);
  EXPECT_LT(return_point_rate(0.0, 0.0, 0.05, 21), 0.08);
}

TEST(ReturnPointSignature, SensorNoiseThatIsNotWhiteIsNotADrift) {
  // Neighbouring readings' noise moves together, and so do the pairs of readings one cycle
  // apart that sit side by side in time. Without the AR(1) inflation of the variance the test
  // fell below 0.01 in 9 of 300 records at rho 0.5 and 52 of 300 at rho 0.8 (and named a drift
  // in 4 of 30 clean voltage records of the independent generator); with it, in none.
  for (double rho : {0.5, 0.8}) {
    EXPECT_LT(return_point_rate(rho, 0.0, 0.01, 23), 0.02) << "rho " << rho;
  }
}

TEST(ReturnPointSignature, NoiseThatIsNotWhiteIsNotAnEffectOnNestedLoops) {
  // Nested loops of other steps leave no two pairs whose readings both moved on by one, so the
  // pairs cannot show the noise's correlation, and the record's estimate (Context::noise_rho)
  // is given instead. AR(1) noise at rho 0.8, 300 records each: the time signature fell below
  // 0.01 in 4.3 % of them without it and 1.0 % with it; the running-maximum signature in 7.3 %
  // and 0.7 %.
  EXPECT_LT(return_point_rate(0.8, 0.0, 0.01, 27, {.nested = true, .told_rho = true}), 0.025);
  EXPECT_LT(return_point_rate(0.8, 0.0, 0.01, 29,
                              {.running_max = true, .nested = true, .told_rho = true}),
            0.025);
}

// The running-maximum signature pairs each first-rise reading with the same state in the next
// cycle, and that reading with the one after (a -> b, b -> c), so rows share readings; with
// AR(1) noise readings close in the record move together though their rows lie apart. With
// only the lag-one inflation of the rows the test fell below 0.01 in 19 and 26 of 300 clean
// records at rho 0.5 and 0.8 (below 0.05 in 38 and 51); with the covariance of differences of
// AR(1) readings (signatures.cpp, least_squares) in 5 and 5 (17 and 11). White: 1 either way.
TEST(ReturnPointSignature, RunningMaximumCalibratedUnderNoiseThatIsNotWhite) {
  for (double rho : {0.0, 0.5, 0.8}) {
    EXPECT_LT(return_point_rate(rho, 0.0, 0.01, 25, {.running_max = true}), 0.03) << "rho " << rho;
    EXPECT_LT(return_point_rate(rho, 0.0, 0.05, 26, {.running_max = true}), 0.09) << "rho " << rho;
  }
}

TEST(ReturnPointSignature, FindsADriftOfAFewNoiseSigmas) {
  // A drift of 8 noise sigmas over the record, one of them within each load segment, white
  // noise: found below 0.01 in 223 of 300 records (232 without the inflation).
  EXPECT_GT(return_point_rate(0.0, 8.0, 0.01, 24), 0.6);
}

// A load test of 12 excursions 0 -> amp -> 0 (amp 1/2, 3/4 or 1, each ramp in steps of 1/8 or
// 1/4 drawn at random), one reading per second: readings in one memory state are reached along
// paths of different steps, so a lag leaves them apart (the pairs the signature uses are those
// across which the running maximum did not grow: after the first excursion to 1). A classical
// Preisach truth plus a linear term, seen through a Kelvin element of fraction `c` (tau two
// readings), AR(1) sensor noise. `lag` gets the Kelvin element's departure from the noise-free
// rate-independent output (tau two readings), the feature lag_signature tests.
Record excursions(std::mt19937& rng, double noise, double rho, double c, std::vector<double>& lag) {
  const PreisachGrid grid{0.0, 1.0, 10};
  const PreisachModel model = testing::random_model(rng, grid);
  std::uniform_int_distribution<int> pick(0, 2), coarse(0, 1);
  std::vector<double> u{0.0};
  for (int e = 0; e < 12; ++e) {
    const int top = 4 + 2 * pick(rng);  // eighths: 4, 6 or 8
    const int up = top == 6 ? 2 : 1 + coarse(rng), down = top == 6 ? 2 : 1 + coarse(rng);
    for (int k = up; k <= top; k += up) u.push_back(k / 8.0);
    for (int k = top - down; k >= 0; k -= down) u.push_back(k / 8.0);
  }
  PreisachState state = PreisachState::negative_saturation(grid);
  std::vector<double> gamma;
  gamma.reserve(u.size());
  for (double v : u) gamma.push_back(model.step(state, v) + 2.0 * v);
  const auto kelvin = [](const std::vector<double>& p, double fraction) {
    std::vector<double> out(p.size());
    const double decay = std::exp(-0.5);
    double v = p.front();
    for (std::size_t t = 0; t < p.size(); ++t) {
      v = t == 0 ? p[t] : p[t] + (v - p[t]) * decay;
      out[t] = (1.0 - fraction) * p[t] + fraction * v;
    }
    return out;
  };
  const std::vector<double> truth = kelvin(gamma, c), departure = kelvin(gamma, 1.0);
  const auto [lo, hi] = std::minmax_element(truth.begin(), truth.end());
  const double range = *hi - *lo;
  std::normal_distribution<double> N(0.0, 1.0);
  DiagnoseData data;
  data.input_is_load = true;
  double e = N(rng);
  lag.clear();
  for (std::size_t t = 0; t < u.size(); ++t) {
    e = rho * e + std::sqrt(1.0 - rho * rho) * N(rng);
    data.input.push_back(u[t]);
    data.time_s.push_back(static_cast<double>(t));
    data.output.push_back(truth[t] + range * noise * e);
    lag.push_back(departure[t] - gamma[t]);
  }
  return make_record(data, DiagnoseOptions{});
}

// How often the lag signature falls below `level` on 300 such records.
double lag_rate(double rho, double c, double level, unsigned seed) {
  return rate_below(level, seed, [&](std::mt19937& rng) {
    const double noise = 0.01;
    std::vector<double> lag;
    const Record rec = excursions(rng, noise, rho, c, lag);
    return lag_signature(rec, lag, noise * rec.range);
  });
}

// Under the null (no lag) the pairs' differences are noise whatever the feature, which is
// fitted, not read off the noisy readings; AR(1) noise is allowed for as in the return-point
// regression. Measured: below 0.01 in 2, 4 and 4 of 300 records at rho 0, 0.5 and 0.8, below
// 0.05 in 13, 16 and 15.
TEST(LagSignature, CalibratedOnWhiteAndCorrelatedNoise) {
  for (double rho : {0.0, 0.5, 0.8}) {
    EXPECT_LT(lag_rate(rho, 0.0, 0.01, 41), 0.035) << "rho " << rho;
    EXPECT_LT(lag_rate(rho, 0.0, 0.05, 42), 0.09) << "rho " << rho;
  }
}

// Measured: a Kelvin element of fraction 0.2 below 0.001 in 291 of 300 records, of 0.1 below
// 0.01 in 211 (below 0.001 in 127), at 1 % noise.
TEST(LagSignature, FindsALagThatARateIndependentModelCannotTakeUp) {
  EXPECT_GT(lag_rate(0.0, 0.2, 0.001, 44), 0.9);
  EXPECT_GT(lag_rate(0.0, 0.1, 0.01, 45), 0.6);
}

// identified_readings: on full cycles 0 -> 1 -> 0, read every 1/8, every Everett pair of a
// held-out reading's memory is traversed by the other cycles, so every held-out reading is
// identified. One cycle also holds an excursion 0 -> 1/4 -> 1/8 -> 0: its reading at 1/8 on the
// way down from 1/4 rests on the pair (1/8, 1/4), which no other cycle traverses, so it alone
// is not identified held out; the readings of the excursion's rise (pairs from 0, as every
// rise) are.
// The lonely stroke's second look (diagnose.cpp, lonely_within_segments): held out by cycles
// inside the segments, every reading of a test at several loads is scored, every segment's
// first rise lies in one fold, and no two consecutive segments' first rises share a fold (so
// the term is always trained on the first rise after the load change before); held out by
// load segment, the end loads always train, from four loads on (three loads, each tested once,
// are held out by cycles, every reading in a fold). Over random protocols and load orders.
TEST(FoldSchemes, CyclesWithinSegmentsScoreEveryFirstRise) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  for (int trial = 0; trial < 40; ++trial) {
    const int loads = 3 + trial % 5, cycles = 3 + trial % 3;
    std::vector<double> F;
    F.reserve(static_cast<std::size_t>(loads));
    for (int s = 0; s < loads; ++s) F.push_back(0.2 + 0.1 * s);
    std::shuffle(F.begin(), F.end(), rng);
    DiagnoseData data;
    data.input_is_load = false;
    std::vector<std::size_t> first_top;  // per segment: the row where the input first tops out
    for (int s = 0; s < loads; ++s) {
      const std::size_t start = data.input.size();
      std::vector<double> u{0.0};
      for (int c = 0; c < cycles; ++c) {
        const double top = c == 0 ? 1.0 : 0.5 + 0.5 * U(rng);
        for (int k = 1; k <= 6; ++k) u.push_back(top * k / 6.0);
        for (int k = 5; k >= 0; --k) u.push_back(top * k / 6.0);
      }
      for (double v : u) {
        data.input.push_back(v);
        data.output.push_back(std::sqrt(v) * (1.0 + F[static_cast<std::size_t>(s)]));
        data.load_N.push_back(F[static_cast<std::size_t>(s)]);
      }
      first_top.push_back(start + 6);
    }
    const Record within = make_record(data, DiagnoseOptions{}, FoldScheme::cycles_within_segments);
    EXPECT_EQ(within.folds, 3) << trial;
    EXPECT_EQ(within.fold_kind, "cycles within load segments");
    for (std::size_t t = 0; t < within.size(); ++t)
      ASSERT_GE(within.fold[t], 0) << trial << " " << t;
    for (std::size_t s = 0; s < within.seg_first.size(); ++s) {
      const std::size_t a = within.seg_first[s];
      for (std::size_t t = a; t <= first_top[s]; ++t)
        EXPECT_EQ(within.fold[t], within.fold[a]) << trial << " segment " << s;
      if (s > 0) {
        EXPECT_NE(within.fold[a], within.fold[within.seg_first[s - 1]]) << trial << " " << s;
      }
    }
    const Record by_load = make_record(data, DiagnoseOptions{});
    if (loads == 3) {  // the middle load alone held out would meet straight maps: by cycles
      EXPECT_EQ(by_load.fold_kind, "cycles") << trial;
      for (std::size_t t = 0; t < by_load.size(); ++t) EXPECT_GE(by_load.fold[t], 0) << trial;
      continue;
    }
    EXPECT_EQ(by_load.fold_kind, "load segments");
    const auto [lo, hi] = std::minmax_element(F.begin(), F.end());
    for (std::size_t t = 0; t < by_load.size(); ++t) {
      const double f = by_load.seg_load[static_cast<std::size_t>(by_load.seg[t])];
      EXPECT_EQ(by_load.fold[t] < 0, f == *lo || f == *hi) << trial << " " << t;
    }
  }
}

// Baseline::fit alternates between the shared loop H and each segment's offset and range until
// the training rows' prediction settles. Held out by cycles inside the segments, a segment's
// training rows can be part of its one cycle (its rise without the descent), where the start
// of the alternation (a line in the input) is biased; two alternations left that bias in the
// held-out prediction (2.5 % of range on a clean noise-free record of this kind). Over random
// protocols of this kind (the input rising through random turns to its top, then straight
// down, the same in every segment; the truth a Prandtl-Ishlinskii operator of play operators,
// computed here, under an affine map of the load), noise-free, the held-out error stays small:
// measured 0.008-0.062 % of range settled, 0.39-1.17 % after two alternations (five of the six
// protocols above 0.3 %).
TEST(BaselineFit, SettlesWhereTheTrainingRowsArePartOfACycle) {
  SCPKIT_SKIP_UNDER_SANITIZERS();
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  for (int trial = 0; trial < 6; ++trial) {
    std::vector<double> points{0.0};
    const int turns = 6 + trial % 4;
    for (int i = 0; i < turns; ++i) points.push_back(U(rng));
    points.push_back(1.0);
    points.push_back(0.0);
    const double per_unit = trial % 2 ? 12.0 : 20.0;
    std::vector<double> u{points[0]};
    for (std::size_t i = 1; i < points.size(); ++i) {
      const double a = points[i - 1], b = points[i];
      const int k = std::max(2, static_cast<int>(std::lround(std::abs(b - a) * per_unit)));
      for (int j = 1; j <= k; ++j) u.push_back(a + (b - a) * j / k);
    }
    std::vector<double> r, w;
    for (int i = 0; i < 10; ++i) {
      r.push_back(0.45 * U(rng));
      w.push_back(0.2 + 0.8 * U(rng));
    }
    const double wsum = std::accumulate(w.begin(), w.end(), 0.0);
    DiagnoseData data;
    data.input_is_load = false;
    const int loads = 4 + trial % 2;
    for (int s = 0; s < loads; ++s) {
      const double x = static_cast<double>(s) / (loads - 1);
      std::vector<double> p = r;  // descended to 0 from above
      for (double v : u) {
        double h = 0.0;
        for (std::size_t i = 0; i < r.size(); ++i) {
          p[i] = std::min(std::max(p[i], v - r[i]), v + r[i]);
          h += w[i] * p[i] / wsum;
        }
        data.input.push_back(v);
        data.output.push_back(4.0 * (0.5 * x + 0.2 * x * x) -
                              4.0 * (0.6 + 0.4 * x) * (0.3 * v + 0.7 * h));
        data.load_N.push_back(0.3 + 0.2 * x);
      }
    }
    const DiagnoseOptions opt;
    const Record rec = make_record(data, opt, FoldScheme::cycles_within_segments);
    const Baseline base(rec, opt.baseline);
    double ss = 0.0;
    std::size_t scored = 0;
    for (int k = 0; k < rec.folds; ++k) {
      std::vector<char> train(rec.size());
      for (std::size_t t = 0; t < rec.size(); ++t) train[t] = rec.trains(t, k) ? 1 : 0;
      const FoldFit fit = base.fit(train);
      for (std::size_t t = 0; t < rec.size(); ++t) {
        if (rec.fold[t] != k) continue;
        ss += (rec.y[t] - fit.pred[t]) * (rec.y[t] - fit.pred[t]);
        ++scored;
      }
    }
    ASSERT_GT(scored, rec.size() / 2) << trial;
    EXPECT_LT(100.0 * std::sqrt(ss / static_cast<double>(scored)) / rec.range, 0.3) << trial;
  }
}

TEST(IdentifiedReadings, PairsTraversedByTheOtherFolds) {
  DiagnoseData data;
  const int cycles = 10, excursion_cycle = 6;
  std::size_t lonely = 0;
  data.input.push_back(0.0);
  for (int c = 0; c < cycles; ++c) {
    for (int k = 1; k <= 8; ++k) data.input.push_back(k / 8.0);
    for (int k = 7; k >= 0; --k) data.input.push_back(k / 8.0);
    if (c == excursion_cycle) {
      data.input.insert(data.input.end(), {1.0 / 8.0, 2.0 / 8.0, 1.0 / 8.0});
      lonely = data.input.size() - 1;
      data.input.push_back(0.0);
    }
  }
  std::mt19937 rng(3);
  std::normal_distribution<double> N(0.0, 0.01);
  for (double u : data.input) data.output.push_back(u * u + N(rng));
  const Record rec = make_record(data, DiagnoseOptions{});
  ASSERT_GE(rec.folds, 2);
  ASSERT_GE(rec.fold[lonely], 0);  // held out
  const std::vector<char> id = identified_readings(rec, 8);
  int held_out = 0;
  for (std::size_t t = 0; t < rec.size(); ++t) {
    if (rec.fold[t] < 0) {
      EXPECT_FALSE(id[t]) << t;  // not held out
      continue;
    }
    ++held_out;
    EXPECT_EQ(static_cast<bool>(id[t]), t != lonely) << "reading " << t << ", input " << rec.u[t];
  }
  EXPECT_GT(held_out, 100);
}

// Inputs read along ramps finer than the baseline's grid: a pair is observed only within the
// record's own input step, not within half a coarse cell (an Everett value moves by several %
// of the range over half a cell). The excursion's reversal at 3/32 is met once; at L = 4 its
// pair (3/32, 2/32) lies on one node and counted as observed before.
TEST(IdentifiedReadings, PairsOnTheRecordsOwnInputSteps) {
  DiagnoseData data;
  const int cycles = 10, excursion_cycle = 6, steps = 32;
  std::size_t lonely = 0;
  data.input.push_back(0.0);
  for (int c = 0; c < cycles; ++c) {
    for (int k = 1; k <= steps; ++k) data.input.push_back(k / static_cast<double>(steps));
    for (int k = steps - 1; k >= 0; --k) data.input.push_back(k / static_cast<double>(steps));
    if (c == excursion_cycle) {
      data.input.insert(data.input.end(), {1.0 / 32, 2.0 / 32, 3.0 / 32, 2.0 / 32});
      lonely = data.input.size() - 1;
      data.input.push_back(1.0 / 32);
      data.input.push_back(0.0);
    }
  }
  std::mt19937 rng(5);
  std::normal_distribution<double> N(0.0, 0.01);
  for (double u : data.input) data.output.push_back(u * u + N(rng));
  const Record rec = make_record(data, DiagnoseOptions{});
  ASSERT_GE(rec.fold[lonely], 0);  // held out
  EXPECT_DOUBLE_EQ(input_steps(rec), 32.0);
  const std::vector<char> id = identified_readings(rec, 4);
  EXPECT_FALSE(id[lonely]);
  int identified = 0, held_out = 0;
  for (std::size_t t = 0; t < rec.size(); ++t) {
    if (rec.fold[t] < 0) continue;
    ++held_out;
    identified += id[t] ? 1 : 0;
  }
  // Every held-out reading of the ordinary cycles is observed by the others' same branches.
  EXPECT_GE(identified, held_out - 3);
  EXPECT_GT(held_out, 500);
}

// The moving Preisach model, y = Gamma[u + a y] (PHYSICS.md section 5), on records written
// out here apart from the library: Gamma a reversible part plus 400 relays, switching up at
// alpha and down at beta < alpha, their weight peaked at the middle of the load span (not a
// Prandtl-Ishlinskii density: a loop moved along the diagonal changes its shape, so the
// records' minor loops between the same loads, entered from the top and from zero, are not
// congruent), solved reading by reading by fixed point, noise-free; a = m x 300 g / 3 mm.
// Fitted with the true a (Baseline::Variant::moving), the held-out error on the readings whose
// memory their fold's training identified falls below the classical fit's, pooled over three
// seeds and m = +-0.3 (measured: 0.62 of it; 5 of the 6 records lower, one level). On the same
// records with m = 0 the moving model at a = 0.3 x 100 g/mm does not (measured: 1.09 times the
// classical error). The grid's discretisation (L levels) is most of what is left.
DiagnoseData moving_preisach_record(double m, unsigned seed);

TEST(BaselineFit, MovingModelFollowsAMovingPreisachRecord) {
  double moved_classical = 0.0, moved_moving = 0.0, still_classical = 0.0, still_moving = 0.0;
  for (const unsigned seed : {1u, 2u, 3u}) {
    for (const double m : {-0.3, 0.0, 0.3}) {
      const DiagnoseData data = moving_preisach_record(m, seed);
      const Record rec = make_record(data, DiagnoseOptions{});
      const Baseline base(rec, DiagnoseOptions{}.baseline);
      const double a = (m == 0.0 ? 0.3 : m) * 300.0 / 3.0;  // g per mm
      const std::vector<char> identified = identified_readings(rec, base.options().levels);
      double& classical_ss = m == 0.0 ? still_classical : moved_classical;
      double& moving_ss = m == 0.0 ? still_moving : moved_moving;
      for (int k = 0; k < rec.folds; ++k) {
        std::vector<char> train(rec.size());
        for (std::size_t t = 0; t < rec.size(); ++t) train[t] = rec.trains(t, k) ? 1 : 0;
        const FoldFit classical = base.fit(train);
        const FoldFit moving = base.fit(train, {nullptr, nullptr, false, a, &classical.pred});
        for (std::size_t t = 0; t < rec.size(); ++t) {
          if (rec.fold[t] != k || !identified[t]) continue;
          classical_ss += std::pow(rec.y[t] - classical.pred[t], 2);
          moving_ss += std::pow(rec.y[t] - moving.pred[t], 2);
        }
      }
    }
  }
  ASSERT_GT(moved_classical, 0.0);
  ASSERT_GT(still_classical, 0.0);
  EXPECT_LT(std::sqrt(moved_moving / moved_classical), 0.75);
  EXPECT_GT(std::sqrt(still_moving / still_classical), 0.9);
}

DiagnoseData moving_preisach_record(double m, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double top = 300.0;
  // Relays switching up at alpha and down at beta < alpha, their weight peaked at the centre
  // of the load span: not a Prandtl-Ishlinskii density, so a loop moved along the diagonal
  // changes its shape (a play model's loops are congruent wherever they sit).
  std::vector<double> alpha, beta, weights;
  for (int i = 0; i < 400; ++i) {
    const double centre = top * uniform(rng), half_width = top * 0.25 * uniform(rng);
    alpha.push_back(centre + half_width);
    beta.push_back(centre - half_width);
    weights.push_back(std::exp(-0.5 * std::pow((centre - 0.5 * top) / (0.2 * top), 2.0)));
  }
  const double weight_sum = std::accumulate(weights.begin(), weights.end(), 0.0);
  std::vector<double> relays(alpha.size(), 0.0);  // 0 off, 1 on: negative saturation
  const double reversible = 0.4, span_mm = 3.0;
  auto response = [&](std::vector<double>& r, double u) {  // mm, switches the relays
    double h = 0.0;
    for (std::size_t i = 0; i < r.size(); ++i) {
      if (u >= alpha[i]) r[i] = 1.0;
      if (u <= beta[i]) r[i] = 0.0;
      h += weights[i] * r[i];
    }
    return span_mm * (reversible * u / top + (1.0 - reversible) * h / weight_sum);
  };
  std::vector<double> loads{0.0};
  auto ramp = [&](double to) {
    const double from = loads.back();
    const int k = std::max(2, static_cast<int>(std::lround(std::abs(to - from) / 30.0)));
    for (int j = 1; j <= k; ++j) loads.push_back(from + (to - from) * j / k);
  };
  for (int pass = 0; pass < 2; ++pass) {
    for (const double to : {300.0, 120.0, 210.0, 120.0, 0.0, 210.0, 120.0, 210.0, 0.0}) ramp(to);
  }
  DiagnoseData data;
  double y = 0.0;
  for (std::size_t t = 0; t < loads.size(); ++t) {
    for (int k = 0; k < 60; ++k) {  // y = Gamma[u + a y]: a contraction at these slopes
      std::vector<double> trial = relays;
      y = response(trial, loads[t] + m * top * y / span_mm);
    }
    y = response(relays, loads[t] + m * top * y / span_mm);
    data.time_s.push_back(60.0 * static_cast<double>(t + 1));
    data.input.push_back(loads[t]);
    data.output.push_back(y);
  }
  return data;
}

}  // namespace
}  // namespace scpkit::diagnosis
