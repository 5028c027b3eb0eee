#pragma once
// Private to diagnose: model-free signatures, tests of properties that every rate-independent
// Preisach operator has whatever its density, read directly off the measurements. They need no
// fitted model, so the baseline's own approximation error cannot raise them.
//
// - Return-point memory: two readings whose inputs left the operator in the same memory state
//   (same dominant turning points, same input) must read the same. Their difference, regressed
//   on the growth of the running input maximum between them and on the time between them,
//   separates a lonely stroke (the first stroke differs from later ones) from a drift.
// - Congruency: two monotone branches that start from the same turning value go through the
//   same output increments, whatever came before. A difference that grows along the branch
//   is non-congruence (after differences in the running maximum are excluded).
// - Holds: readings taken while the input is held still must not move; motion in the direction
//   of the last input step is creep (a drift moves them regardless of that direction).
// - Lag (given a feature from a fitted model): readings of one memory state reached along
//   different paths differ by the lag each path leaves, which no rate-independent model makes.
#include <string>
#include <vector>

#include "baseline.hpp"

namespace scpkit::diagnosis {

/// A regression coefficient tested against zero.
struct Signature {
  bool available = false;  ///< the data hold what the test needs
  int units = 0;           ///< independent comparisons it rests on (pairs, branches, holds)
  double estimate = 0.0;   ///< effect size in output units (per unit of the feature)
  double z = 0.0;          ///< estimate / standard error
  double p_value = 1.0;    ///< two-sided unless stated
  std::string what;        ///< one phrase: what was compared
};

struct ReturnPointSignatures {
  Signature running_max;  ///< d ~ (growth of the running maximum): lonely stroke
  Signature time;         ///< d ~ (time between the readings): drift
};

/// The operator's memory state after each reading: its dominant turning points (the current
/// input last), rounded to 1e-7 of the input range, or {0} back at the lowest input (every
/// hysteron off, whatever came before); the operator restarts with each segment. Readings
/// with equal keys are in the same memory state.
std::vector<std::vector<long>> memory_states(const Record& rec);
/// The same for input `u` read in segments `seg` (a file's columns before a Record is made:
/// protocol_limits_of).
std::vector<std::vector<long>> memory_states(const std::vector<double>& u,
                                             const std::vector<int>& seg);

/// Whether each reading's value is fixed by what its fold trained on: a rate-independent
/// operator's output is a sum of Everett values, one per pair of consecutive dominant turning
/// points (the current input last), and the training readings on a branch observe the pair of
/// its starting turning point and their input. A held-out reading is identified when every
/// pair of its memory was observed in its fold's training, both inputs within half a cell of
/// an observed pair's (a pair whose inputs are that close contributes nothing). The cell is
/// the range over `levels`, or over the record's input steps (input_steps) where those are
/// finer: inputs read along ramps (not on a grid) otherwise count pairs up to half a coarse
/// cell apart as observed, and an Everett value moves by several % of the range over half a
/// cell. On inputs on a grid of the record's steps, equal inputs match and others do not. The first
/// rise's pair from the lowest input counts only below the segment's top (above it, every later
/// reading shares it). Readings that are not held out are 0.
std::vector<char> identified_readings(const Record& rec, int levels);
/// The input range over the median step between consecutive readings' inputs (where the input
/// moves, within a segment), rounded: the number of input steps the record resolves.
double input_steps(const Record& rec);

/// `sigma`: the noise of one reading (the diagnosis' floor); `noise_rho`: its lag-one
/// correlation as the record shows it, used where the pairs cannot show it (0: unknown).
ReturnPointSignatures return_point_signatures(const Record& rec, double sigma,
                                              double noise_rho = 0.0);
/// Creep read where a rate-independent model cannot take it up: readings in one memory state
/// must read the same, while a lag leaves each reading short of its value by what the recent
/// path moved. `lag` per row: a Kelvin element's departure from a rate-independent prediction
/// (v - p, v relaxing towards p). The differences of the return-point pairs across which the
/// running maximum did not grow, regressed on its difference beside the time columns;
/// one-sided (a lag, not a lead).
Signature lag_signature(const Record& rec, const std::vector<double>& lag, double sigma);
/// Minor loops between the same extrema after different histories: does the difference of two
/// branches change along them? `raw` is the calibrated test; `robust` reads that change through
/// a running median of three, so that one reading off its neighbours (a spike) does not count.
/// It is conservative (on congruent loops 1.6 % of p-values below 0.05), a check beside `raw`.
struct CongruencySignatures {
  Signature raw, robust;
};
CongruencySignatures congruency_signatures(const Record& rec);
/// One-sided: motion during holds in the direction of the last input step.
Signature hold_signature(const Record& rec, double sigma);

/// The response's direction: +1 where it rises with the input (the sign of sum(du dy) over the
/// input steps within segments), else -1.
double response_direction(const Record& rec);

}  // namespace scpkit::diagnosis
