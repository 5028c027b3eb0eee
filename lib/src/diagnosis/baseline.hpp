#pragma once
// Private to diagnose: the record as diagnose sees it, its held-out folds, and the baseline
// model refitted without each fold.
//
// Load tests: a Preisach operator on the load. Tests at several constant loads (voltage,
// power, temperature): the augmented model y = a_s + b_s H[v] with H a Preisach operator
// restarted in each segment, a_s and b_s free per segment where the segment has training
// rows, and from quadratic maps f1(F), f2(F) through the trained segments where it has none
// (paper 000's identification, refined by alternations between H and the per-segment affine
// maps: two, or until settled where the training rows are parts of cycles).
#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "scpkit/diagnosis/diagnose.hpp"
#include "scpkit/identification/preisach_fit.hpp"

namespace scpkit::diagnosis {

struct Record {
  std::vector<double> time, u, y;
  bool clocked = true;  ///< false: no time_s or dwell_s, `time` is the reading index
  bool several_loads = false;
  bool input_is_load = false;  ///< load tests: the first rise is memory-only (never scored)
  std::vector<int> seg;        ///< segment of each row (0, 1, ...; one segment for load tests)
  std::vector<std::size_t> seg_first, seg_count;
  std::vector<double> seg_load;  ///< N (several_loads only)
  /// Held-out fold of each row; kAlwaysTrained = in every training set, never scored;
  /// kMemoryOnly = in the memory of the operator only (never fitted, never scored).
  std::vector<int> fold;
  static constexpr int kAlwaysTrained = -1;
  static constexpr int kMemoryOnly = -2;
  /// Whether row t is fitted when fold k is held out.
  bool trains(std::size_t t, int k) const { return fold[t] != k && fold[t] != kMemoryOnly; }
  int folds = 0;
  std::string fold_kind;  ///< "cycles" or "load segments"
  /// Baseline::fit alternates until the training rows' prediction settles, not twice
  /// (FoldScheme::cycles_within_segments, where a segment's training rows are part of a cycle).
  bool settle = false;
  double range = 1.0;  ///< output range
  std::size_t size() const { return y.size(); }
};

/// How a test at several constant loads is held out.
enum class FoldScheme {
  /// By load segment (the maps are tested on loads they were not fitted at); records of one
  /// load or of two loads in two segments are held out by cycles either way.
  load_segments,
  /// By blocks of whole cycles inside every segment, rotated from segment to segment, so that
  /// every segment's first rise is scored and its offset and range are fitted on its later
  /// cycles (the lonely stroke's second look, diagnose.cpp).
  cycles_within_segments,
};

/// Builds the record and its folds. IdentificationError when it cannot be diagnosed.
Record make_record(const DiagnoseData& data, const DiagnoseOptions& options,
                   FoldScheme scheme = FoldScheme::load_segments);

/// Map families through the per-segment offsets and ranges (several loads).
struct MapFit {
  std::vector<double> coef_a, coef_b;  ///< on the basis below
  double knee_width = 0.0;             ///< 0: quadratic; > 0: plus exp(-(F - F_lo) / width)
  bool cubic = false;                  ///< plus x^3 instead of a knee
  double f_lo = 0.0;
  double f_scale = 1.0;  ///< basis in x = (F - f_lo) / f_scale
  double eval(const std::vector<double>& c, double F) const;
};
/// Quadratic maps, plus a knee when knee_width > 0 or a cubic term when `cubic` (each needs
/// four distinct loads).
MapFit fit_maps(const std::vector<double>& F, const std::vector<double>& a,
                const std::vector<double>& b, double knee_width, double f_lo, double f_scale,
                bool cubic = false);

/// One model fitted on the rows where train != 0, predicting every row.
struct FoldFit {
  std::vector<double> pred;
  std::vector<double> h;     ///< several loads: H's output per row
  std::vector<double> a, b;  ///< several loads: per segment, as used for the prediction
  std::vector<char> free;    ///< several loads: the segment had training rows
};

/// The quadratic maps through the segments `fit` trained (its free ones): offsets `a` (the
/// fit's own, or corrected by an extension) and the fit's ranges, on the record's load span.
MapFit maps_through_trained(const Record& rec, const FoldFit& fit, const std::vector<double>& a);

/// A causal linear filter on the model's output (PreisachFitOptions::output_filter).
using OutputFilter = std::function<void(Eigen::Ref<Eigen::VectorXd>)>;

class Baseline {
 public:
  /// Chooses L and the smoothness once (cross-validation on the whole record), then fixes them.
  Baseline(const Record& rec, const PreisachFitOptions& initial);
  /// Variations of the fit that extensions need.
  struct Variant {
    OutputFilter filter;                     ///< y = L[model] (creep)
    const std::vector<double>* y = nullptr;  ///< fit this response instead of the record's
    bool quick = false;                      ///< one grid instead of the shifted-grid average
    /// Load tests: the moving model y = Gamma[u + moving * y] (PHYSICS.md section 5), 0 = off.
    /// Identified on the effective input u + moving * y with the measured y on training rows
    /// and `fill` (a prediction made without the other rows, e.g. the baseline's) elsewhere;
    /// predicted by solving y = Gamma[u + moving * y] reading by reading, from the model alone.
    double moving = 0.0;
    const std::vector<double>* fill = nullptr;
  };
  /// The model fitted on the rows where train != 0, predicting every row.
  FoldFit fit(const std::vector<char>& train, const Variant& variant) const;
  FoldFit fit(const std::vector<char>& train) const { return fit(train, Variant{}); }
  const PreisachFitOptions& options() const { return options_; }
  std::string name() const;

 private:
  std::vector<double> fit_moving(const std::vector<char>& train, const Variant& variant,
                                 PreisachFitOptions o) const;
  const Record& rec_;
  PreisachFitOptions options_;
};

}  // namespace scpkit::diagnosis
