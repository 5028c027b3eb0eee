#pragma once
// Generalized Prandtl-Ishlinskii (GPI) model (paper 000 Eqs. 4-7).
//
// Generalized play operator of radius r with strictly increasing envelopes gamma_R, gamma_L
// (Eq. 5, written in its rate-independent closed form):
//
//   w(t) = min( gamma_L(v(t)) + r, max( gamma_R(v(t)) - r, w(t-) ) )
//
// (rising input: max(gamma_R(v) - r, w); falling: min(gamma_L(v) + r, w)). Order
// preservation needs gamma_R(v) - r <= gamma_L(v) + r on the input range, i.e.
// gamma_R <= gamma_L there for r_0 = 0.
//
//   H_GPI[v](t) = sum_j p_j w_j(t) + c                                          (Eq. 7)
//
// Envelopes are linear, gamma(v) = a v + b with a > 0 (paper 000 Eqs. 16-17); the family is
// a small value type so another strictly increasing family can replace it.
// Initial state: each operator on the major loop's lower turning point at v_min,
// w_j = gamma_L(v_min) + r_j (the state a falling input leaves); see docs/theory.md.
#include <span>
#include <vector>

namespace scpkit {

/// gamma(v) = a v + b, a > 0.
struct LinearEnvelope {
  double a = 1.0;
  double b = 0.0;
  double operator()(double v) const { return a * v + b; }
  double inverse(double g) const { return (g - b) / a; }
};

struct GpiModel {
  LinearEnvelope right;         ///< gamma_R, the rising envelope
  LinearEnvelope left;          ///< gamma_L, the falling envelope
  std::vector<double> radii;    ///< r_j >= 0, ascending
  std::vector<double> weights;  ///< p(r_j)
  double bias = 0.0;            ///< c
  double v_min = 0.0;           ///< the input range the model was identified on
  double v_max = 1.0;

  /// Throws InvalidArgument unless radii are >= 0 and ascending, sizes match, envelopes are
  /// strictly increasing, gamma_R <= gamma_L on [v_min, v_max] (order preservation) and the
  /// weights keep one sign (every partial sum too: the model is invertible).
  void validate() const;
  /// +1 when the output rises with the input, -1 when it falls (sign of the weights).
  int direction() const;
};

/// Memory of a GPI model: each operator's output and the last input.
struct GpiState {
  std::vector<double> w;
  double v = 0.0;
  /// Every operator at the lower turning point of the major loop at v0.
  static GpiState at_lower_turning_point(const GpiModel& m, double v0);
};

/// Applies v (clamped to [v_min, v_max]) and returns H[v].
double gpi_step(const GpiModel& m, GpiState& s, double v);
/// H for the current memory.
double gpi_output(const GpiModel& m, const GpiState& s);
/// Runs a sequence from `s` (updated).
std::vector<double> gpi_simulate(const GpiModel& m, GpiState& s, std::span<const double> v);

}  // namespace scpkit
