#pragma once
// The augmented model for voltage (or power, temperature) tests under several constant
// loads (paper 000 Eq. 3):
//
//   y = f2(F) * H[v] + f1(F),   H[v_min] = 0,  H[v_max] = -1 on the first rise,
//
// f1 (offset) and f2 (range) quadratic in the load F (paper 000 Eqs. 14-15), H one
// normalised hysteresis operator shared by every load (GPI, Preisach, linear or poly2). Each
// constant-load segment starts H from its initial state. H is a function of v alone, so its
// inverse needs only the normalised targets h_d = (y_d - f1(F)) / f2(F): a load change between
// steps changes h_d, not the inverse's memory (paper 000's "hold v when y_d is unchanged" is
// wrong when F changes; see docs/theory.md).
#include <span>
#include <vector>

#include "scpkit/hysteresis/operator.hpp"

namespace scpkit {

/// c0 + c1 F + c2 F^2.
struct Quadratic {
  double c0 = 0.0, c1 = 0.0, c2 = 0.0;
  double operator()(double F) const { return c0 + F * (c1 + F * c2); }
  /// True when the quadratic has a root inside [lo, hi] (or touches zero there).
  bool crosses_zero(double lo, double hi) const;
};

struct AugmentedModel {
  Quadratic f1;  ///< offset: the response at v_min, vs load (N)
  Quadratic f2;  ///< range: y(v_min) - y(v_max) on the first rise, vs load (N); never zero
  HysteresisOperator h{PolynomialModel{{0.0, 0.0}, 0.0, 1.0}};
  double load_min = 0.0;  ///< identified load range, N
  double load_max = 0.0;

  /// Throws InvalidArgument when f2 crosses zero on the identified load range.
  void validate() const;
  bool outside_load_range(double load) const;
  /// Response for loads and inputs; H restarts where `starts` is set (and at the start).
  std::vector<double> simulate(std::span<const double> load, std::span<const double> input,
                               std::span<const char> starts) const;
  /// Inputs that track target responses at the given loads; outputs and reachability.
  std::vector<InverseStep> invert(std::span<const double> load, std::span<const double> target,
                                  std::span<const char> starts) const;
};

}  // namespace scpkit
