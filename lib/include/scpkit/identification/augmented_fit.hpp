#pragma once
// Identification of the augmented model y = f2(F) H[v] + f1(F) (paper 000 Section III):
//  1. cut the record into constant-load segments (segment ids, else load changes);
//  2. per segment: offset D = y at its lowest input on the first rise, range
//     P = D - y at its highest input (so H[v_min] = 0, H[v_max] = -1);
//  3. f1, f2: least-squares quadratics of D and P in F (a line for two loads); refuse an f2
//     that crosses zero inside the identified loads;
//  4. H: one operator of the chosen family fitted to the pooled normalised data
//     h = (y - f1(F)) / f2(F), each segment from the initial state (Preisach: cross-validated
//     with the load segments as blocks).
#include <span>
#include <string>
#include <vector>

#include "scpkit/hysteresis/augmented.hpp"
#include "scpkit/identification/gpi_fit.hpp"
#include "scpkit/identification/lonely_fit.hpp"
#include "scpkit/identification/preisach_fit.hpp"
#include "scpkit/metrics.hpp"

namespace scpkit {

struct LoadSegment {
  std::size_t first = 0;  ///< first sample
  std::size_t count = 0;
  double load = 0.0;    ///< N
  double offset = 0.0;  ///< D
  double range = 0.0;   ///< P
};

struct AugmentedFitOptions {
  std::string family = "gpi";  ///< gpi, preisach, lonely, linear or poly2
  PreisachFitOptions preisach;
  GpiFitOptions gpi;
  LonelyFitOptions lonely;
};

struct AugmentedFit {
  AugmentedModel model;
  std::vector<LoadSegment> segments;
  ErrorMetrics train;
  double cv_rms_pct_range = -1.0;  ///< H's cross-validated error (Preisach), normalised units
  std::string report;
};

/// Constant-load segments: a new one where the id changes (ids optional) or the load moves.
std::vector<LoadSegment> split_load_segments(std::span<const double> load,
                                             std::span<const int> ids);

/// IdentificationError when the data cannot identify the model (fewer than two loads, an
/// f2 crossing zero, too little excitation in H).
AugmentedFit fit_augmented(std::span<const double> load, std::span<const double> input,
                           std::span<const double> output, std::span<const int> segment_ids,
                           const AugmentedFitOptions& options);

}  // namespace scpkit
