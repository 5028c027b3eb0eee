#pragma once
// diagnose: what the rate-independent model gets wrong, the named cause, the extended model and
// its gain on held-out data (SPEC.md "diagnose"; PHYSICS.md section 5).
//
// 1. Baseline: a Preisach model, identified with held-out validation: the record is cut into
//    blocks of whole cycles (or the given segments); each block is predicted by a model fitted
//    on the others (its memory driven by the whole input history). The out-of-fold residuals
//    r_t are what the model gets wrong on data it has not seen.
// 2. Noise floor: white noise from the first differences of the residuals
//    (sigma = 1.4826 MAD(dr) / sqrt 2), plus the sensor's quantisation step q (q^2 / 12).
// 3. One detector per effect: a signature statistic on r, tested against a block-permutation
//    null (contiguous blocks of residuals shuffled, which keeps their autocorrelation), and the
//    extension the effect implies, fitted on the training blocks and scored on the held-out
//    block exactly as the baseline. An effect is detected when its statistic is significant
//    and its extension gains on held-out data.
// 4. cause: the detected effect with the largest held-out gain; "none" when nothing is detected
//    and the baseline's held-out error is at the noise floor; "unexplained" when nothing is
//    detected but the residuals are structured (well above the noise floor).
//
// This version covers single-input records (load or one drive input): drift, creep,
// lonely_stroke and outliers. minor_loop_noncongruence, load_shape_coupling and
// offset_nonlinearity (voltage tests at several loads) are reported as not tested.
#include <cstdint>
#include <span>
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
};

struct Diagnosis {
  std::string baseline_model = "preisach";
  double rms_pct_range = 0.0;  ///< baseline, held-out
  double max_pct_range = 0.0;
  double noise_floor_pct_range = 0.0;
  std::vector<Finding> findings;
  std::string cause = "none";
};

struct DiagnoseOptions {
  int folds = 5;
  int permutations = 199;
  double alpha = 0.01;        ///< significance level of each detector
  double min_gain_pct = 5.0;  ///< an extension must gain at least this on held-out data
  std::uint64_t seed = 1;
  /// How the baseline is identified: L and smoothness chosen by cross-validation unless set.
  PreisachFitOptions baseline;
};

/// time_s may be empty (sample index used); blocks optional (segment ids).
Diagnosis diagnose(std::span<const double> time_s, std::span<const double> input,
                   std::span<const double> output, std::span<const int> blocks,
                   const DiagnoseOptions& options = {});

}  // namespace scpkit
