#pragma once
// Helical-spring model of a coiled actuator (paper 002 Eq. 4, Wahl, "Mechanical Springs",
// ch. 10):
//
//   K_leg = G d^4 / (8 n_leg D^3),  n_leg = n / legs;  legs in parallel: K = legs * K_leg
//
// n is the coil count of the whole actuator (all legs), as paper 002 Table 1 gives one n per
// actuator: read per leg, its 2-ply actuator (n = 440 over about 100 mm) would have a pitch of
// 0.23 mm, below its 0.25 mm wire, which no helix has. Stiffness ratios between actuators with
// the same number of legs are unaffected by this reading.
//
// d wire (thread) diameter, D the *mean* coil diameter, n active coils, G shear modulus.
// Departure from paper 002: the paper calls D the outer diameter. Its Table 1 ratios
// (1, 1.06, 1.97) come out only with D read as the mean diameter, and read as the outer
// diameter the 2-ply spring index D_mean/d would be 0.4 < 1, which no helix has
// (docs/theory.md, tests/mechanics_test.cpp).
#include <cmath>
#include <string>

namespace scpkit {

/// A value with a one-sigma uncertainty.
struct Uncertain {
  double value = 0.0;
  double sigma = 0.0;
  double relative() const { return value != 0.0 ? sigma / std::abs(value) : 0.0; }
};

struct CoilGeometry {
  double wire_d_m = 0.0;  ///< d, thread diameter
  double mean_D_m = 0.0;  ///< D, mean coil diameter (outer diameter minus d)
  double coils = 0.0;     ///< n, active coils of the whole actuator (all legs)
  int legs = 1;           ///< 1, or 2 for a double-backed actuator
  double length_m = 0.0;  ///< resting length (0 = unknown)

  /// C = D / d.
  double spring_index() const { return mean_D_m / wire_d_m; }
  /// Throws InvalidArgument unless d, D, n > 0, legs in {1, 2} and C >= 1.
  void validate() const;
  /// Why the geometry is doubtful (C < 3: the helical-spring formula loses accuracy), or "".
  std::string caution() const;
};

/// One-sigma manufacturing tolerances of a coil.
struct CoilTolerances {
  double wire_d_m = 0.01e-3;  ///< paper-scale sigma_d = 0.01 mm
  double mean_D_m = 0.02e-3;  ///< sigma_D = 0.02 mm
  double coils_rel = 0.05;    ///< sigma_n / n = 5 %
};

/// K = legs^2 G d^4 / (8 n D^3) (legs in parallel, n / legs coils each), N/m.
double spring_stiffness(double shear_modulus_Pa, const CoilGeometry& g);

/// Stiffness with first-order propagated uncertainty from the tolerances and sigma_G:
/// (sigma_K/K)^2 = (sigma_G/G)^2 + (4 sigma_d/d)^2 + (3 sigma_D/D)^2 + (sigma_n/n)^2.
Uncertain spring_stiffness(const Uncertain& shear_modulus_Pa, const CoilGeometry& g,
                           const CoilTolerances& tol);

/// K_a / K_b for two coils of the same material (G cancels), with propagated uncertainty.
Uncertain stiffness_ratio(const CoilGeometry& a, const CoilGeometry& b, const CoilTolerances& tol);

}  // namespace scpkit
