// Every model family behind one operator type: forward(inverse(targets)) reproduces every
// reachable target, the memory restarting the same way in both directions.
#include "scpkit/hysteresis/operator.hpp"

#include <gtest/gtest.h>

#include <random>

#include "scpkit/error.hpp"
#include "scpkit/identification/polynomial_fit.hpp"
#include "test_support.hpp"

namespace scpkit {
namespace {

std::vector<HysteresisOperator> families(std::mt19937& rng) {
  const GpiModel g = testing::paper_gpi(rng, -1.0);
  return {HysteresisOperator(testing::random_model(rng, PreisachGrid{0.0, 5.1, 10})),
          HysteresisOperator(g), HysteresisOperator(PolynomialModel{{0.008, -0.173}, 0.0, 5.1}),
          HysteresisOperator(PolynomialModel{{0.1, 0.5, -0.03}, 0.0, 5.1}),
          HysteresisOperator(LonelyModel{testing::random_model(rng, PreisachGrid{0.0, 5.1, 8}),
                                         {0.3, 0.1, 0.0, 0.2, 0.05, 0.0, 0.1, 0.02}})};
}

TEST(Operator, InverseOfForwardReproducesTheTargetsForEveryFamily) {
  std::mt19937 rng(81);
  std::uniform_real_distribution<double> U(0.0, 5.1);
  for (const HysteresisOperator& op : families(rng)) {
    std::vector<double> u(400);
    std::vector<char> starts(u.size(), 0);
    for (std::size_t t = 0; t < u.size(); ++t) {
      u[t] = U(rng);
      // Four segments, each from the initial state; the third after a load increase (the
      // lonely model re-arms with the opposite sign there).
      starts[t] = t % 100 != 0 ? kContinue : (t == 200 ? kRestartAfterLoadIncrease : kRestart);
    }
    const std::vector<double> y = op.simulate(u, starts);
    const std::vector<InverseStep> inv = op.invert(y, starts);
    std::vector<double> u_hat;
    for (std::size_t t = 0; t < inv.size(); ++t) {
      ASSERT_TRUE(inv[t].reached) << op.family() << " t " << t;
      ASSERT_NEAR(inv[t].output, y[t], 1e-9) << op.family() << " t " << t;
      u_hat.push_back(inv[t].input);
    }
    // Fed back through the forward model, the inputs reproduce the targets.
    const std::vector<double> y_hat = op.simulate(u_hat, starts);
    for (std::size_t t = 0; t < y.size(); ++t) ASSERT_NEAR(y_hat[t], y[t], 1e-9) << op.family();
  }
}

TEST(Operator, PolynomialFitIsExactOnPolynomials) {
  std::vector<double> x, y;
  for (int i = 0; i <= 20; ++i) {
    x.push_back(100.0 + i);  // far from 0: the centring must be undone correctly
    y.push_back(2.0 - 0.5 * x.back() + 0.01 * x.back() * x.back());
  }
  const PolynomialModel p = fit_polynomial(x, y, 2);
  EXPECT_NEAR(p.coefficients[0], 2.0, 1e-6);
  EXPECT_NEAR(p.coefficients[1], -0.5, 1e-8);
  EXPECT_NEAR(p.coefficients[2], 0.01, 1e-10);
  EXPECT_THROW_MSG(fit_polynomial(std::vector<double>(5, 1.0), std::vector<double>(5, 2.0), 1),
                   IdentificationError, "never changes");
}

}  // namespace
}  // namespace scpkit
