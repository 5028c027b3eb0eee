// The generalized play operator and GPI model (paper 000 Eqs. 4-7) and their exact inverse.
#include "scpkit/hysteresis/gpi.hpp"

#include <gtest/gtest.h>

#include <random>

#include "scpkit/error.hpp"
#include "scpkit/hysteresis/inverse.hpp"
#include "test_support.hpp"

namespace scpkit {
namespace {

GpiModel paper_model(std::mt19937& rng, double sign) { return testing::paper_gpi(rng, sign); }

TEST(Gpi, StepIsThePaperCaseFormulaOfEq5) {
  std::mt19937 rng(71);
  const GpiModel m = paper_model(rng, -1.0);
  GpiState s = GpiState::at_lower_turning_point(m, 0.0);
  std::vector<double> w = s.w;  // reference: Eq. 5 case by case
  double v_prev = 0.0;
  std::uniform_real_distribution<double> U(0.0, 5.1);
  for (int t = 0; t < 2000; ++t) {
    const double v = U(rng);
    double y = m.bias;
    for (std::size_t j = 0; j < w.size(); ++j) {
      if (v > v_prev) w[j] = std::max(m.right(v) - m.radii[j], w[j]);
      if (v < v_prev) w[j] = std::min(m.left(v) + m.radii[j], w[j]);
      y += m.weights[j] * w[j];
    }
    ASSERT_NEAR(gpi_step(m, s, v), y, 1e-12);
    v_prev = v;
  }
}

TEST(Gpi, IsRateIndependentAndStaysInsideTheBand) {
  std::mt19937 rng(72);
  const GpiModel m = paper_model(rng, 1.0);
  GpiState coarse = GpiState::at_lower_turning_point(m, 0.0), fine = coarse;
  std::uniform_real_distribution<double> U(0.0, 5.1);
  double prev = 0.0;
  for (int t = 0; t < 300; ++t) {
    const double v = U(rng);
    double y_fine = 0.0;
    for (int k = 1; k <= 7; ++k) y_fine = gpi_step(m, fine, prev + (v - prev) * k / 7);
    ASSERT_NEAR(gpi_step(m, coarse, v), y_fine, 1e-12);
    for (std::size_t j = 0; j < m.radii.size(); ++j) {
      ASSERT_GE(coarse.w[j], m.right(v) - m.radii[j] - 1e-12);
      ASSERT_LE(coarse.w[j], m.left(v) + m.radii[j] + 1e-12);
    }
    prev = v;
  }
}

TEST(GpiInverse, PaperParametersWithNegativeWeightsRoundTrip) {
  std::mt19937 rng(73);
  for (double sign : {-1.0, 1.0}) {
    for (int trial = 0; trial < 20; ++trial) {
      const GpiModel m = paper_model(rng, sign);
      GpiState plant = GpiState::at_lower_turning_point(m, 0.0), memory = plant;
      GpiInverter inverter(m);
      std::uniform_real_distribution<double> U(0.0, 5.1);
      for (int t = 0; t < 300; ++t) {
        const double v = U(rng);
        const double target = gpi_step(m, plant, v);
        const InverseStep s = inverter.step(memory, target);
        ASSERT_TRUE(s.reached);
        ASSERT_NEAR(s.output, target, 1e-10) << "sign " << sign << " trial " << trial << " t " << t;
        // (The input itself need not come back: with gamma_R != gamma_L even the r = 0
        // operator has a dead band after each reversal, where the output does not move.)
      }
    }
  }
}

TEST(GpiInverse, SaturatesAndFlagsUnreachableTargets) {
  std::mt19937 rng(74);
  const GpiModel m = paper_model(rng, -1.0);
  GpiState s = GpiState::at_lower_turning_point(m, 1.0);
  GpiInverter inverter(m);
  const InverseStep low = inverter.step(s, -100.0);  // below the output at v_max
  EXPECT_FALSE(low.reached);
  EXPECT_DOUBLE_EQ(low.input, 5.1);  // negative weights: the lowest output is at the top input
  const InverseStep high = inverter.step(s, 100.0);
  EXPECT_FALSE(high.reached);
  EXPECT_DOUBLE_EQ(high.input, 0.0);
}

TEST(Gpi, ValidationNamesTheBrokenCondition) {
  std::mt19937 rng(75);
  GpiModel m = paper_model(rng, 1.0);
  m.weights[3] = -0.1;
  EXPECT_THROW_MSG(m.validate(), InvalidArgument, "one sign");
  m = paper_model(rng, 1.0);
  m.right = {1.5, 1.0};  // gamma_R above gamma_L
  EXPECT_THROW_MSG(m.validate(), InvalidArgument, "order preservation");
  m = paper_model(rng, 1.0);
  m.left.a = 0.0;
  EXPECT_THROW_MSG(m.validate(), InvalidArgument, "strictly increasing");
}

}  // namespace
}  // namespace scpkit

#include "scpkit/identification/gpi_fit.hpp"

namespace scpkit {
namespace {

std::vector<double> damped_voltage(std::mt19937& rng, int cycles, int per_half, double vmax) {
  std::vector<double> v{0.0};
  std::uniform_real_distribution<double> U(0.0, 1.0);
  for (int c = 0; c < cycles; ++c) {
    const double amp = 1.0 - 0.8 * c / cycles;
    for (double target :
         {vmax * (0.5 + 0.5 * amp * (0.7 + 0.3 * U(rng))), vmax * 0.5 * (1.0 - amp) * U(rng)}) {
      const double from = v.back();
      for (int k = 1; k <= per_half; ++k) v.push_back(from + (target - from) * k / per_half);
    }
  }
  return v;
}

TEST(GpiFit, RecoversAKnownGpiAndPredictsUnseenInputs) {
  std::mt19937 rng(76);
  GpiModel truth = paper_model(rng, -1.0);
  // The fit's radii: 11 operators up to a quarter of the input range; give the truth the same.
  for (int j = 0; j <= 10; ++j) truth.radii[j] = 0.25 * 5.1 * j / 10.0;
  truth.validate();
  const auto v = damped_voltage(rng, 12, 8, 5.1);
  GpiState s = GpiState::at_lower_turning_point(truth, v.front());
  const auto y = gpi_simulate(truth, s, v);
  const GpiFit fit = fit_gpi(v, y, {}, GpiFitOptions{});
  EXPECT_LT(fit.summary.train.rms_pct_range, 0.05) << fit.summary.BriefReport();
  EXPECT_LE(fit.model.weights.front(), 0.0);
  // Unseen inputs inside the identified range (the model clamps outside it).
  const auto v2 = damped_voltage(rng, 6, 5, *std::max_element(v.begin(), v.end()));
  GpiState a = GpiState::at_lower_turning_point(truth, 0.0),
           b = GpiState::at_lower_turning_point(fit.model, 0.0);
  const auto y_true = gpi_simulate(truth, a, v2), y_fit = gpi_simulate(fit.model, b, v2);
  EXPECT_LT(error_metrics(y_true, y_fit).rms_pct_range, 0.5);
}

}  // namespace
}  // namespace scpkit
