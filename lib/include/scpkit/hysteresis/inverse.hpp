#pragma once
// Exact inverse of a rate-independent operator along monotone input paths (departure from
// paper 001 Algorithm 1 and paper 000's numerical Preisach inversion; see docs/theory.md).
//
// From the current memory, moving the input monotonically up (or down) changes the output
// continuously and monotonically. For the discretised Preisach operator the output along such
// a path is piecewise quadratic in the input, with pieces delimited by grid nodes and by the
// earlier extrema that the move wipes out:
//
//   rising from the memory's last minimum m:   y(u) = const + 2 E(u, m)
//   falling from the memory's last maximum M:  y(u) = const - 2 E(M, u)
//
// so the input that reaches a target is found exactly: locate the piece by bisection over the
// breakpoints, then solve its quadratic. Targets beyond what the input range [u_min, u_max]
// can reach saturate at the limit and are flagged. The inverter's memory is the plant's:
// step() applies the chosen input to the state it is given.
#include <utility>
#include <vector>

#include "scpkit/hysteresis/gpi.hpp"
#include "scpkit/hysteresis/lonely.hpp"
#include "scpkit/hysteresis/preisach.hpp"

namespace scpkit {

/// One compensation step.
struct InverseStep {
  double input = 0.0;   ///< the input to apply
  double output = 0.0;  ///< the model's output after applying it
  bool reached = true;  ///< false when the target lies beyond what [u_min, u_max] can reach
};

class PreisachInverter {
 public:
  /// u_min, u_max: the admissible inputs (default: the model's grid).
  explicit PreisachInverter(const PreisachModel& model);
  PreisachInverter(const PreisachModel& model, double u_min, double u_max);

  /// The input that brings the output of `state` to `target` by one monotone move; applies it
  /// to `state`. Holds the input when the target equals the current output. Allocation-free
  /// once the breakpoint buffer has grown to the memory depth plus L.
  InverseStep step(PreisachState& state, double target);

  /// Output after moving the input of `state` to u (state unchanged).
  double output_at(const PreisachState& state, double u);

 private:
  double solve_on_path(const PreisachState& state, double u0, double u1, double target);
  const PreisachModel* model_;
  double u_min_, u_max_;
  PreisachState scratch_;
  std::vector<double> breaks_;
};

/// Exact inverse of the lonely-stroke model: the Preisach path plus sigma * g(max(M, u)),
/// still piecewise quadratic, with the running maximum M as one more breakpoint.
class LonelyInverter {
 public:
  LonelyInverter(const LonelyModel& model, double u_min, double u_max);
  InverseStep step(LonelyState& state, double target);

 private:
  double output_at(const LonelyState& state, double u);
  const LonelyModel* model_;
  double u_min_, u_max_;
  LonelyState scratch_;
  std::vector<double> breaks_;
};

/// Exact GPI inverse (paper 000 Eqs. 10-11, generalised): along a rising input the operators
/// follow w_j = max(g - r_j, w_j(t-)) in g = gamma_R(v), so H is piecewise linear in g with
/// breakpoints g_j = w_j(t-) + r_j; along a falling input w_j = min(g + r_j, w_j(t-)) in
/// g = gamma_L(v). The target fixes g on the right piece, then v = gamma^-1(g). Works from any
/// memory and for either weight sign (the paper's printed formulas give negative radii for
/// negative weights); the branch is chosen by where the target lies, not by the sign of the
/// target's change alone.
class GpiInverter {
 public:
  explicit GpiInverter(const GpiModel& model);
  InverseStep step(GpiState& state, double target);

 private:
  // Output at the end of the rising (up) or falling path, and the g solving the target on
  // it (NaN when the target lies beyond the end).
  std::pair<double, double> walk(const GpiState& state, bool up, double target);
  const GpiModel* model_;
  std::vector<std::pair<double, double>> breaks_;  // (g_j, p_j)
};

/// Paper 000 Eq. 11 as printed: the inverse of a classical PI operator
/// Pi[x] = p_0 x + sum_{k>=1} p_k F_{r_k}[x] (F_r the play operator, zero initial state) is
/// Pi^-1[y] = p^_0 y + sum_k p^_k F_{r^_k}[y], with
///   r^_j = p_0 r_j + sum_{k<j} p_k (r_j - r_k),   p^_0 = 1 / p_0,
///   p^_k = -p_k / ((p_0 + sum_{j<=k} p_j)(p_0 + sum_{j<k} p_j)).
/// Kept as a labelled comparison: with the paper's all-negative weights it gives negative radii
/// (no play operator has one), which is why scpkit inverts Pi+ = -Pi on -y instead, or, more
/// generally, solves along the input path from the tracked memory (GpiInverter).
struct PaperPiInverse {
  std::vector<double> radii;    ///< r^_k, k >= 1 (index 0 unused, 0)
  std::vector<double> weights;  ///< p^_0, p^_k
};
PaperPiInverse paper_pi_inverse(const std::vector<double>& radii,
                                const std::vector<double>& weights);

/// Paper 001 Algorithm 1, corrected (a labelled comparison for the exact inverters): from the
/// current memory, step the input by d0 in the direction that moves the output toward the
/// target, halve the step whenever it would overshoot, stop within `tolerance` or when the
/// step falls below 1e-12 of the range; inputs stay within [u_min, u_max] and a target beyond
/// the limit is flagged. The printed algorithm compares u with itself, fits two unknowns from
/// one equation, steps by d instead of d0, ignores the decreasing direction and never clamps.
struct IterativeInverseResult {
  InverseStep step;
  int iterations = 0;
};
IterativeInverseResult iterative_inverse_step(const PreisachModel& model, PreisachState& state,
                                              double target, double u_min, double u_max, double d0,
                                              double tolerance, int max_iterations = 200);

}  // namespace scpkit
