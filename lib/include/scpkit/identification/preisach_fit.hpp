#pragma once
// Identification of a discretised Preisach operator from input/output samples
// (paper 002 "identified efficiently as a linear least-squares optimization problem";
// paper 000 Section 3 with MATLAB lsqnonneg).
//
//   minimise  1/N sum_t (c + sum_k w_k s_k(t) - y_t)^2
//             + lambda / N_pairs * sum_{neighbour cells a,b} (L^2 (q_a - q_b))^2
//   subject to  sign * w_k >= 0,  c free,
//
// with q = w / relative cell area (mass per full square) and s_k(t) the signed area fraction
// of cell k. lambda = 0 is the papers' recipe. L and lambda are chosen by cross-validation
// over blocks of the record (whole cycles or given segments, never random rows): each block is
// predicted with the memory built from the *input* history, by a model fitted on the others.
// The model is the mean of fits on S grids shifted by h/S, which removes the dependence of
// the answer on where the grid lines fall relative to the input's turning points.
// Departures from the papers: the smoothness term, the shifted-grid average and the
// cross-validated choice of L and lambda, see docs/theory.md.
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "scpkit/hysteresis/preisach.hpp"
#include "scpkit/identification/nnls.hpp"
#include "scpkit/metrics.hpp"

namespace scpkit {

struct PreisachFitOptions {
  int levels = 0;  ///< L; 0 = choose by cross-validation among candidate_levels
  std::vector<int> candidate_levels = {8, 12, 16, 20, 25, 30};
  double smoothness = -1.0;  ///< lambda; < 0 = choose by cross-validation
  std::vector<double> candidate_smoothness = {0.0, 1e-6, 1e-5, 1e-4, 1e-3};
  /// S: the model is the mean of S fits on grids shifted by h/S (averaged shifted grids,
  /// the ASH idea of Scott 1985), one operator on the h/S grid. 1 = the papers' single grid.
  int grid_shifts = 4;
  int sign = 0;              ///< +1: densities >= 0; -1: <= 0 (falling response); 0: from data
  std::optional<double> lo;  ///< lowest threshold; default: smallest input
  std::optional<double> hi;  ///< highest threshold; default: largest input
  int folds = 5;             ///< blocks for cross-validation when no block ids are given
  /// Restart the memory (negative saturation) at the start of every given block: segments
  /// that are separate tests, e.g. the constant-load segments of an augmented model.
  bool restart_at_blocks = false;
  /// Start the memory (and every restart) after one excursion lo -> hi -> lo
  /// (PreisachState::after_cycle): the shifted grids' hysterons below the smallest input then
  /// give no first-stroke term, so the model is the conventional plane over the tested inputs.
  /// diagnose's baseline, whose lonely-stroke extension adds that term explicitly.
  bool precondition = false;
  /// Rows to leave out of the least squares (non-zero entries) while their inputs still drive
  /// the memory: held-out validation on one record. Empty = use every row.
  std::vector<char> exclude;
  /// A linear, causal filter applied to the model's output before it is compared with the data
  /// (y = L[Gamma[u]]): applied to every regressor column, the weights stay a linear
  /// least-squares problem. diagnose fits a Kelvin creep term this way. Empty = identity.
  /// The returned model is Gamma; predictions are L applied to its output.
  std::function<void(Eigen::Ref<Eigen::VectorXd>)> output_filter;
  /// A reversible term beside the operator: y = Gamma[u] + r (u - lo) / (hi - lo), with
  /// sign * r >= 0, one more column of the least squares (Mayergoyz's reversible component).
  /// A discrete grid follows a response linear in the input only as the steps of its diagonal
  /// cells; this term follows it exactly. kChosen: with or without, by cross-validation
  /// alongside L and lambda; the term is taken where its best held-out error beats the best
  /// without by more than one standard error over the held-out blocks (diagnose's baseline
  /// option). The returned model is Gamma; PreisachFit::reversible_term gives the term.
  enum class Reversible { kOff, kOn, kChosen };
  Reversible reversible = Reversible::kOff;
  NnlsOptions nnls;
  /// Threads over the S shifted grids (each grid's design and solves are independent). The fit
  /// is identical for any count: every grid's result is combined in grid order. With more than
  /// one, output_filter is called from several threads at once and must not modify shared state.
  int threads = 1;

  /// False (with the reason) for impossible settings.
  bool IsValid(std::string* why) const;
};

struct CrossValidationPoint {
  int levels = 0;
  double smoothness = 0.0;
  bool reversible = false;
  double rms_pct_range = 0.0;  ///< pooled held-out RMS error, % of output range
};

struct PreisachFitSummary {
  enum class Termination { kConverged, kNoConvergence };
  Termination termination = Termination::kConverged;
  int levels = 0;       ///< L of each shifted grid (the model's own grid is finer when S > 1)
  int grid_shifts = 1;  ///< S
  double smoothness = 0.0;
  bool reversible = false;  ///< the reversible term was fitted
  int sign = 1;
  int cells = 0;                    ///< cells of one L grid
  int unexcited_cells = 0;          ///< cells whose signed area never changes in the data
  int unidentified_directions = 0;  ///< cells + 1 minus the rank of the regressor
  int nnls_iterations = 0;
  double kkt_violation = 0.0;
  int folds_used = 0;      ///< blocks the record was cut into
  int heldout_blocks = 0;  ///< blocks held out in turn (covered by the others' input range)
  std::vector<CrossValidationPoint> cross_validation;  ///< empty when L and lambda were given
  double cv_rms_pct_range = -1.0;  ///< the chosen setting's held-out error; -1 if not run
  ErrorMetrics train;              ///< on the identification data
  std::vector<std::string> warnings;
  std::string message;

  std::string BriefReport() const;
};

struct PreisachFit {
  PreisachModel model;
  PreisachFitSummary summary;
  double input_min = 0.0;  ///< the identified input range (the model's grid may extend beyond)
  double input_max = 0.0;
  /// r of PreisachFitOptions::reversible (0 without the term), averaged over the shifted grids.
  double reversible = 0.0;
  /// The reversible term at input u: r (u - input_min) / (input_max - input_min).
  double reversible_term(double u) const {
    return reversible * (u - input_min) / (input_max - input_min);
  }
};

/// Identifies a Preisach model. `blocks` (optional, one id per sample) names the segments used
/// as cross-validation folds; empty means "split the record into whole cycles".
/// Throws IdentificationError when the data cannot identify any model (too few samples, no
/// input variation, non-finite values).
PreisachFit fit_preisach(std::span<const double> input, std::span<const double> output,
                         std::span<const int> blocks, const PreisachFitOptions& options);

/// Blocks of whole cycles: cuts the record at input minima into `folds` contiguous parts with
/// about equal sample counts. Exposed for diagnose and tests.
std::vector<int> cycle_blocks(std::span<const double> input, int folds);

}  // namespace scpkit
