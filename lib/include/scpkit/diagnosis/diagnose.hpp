#pragma once
// diagnose: what the rate-independent model gets wrong, the named cause, the extended model and
// its gain on held-out data (SPEC.md "diagnose"; PHYSICS.md section 5).
//
// 1. Baseline, identified with held-out validation (never random rows):
//    - one record (a load test, or a drive at one constant load): a Preisach operator on the
//      input; held out by blocks of whole cycles (or the file's segments, when there are two
//      or more); on a load input the first rise, until the load first reaches its maximum,
//      only drives the memory (it depends on the unseen state before the test, hysterons
//      below the lowest load) and is neither fitted nor scored;
//    - tests at several constant loads (voltage, power, temperature): the augmented model
//      y = f1(F) + f2(F) H[v], H a Preisach operator; held out by load segment (each interior
//      load in turn, predicted through the quadratic maps of the others).
//    Each block is predicted by the model fitted without it, its memory driven by the whole
//    input history. The out-of-fold residuals r_t are what the model gets wrong.
// 2. Noise floor from the data: white noise from the residuals' first differences
//    (1.4826 MAD / sqrt 2) and the sensor's quantisation step q (q^2 / 12).
// 3. One detector per named effect: the extension the effect implies (PHYSICS.md section 5),
//    fitted without each block and scored on it exactly as the baseline; detected when it
//    gains >= min_gain_pct of held-out E_RMS (creep: min_creep_gain_pct, raised to
//    min_gain_pct where the protocol hides creep) and the gain is significant against random
//    sign flips of per-block gains; effects defined by a residual signature must also pass a
//    block-permutation test of that signature (blocks of residuals keep their autocorrelation)
//    at alpha, and then its gain need only be significant at gain_alpha (an intersection-union
//    test: its level is still alpha, since the signature alone is a level-alpha test).
// 4. cause: outliers when detected, else the detected effect with the largest held-out gain;
//    "none" when nothing is detected and the held-out error is within twice the noise floor;
//    "unexplained" otherwise.
// 5. Protocol limits: the effects the record's protocol keeps from view (protocol_limits_of),
//    listed beside the cause with the change that would show them.
#include <cstdint>
#include <string>
#include <vector>

#include "scpkit/identification/preisach_fit.hpp"

namespace scpkit {

struct Finding {
  std::string effect;
  bool tested = false;  ///< false when this data cannot test the effect
  bool detected = false;
  double score = 0.0;    ///< the signature statistic (effect-specific, larger = stronger)
  double p_value = 1.0;  ///< against the block-permutation null
  std::string evidence;  ///< one sentence
  std::string extended_model;
  double heldout_rms_before = 0.0;  ///< % of output range
  double heldout_rms_after = 0.0;
  double gain_pct = 0.0;  ///< 100 (1 - after / before)
  /// Scored on the held-out readings whose memory their training identified only (the
  /// before and after E_RMS and the gain are theirs), not on every held-out reading.
  bool on_identified = false;
  /// The extended model's prediction of each reading, out of fold where held out, in sample
  /// (the first fold's fit) where never held out, the baseline's elsewhere; empty when no
  /// extension was fitted.
  std::vector<double> heldout_prediction;
  /// The readings the finding singles out, 1 each (outliers: those the spike screen flagged,
  /// named or not); empty for the other effects and where none is.
  std::vector<char> flagged;
};

/// An effect the record's protocol keeps from view, and the protocol change that would show it.
struct ProtocolLimit {
  std::string effect;
  std::string note;  ///< one sentence: why this protocol hides it, and what to change
};

struct Diagnosis {
  std::string baseline_model = "preisach";
  std::string heldout_by;        ///< "cycles", "segments" or "load segments"
  int heldout_folds = 0;         ///< folds held out in turn
  std::size_t heldout_rows = 0;  ///< readings scored out of fold
  double rms_pct_range = 0.0;    ///< baseline, held-out
  double max_pct_range = 0.0;
  /// held-out E_RMS without its largest 5 % of residuals: what `none` is judged on
  double sustained_rms_pct_range = 0.0;
  double noise_floor_pct_range = 0.0;
  /// The noise's lag-one correlation in time as the residuals show it (0: white), which the
  /// floor and the return-point signatures allow for.
  double noise_correlation = 0.0;
  /// Held-out readings whose memory the training folds identified (every Everett pair of the
  /// memory observed in training), and their sustained E_RMS: `unexplained` needs both.
  std::size_t identified_rows = 0;
  double identified_sustained_rms_pct_range = 0.0;
  /// Per reading, in the data's order: the baseline's held-out prediction, NaN where the
  /// reading was not scored (never held out, only driving the memory, or beyond the inputs its
  /// fold's training spanned); the fold that held it out (0-based, -1 where none); whether that
  /// fold's training identified its memory. `scpkit diagnose --residuals` writes them.
  std::vector<double> baseline_prediction;
  std::vector<int> heldout_fold;
  std::vector<char> identified;
  std::vector<Finding> findings;
  std::string cause = "none";
  std::string cause_note;  ///< why `none` or `unexplained`, where it is not plain
  /// What this protocol keeps from view (protocol_limits_of): read beside a `none`.
  std::vector<ProtocolLimit> protocol_limits;
};

/// The baseline's identification options: those of `scpkit fit` but for the smoothness
/// candidates, which leave out 0. An unregularised fit on a fine grid is ill-conditioned, and
/// its held-out error follows round-off: cross-validation chose between it and a smoothed fit
/// on the last digits, so the same record in other units, or shifted by 1e-9 of itself, got
/// another baseline and, once, another cause (docs/diagnose-log.md, sessions 24 and 25).
/// The reversible term is taken where cross-validation takes it by the one-standard-error rule
/// (`kChosen`): a response partly linear in the input leaves the operator alone a structured
/// error that diagnose called `unexplained` on clean records (docs/diagnose-log.md, sessions
/// 35-37).
inline PreisachFitOptions diagnose_baseline_options() {
  PreisachFitOptions o;
  o.candidate_smoothness = {1e-6, 1e-5, 1e-4, 1e-3};
  o.reversible = PreisachFitOptions::Reversible::kChosen;
  return o;
}

struct DiagnoseOptions {
  int folds = 5;
  int permutations = 999;     ///< resampling tests: p resolves 0.001, well below alpha
  double alpha = 0.01;        ///< significance level of each detector
  double gain_alpha = 0.05;   ///< the gain's test, after a significant residual signature
  double min_gain_pct = 5.0;  ///< an extension must gain at least this on held-out data
  /// ... creep's extensions (a lag behind the input in time, which no rate-independent
  /// baseline can take up) at least this, where the protocol shows creep: holds of different
  /// lengths or readings during holds (else min_gain_pct; docs/diagnose.md, item 3).
  double min_creep_gain_pct = 2.0;
  std::uint64_t seed = 1;
  /// How the baseline is identified: L, smoothness and the reversible term chosen by
  /// cross-validation unless set (`baseline.reversible = kOff`: the operator alone).
  PreisachFitOptions baseline = diagnose_baseline_options();
};

/// What diagnose reads from a measurement.
struct DiagnoseData {
  std::vector<double> time_s;   ///< optional (from dwell_s, else the reading index, when empty)
  std::vector<double> dwell_s;  ///< optional: time held at this input before the reading
  std::vector<double> input;    ///< load (load tests) or the drive (voltage, power, temperature)
  std::vector<double> output;   ///< response
  /// Tests at several constant loads: the load of each reading, constant over each load segment
  /// (from a file: held_load_N in scpkit/io/held_load.hpp, which averages a load cell's scatter).
  std::vector<double> load_N;
  std::vector<int> segments;  ///< optional segment ids
  /// The input is a load (its first rise depends on the unseen state before the test); false
  /// for a drive (voltage, power, temperature) that starts from rest.
  bool input_is_load = true;
};

/// IdentificationError when the data cannot be diagnosed (too few readings, no excitation,
/// nothing to hold out); InvalidArgument for inconsistent columns.
Diagnosis diagnose(const DiagnoseData& data, const DiagnoseOptions& options = {});

/// The readings' times from data.dwell_s (time held at the input before each reading), used when
/// a file has no clock: a hold starts at the previous reading when the input (or the load)
/// changes or the dwell does not grow, and each of its readings comes its dwell after that.
std::vector<double> reading_times_from_dwell(const DiagnoseData& data);

/// The effects this record's protocol keeps diagnose from seeing, each measured as a miss
/// (docs/diagnose.md): on a load test the lonely stroke (a virgin specimen's first loading
/// looks the same); with one reading per hold and holds of one length, creep (its lag is loop
/// width to the baseline); loads tested in the order of their size, drift (f1 absorbs it).
/// Read off the protocol alone, so a planned test can be checked before it is run.
std::vector<ProtocolLimit> protocol_limits_of(const DiagnoseData& data);

/// The effect names of SPEC.md, in the order diagnose reports them.
const std::vector<std::string>& effect_names();

}  // namespace scpkit
