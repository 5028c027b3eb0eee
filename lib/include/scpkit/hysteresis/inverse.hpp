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
#include <vector>

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

}  // namespace scpkit
