// The held-out gain test of diagnose (private to the library: lib/src/diagnosis/stats.hpp):
// a one-sided sign-flip test on the per-block gains.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "diagnosis/stats.hpp"

namespace scpkit::diagnosis {
namespace {

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

}  // namespace
}  // namespace scpkit::diagnosis
