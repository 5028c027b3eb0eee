#pragma once
// Specimen-change diagnosis: what changed between two tests of one kind (the same input and
// response), e.g. a fibre tested dry and again after days of moisture.
//
// The reference test's Preisach model Gamma (identified on the whole reference file, L and
// lambda by cross-validation) predicts the second test from its own input history. Held out by
// contiguous blocks of the second test's rows (each block predicted by parameters fitted on the
// others), nested candidates, each one more parameter family than the one before:
//   none         y = Gamma[u]                     (the same specimen, unchanged)
//   offset       y = Gamma[u] + c                 (remounted, re-zeroed, a set strain)
//   range        y = g Gamma[u] + c               (the stroke scaled: a stiffer or softer fibre)
//   input_shift  y = g Gamma[u - d] + c           (the transition moved along the input: e.g. a
//                                                  glass transition lowered by absorbed water)
// and, apart from the chain, `shape`: a Preisach model of the second test alone (the same L and
// lambda), fitted on its training blocks (the hysteresis itself changed shape).
// A candidate is accepted when it gains at least `min_gain_pct` on the held-out error of the one
// accepted before it, with a sign-flip p-value over the held-out blocks below `alpha`, and that
// one's held-out error is material: above `floor_factor` times the second test's noise floor
// (from its second differences, 1.4826 median |y[t+1] - 2 y[t] + y[t-1]| / sqrt(6), and at least
// a quantised sensor's step / sqrt(12)). `shape`
// when it so beats the last accepted one. The named change is the last accepted; `none` when
// nothing gains on the unchanged model.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace scpkit {

struct SpecimenChangeCandidate {
  std::string change;                   ///< none, offset, range, input_shift, shape
  std::string model;                    ///< the candidate in words
  double g = 1.0;                       ///< range factor (chain steps: fitted on every reading)
  double c = 0.0;                       ///< offset, response units
  double d = 0.0;                       ///< input shift, input units
  double heldout_rms_pct = 0.0;         ///< % of the second test's response range
  double heldout_rms_before_pct = 0.0;  ///< of the candidate it extends (none: its own)
  double heldout_max_pct = 0.0;
  double gain_pct = 0.0;  ///< 100 (1 - heldout / heldout of the candidate it extends)
  double p_value = 1.0;   ///< sign-flip over held-out blocks against that candidate
  bool accepted = false;
  std::string evidence;
};

struct SpecimenChange {
  std::string reference_model;     ///< the reference's Preisach model in words
  double reference_rms_pct = 0.0;  ///< its in-sample E_RMS, % of the reference's range
  int blocks = 0;                  ///< held-out blocks of the second test
  double noise_floor_pct = 0.0;    ///< the second test's noise floor, % of its range
  std::vector<SpecimenChangeCandidate> candidates;  ///< none, offset, range, input_shift, shape
  std::string change = "none";
};

struct SpecimenChangeOptions {
  int blocks = 8;  ///< contiguous held-out blocks of the second test (at least 4)
  double min_gain_pct = 5.0;
  double alpha = 0.05;
  double floor_factor = 1.5;
  double max_shift = 0.3;  ///< |d| up to this fraction of the reference's input span
  int permutations = 2000;
  std::uint64_t seed = 1;
};

/// Throws InvalidArgument for mismatched lengths and IdentificationError when either test
/// cannot be identified (too few readings or too little excitation); the reference's begins
/// "the reference: ".
SpecimenChange diagnose_specimen_change(std::span<const double> reference_input,
                                        std::span<const double> reference_output,
                                        std::span<const double> input,
                                        std::span<const double> output,
                                        const SpecimenChangeOptions& options = {});

}  // namespace scpkit
