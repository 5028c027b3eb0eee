#pragma once
// The lonely-stroke Preisach model (paper 001), in its equivalent form (PHYSICS.md section 4).
//
// Paper 001 extends the Preisach plane below the feasible minimum input i_min (m expanded
// columns, beta in [i_ext, i_min)). Those hysterons switch on when u > alpha and can never
// switch off (u >= i_min > beta), so their contribution depends only on the running maximum
// M(t) of the input, and all expanded columns with the same alpha act as one:
//
//   y = Gamma[u] + sigma * g(M),   g(M) = sum_j W_j (2 clamp((M - x_j) / h, 0, 1) - 1),
//
// with Gamma the conventional Preisach operator (its bias included) on the grid x_j = lo + j h.
// The expanded hysterons are re-armed (switched off, M reset to the current input) at every
// load change. sigma = +1 after a load decrease, the paper's case (densities <= 0 on the
// expanded cells for a falling response), and sigma = -1 after a load increase, the case the
// paper leaves open: the repeatable loop then lies below the first one, so the expanded cells
// take the opposite sign.
#include <vector>

#include "scpkit/hysteresis/preisach.hpp"

namespace scpkit {

/// Restart flags of a record (HysteresisOperator::simulate / invert and the fits).
enum RestartFlag : char {
  kContinue = 0,                  ///< the memory carries on
  kRestart = 1,                   ///< a new segment (start, or after a load decrease)
  kRestartAfterLoadIncrease = 2,  ///< a new segment after a load increase (lonely: sigma = -1)
};

struct LonelyModel {
  PreisachModel preisach;
  std::vector<double> column_weights;  ///< W_j, one per level of the Preisach grid

  /// g(M) as above. Throws InvalidArgument on a size mismatch at construction (validate()).
  double running_max_term(double M) const;
  void validate() const;
};

struct LonelyState {
  PreisachState preisach;
  double running_max = 0.0;
  double sigma = 1.0;
  /// Negative saturation; expanded hysterons armed; sigma from the restart flag.
  static LonelyState initial(const LonelyModel& m, char flag = kRestart);
};

double lonely_output(const LonelyModel& m, const LonelyState& s);
double lonely_step(const LonelyModel& m, LonelyState& s, double u);

}  // namespace scpkit
