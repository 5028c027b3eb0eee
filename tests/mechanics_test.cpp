// Helical-spring stiffness, paper 002 Table 1, and the corrected ply mapping.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "scpkit/error.hpp"
#include "scpkit/mechanics/coil.hpp"
#include "scpkit/mechanics/material.hpp"
#include "scpkit/mechanics/ply_mapping.hpp"
#include "test_support.hpp"

namespace scpkit {
namespace {

CoilGeometry coil(double d_mm, double D_mm, double n, int legs = 1) {
  CoilGeometry c;
  c.wire_d_m = d_mm * 1e-3;
  c.mean_D_m = D_mm * 1e-3;
  c.coils = n;
  c.legs = legs;
  return c;
}

TEST(Coil, StiffnessIsTheHelicalSpringFormula) {
  // K = G d^4 / (8 n D^3), recomputed by hand: G = 1 GPa, d = 1 mm, D = 5 mm, n = 10.
  EXPECT_NEAR(spring_stiffness(1e9, coil(1.0, 5.0, 10)), 1e9 * 1e-12 / (8 * 10 * 125e-9), 1e-9);
  // Two legs sharing the 10 coils: two springs of 5 coils in parallel, 4 times as stiff.
  EXPECT_NEAR(spring_stiffness(1e9, coil(1.0, 5.0, 10, 2)),
              4 * spring_stiffness(1e9, coil(1.0, 5.0, 10)), 1e-9);
}

TEST(Coil, ReproducesPaper002Table1WithTheMeanDiameter) {
  // Table 1 prints K/K_2ply = 1, 1.06, 1.97 (truncated to two decimals: 1.0699, 1.9729).
  const CoilGeometry c2 = coil(0.25, 0.35, 440), c4 = coil(0.31, 0.53, 280),
                     c6 = coil(0.41, 0.68, 220);
  const CoilTolerances tol;
  const double r4 = stiffness_ratio(c4, c2, tol).value, r6 = stiffness_ratio(c6, c2, tol).value;
  EXPECT_DOUBLE_EQ(stiffness_ratio(c2, c2, tol).value, 1.0);
  EXPECT_EQ(std::floor(r4 * 100) / 100, 1.06);
  EXPECT_EQ(std::floor(r6 * 100) / 100, 1.97);
  EXPECT_NEAR(r4, std::pow(0.31 / 0.25, 4) * 440 / 280 * std::pow(0.35 / 0.53, 3), 1e-12);
  // Read as the outer diameter, the 2-ply coil's mean diameter would be 0.10 mm < d.
  EXPECT_THROW_MSG(coil(0.25, 0.35 - 0.25, 440).validate(), InvalidArgument, "spring index");
}

TEST(Coil, ToleranceUncertaintyMatchesPhysicsNotes) {
  // sigma_d 0.01 mm, sigma_D 0.02 mm, sigma_n 5 %: each K uncertain by 14-24 % (PHYSICS.md).
  const CoilTolerances tol;
  const Uncertain k2 = spring_stiffness(Uncertain{1e9, 0.0}, coil(0.25, 0.35, 440), tol);
  const Uncertain k6 = spring_stiffness(Uncertain{1e9, 0.0}, coil(0.41, 0.68, 220), tol);
  EXPECT_NEAR(k2.relative(), 0.24, 0.005);
  EXPECT_NEAR(k6.relative(), 0.14, 0.005);
  // Monte Carlo check of the first-order propagation on the 6-ply coil.
  std::mt19937 rng(41);
  std::normal_distribution<double> N(0.0, 1.0);
  double sum = 0, sum2 = 0;
  const int M = 200000;
  for (int i = 0; i < M; ++i) {
    CoilGeometry c = coil(0.41 + 0.01 * N(rng), 0.68 + 0.02 * N(rng), 220 * (1 + 0.05 * N(rng)));
    const double k = spring_stiffness(1e9, c);
    sum += k;
    sum2 += k * k;
  }
  const double mean = sum / M, sd = std::sqrt(sum2 / M - mean * mean);
  EXPECT_NEAR(sd / mean, k6.relative(), 0.02);
}

TEST(PlyMapping, ThreadMappingIsInputScalingByPliesRatio) {
  std::mt19937 rng(42);
  const PreisachModel thread2 = testing::random_model(rng, PreisachGrid{0.2, 2.45, 10});
  const PreisachModel thread6 = map_thread_plies(thread2, 2, 6);
  PreisachState a = PreisachState::negative_saturation(thread2.grid());
  PreisachState b = PreisachState::negative_saturation(thread6.grid());
  std::uniform_real_distribution<double> U(0.6, 7.35);  // 60-750 g for 6 plies, in N
  for (int t = 0; t < 300; ++t) {
    const double F = U(rng);
    ASSERT_NEAR(thread6.step(b, F), thread2.step(a, F / 3.0), 1e-12);  // each ply sees F/6
  }
  // The printed right-hand side, (p/q) Gamma_p[F], is a different operator: a bias-carrying
  // Gamma is not scale invariant.
  const PreisachModel printed = paper_eq7_as_printed(thread2, 2, 6);
  PreisachState c = PreisachState::negative_saturation(printed.grid());
  PreisachState d = PreisachState::negative_saturation(thread6.grid());
  double gap = 0.0;
  for (double F : {0.6, 3.0, 7.0, 1.0})
    gap = std::max(gap, std::abs(printed.step(c, F) - thread6.step(d, F)));
  EXPECT_GT(gap, 1e-3);
}

TEST(PlyMapping, GainPredictionUsesTheStiffnessRatioTheRightWayUp) {
  const CoilGeometry c2 = coil(0.25, 0.35, 440), c4 = coil(0.31, 0.53, 280);
  const Uncertain g4 = predict_scp_gain(6.9447, 2, c2, 4, c4, CoilTolerances{});
  const double k2 = spring_stiffness(1.0, c2), k4 = spring_stiffness(1.0, c4);
  EXPECT_NEAR(g4.value, 6.9447 * 2.0 * k2 / k4, 1e-9);
  EXPECT_NEAR(paper_eq8_as_printed_gain(6.9447, 2, c2, 4, c4), 6.9447 * 2.0 * k4 / k2, 1e-9);
  // With the paper's own numbers the corrected prediction misses the measured 4-ply gain
  // (7.01) by +68..+87 % (PHYSICS.md section 2): the model's known gap, pinned here.
  const double miss = g4.value / 7.01 - 1.0;
  EXPECT_GT(miss, 0.68);
  EXPECT_LT(miss, 0.87);
  EXPECT_GT(g4.sigma / g4.value, 0.25);  // both coils' tolerances combined
}

TEST(PlyMapping, GainFitRecoversALineAndRejectsDegenerateData) {
  std::vector<double> x, y;
  for (int i = 0; i < 50; ++i) {
    x.push_back(0.001 * i);
    y.push_back(7.5 * 0.001 * i + 0.002);
  }
  const GainFit g = fit_scp_gain(x, y);
  EXPECT_NEAR(g.gain, 7.5, 1e-9);
  EXPECT_NEAR(g.offset, 0.002, 1e-12);
  EXPECT_NEAR(g.r2, 1.0, 1e-12);
  EXPECT_THROW_MSG(fit_scp_gain(std::vector<double>(5, 0.01), std::vector<double>(5, 0.1)),
                   IdentificationError, "never changes");
  EXPECT_THROW_MSG(fit_scp_gain(std::vector<double>{0.0, 1.0}, std::vector<double>{0.0, 1.0}),
                   IdentificationError, "too few");
}

TEST(Material, ShippedCardLoadsAndMatchesTable1) {
  const Material m = find_material("nylon-110-34-dtex");
  ASSERT_EQ(m.geometries.size(), 3u);
  EXPECT_NEAR(m.geometry_for(4)->coil.mean_D_m, 0.53e-3, 1e-12);
  EXPECT_GT(m.shear_modulus_Pa.sigma, 0.0);
  EXPECT_FALSE(m.shear_modulus_source.empty());
}

}  // namespace
}  // namespace scpkit
