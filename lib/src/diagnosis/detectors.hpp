#pragma once
// Private to diagnose: what every detector shares (the record, the baseline refitted without
// each fold, its out-of-fold residuals, the noise floor; context.cpp) and one function per
// named effect.
#include <Eigen/Core>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "baseline.hpp"
#include "scpkit/diagnosis/diagnose.hpp"
#include "scpkit/error.hpp"
#include "signatures.hpp"
#include "stats.hpp"

namespace scpkit::diagnosis {

/// Too few held-out readings lie within the inputs their folds trained on (Context).
class TooFewHeldOut : public IdentificationError {
 public:
  using IdentificationError::IdentificationError;
};

struct Context {
  const Record& rec;
  const Baseline& base;
  const DiagnoseOptions& opt;
  std::vector<FoldFit> by_fold;                  ///< the baseline fitted without fold k
  std::vector<double> oof;                       ///< out-of-fold prediction (scored rows)
  std::vector<double> r;                         ///< y - oof (0 on rows never held out)
  std::vector<std::size_t> scored;               ///< rows held out in some fold
  std::vector<std::vector<std::size_t>> blocks;  ///< consecutive scored rows, for the tests
  /// The noise as the first differences show it (white part and sensor step; output units):
  /// the detectors' robust scale.
  double floor = 0.0;
  double white = 0.0;  ///< the floor's white part
  /// The noise's standard deviation with its lag-one correlation in time included: the noise
  /// floor the held-out error is judged against (output units).
  double noise_sd = 0.0;
  double noise_rho = 0.0;   ///< that lag-one correlation
  double resolution = 0.0;  ///< sensor step (0: continuous)
  /// The sensor step dominates the noise (over twice its white part): the same true value
  /// rounds the same way every time, and a motion below the step is not read at all.
  bool step_dominates() const { return resolution > 2.0 * white; }
  double rms_before = 0.0;             ///< % of range
  ReturnPointSignatures return_point;  ///< model-free (signatures.hpp)
  Signature congruency, holds;
  Signature congruency_robust;  ///< the same, blind to single readings off their neighbours
  Signature dwell;  ///< creep with one reading per hold: residuals against the hold times
  /// Load tests read once per hold: readings in one memory state against the lag their path
  /// would leave (creep; lag_signature in signatures.hpp, computed by detect_creep).
  Signature lag;
  Signature coupling;  ///< the loop shape changing with the load (detect_load_shape_coupling)
  /// Creep with readings during holds named by the Kelvin element's held-out gain while the
  /// readings during holds do not move at alpha (detect_creep): known by a gain only, it
  /// competes by gain and yields to a drift seen in time (cause.cpp).
  bool creep_by_gain_only = false;
  /// The creep finding is the Kelvin element carried across load changes (detect_creep): its
  /// lag offsets each segment's first rise, as a lonely stroke does (cause.cpp).
  bool creep_carried = false;
  /// A drift detected by its held-out gain with an extension sized inside the load segments
  /// (detect_drift, tests held out by load segment): a trend no map of the load makes, so an
  /// offset nonlinearity yields to it (cause.cpp).
  bool drift_within_segments = false;
  /// The non-congruence finding is the term without wiping-out (detect_noncongruence): its
  /// evidence is readings in one memory state that differ, which a drift shows too, not the
  /// congruency signature, so it competes by gain (cause.cpp).
  bool loops_unclosed = false;
  /// The flagged readings' removal gain the outliers finding was judged by (detect_outliers):
  /// on every other held-out reading, or on those whose memory both trainings identified where
  /// that is larger (% ; 0 where nothing was flagged).
  double outliers_removal_gain = 0.0;
  /// Held-out readings whose memory their fold's training identified (identified_readings).
  std::vector<char> identified;
  /// Folds whose training rows chose a lonely-stroke term (detect_lonely_stroke).
  int lonely_folds_with_term = 0;
  std::mt19937_64 rng;

  Context(const Record& r, const Baseline& b, const DiagnoseOptions& o);
  std::vector<char> train_mask(int fold) const;
};

/// Fewer held-out readings than this whose memory their training identified cannot show
/// structure beside the baseline's gaps.
constexpr std::size_t kMinIdentified = 10;

/// What an extension must gain (% of held-out E_RMS) where its model-free signature at alpha,
/// not its gain, names the effect: a drift (detect_drift) and a load-shape coupling
/// (name_by_signature in cause.cpp). Clean records' extensions gained up to 0.84 % there.
constexpr double kSignatureGainPct = 1.0;

/// The scored readings whose memory their fold's training identified (Context::identified), in
/// order: the one count of them the detectors and the report use.
std::vector<std::size_t> identified_scored(const Context& ctx);
/// "on the N held-out readings whose memory their training identified", for evidence.
std::string on_identified_readings(std::size_t count);

/// Held-out comparison of an extension's out-of-fold prediction with the baseline's, on the
/// scored rows that `use` admits (all when empty): E_RMS after (% of range), the gain, and the
/// sign-flip p-value of the per-block gains (drawn from `rng`, the context's stream when null).
struct Score {
  std::size_t count = 0;    ///< readings compared
  double rms_before = 0.0;  ///< the baseline's, on the rows scored (% of range)
  double rms_after = 0.0;
  double gain_pct = 0.0;
  double p_value = 1.0;
};
Score score(Context& ctx, const std::vector<double>& after, const std::vector<char>& use = {},
            std::mt19937_64* rng = nullptr);
/// The same comparison without the p-value (left at 1), for a gain that is compared, not
/// tested: no random draws. `block_gains` receives the per-block gains when given.
Score heldout_gain(const Context& ctx, const std::vector<double>& after,
                   const std::vector<char>& use = {}, std::vector<double>* block_gains = nullptr);

/// Features of an effect, one row per reading, computed from one fold's baseline fit.
using Features = std::function<Eigen::MatrixXd(const FoldFit&)>;

/// For its lifetime the context's permutation tests draw from a stream of their own, seeded
/// from the options' seed and `salt`; the shared stream is restored where it was.
class OwnStream {
 public:
  OwnStream(Context& ctx, std::uint64_t salt) : ctx_(ctx), shared_(ctx.rng) {
    ctx.rng.seed(ctx.opt.seed + salt);
  }
  ~OwnStream() { ctx_.rng = shared_; }
  OwnStream(const OwnStream&) = delete;
  OwnStream& operator=(const OwnStream&) = delete;

 private:
  Context& ctx_;
  std::mt19937_64 shared_;
};

/// An effect seen as a residual signature X: block-permutation test of R^2(r ~ X), and the
/// two-stage extension y = baseline + X beta (beta on each fold's training rows). With
/// `signature`, that test is stored there too, resolved with ten times the permutations (on a
/// stream of its own) where the usual count leaves p at its least value, so that it can be
/// held to alpha / 10 (cause.cpp names some effects by their signature alone).
Finding feature_finding(Context& ctx, const std::string& effect, const std::string& extension,
                        const Features& features, const std::string& what,
                        Signature* signature = nullptr);

/// An effect whose extension is another model: `fit(train)` predicts every row. Scored on the
/// held-out rows, or on those of them where `use` is non-zero when it is given.
Finding model_finding(Context& ctx, const std::string& effect, const std::string& extension,
                      const std::function<std::vector<double>(int fold)>& fold_prediction,
                      const std::string& what, const std::vector<char>& use = {});

/// One fold's baseline fitted together with an offset c and a multiple beta of the regressor g
/// (backfitting): the baseline refitted on y - c - beta g and (c, beta) regressed on the
/// training residuals, in turn; the regressor is one column, so each round moves beta the same
/// fraction of the way to the joint fit (exactly so for a linear least-squares baseline, nearly
/// for NNLS): three rounds on one grid give that fraction and the limit (Aitken's
/// extrapolation), then a fit on the full grid and the offset again. Returns the prediction of
/// every row with c + beta g added.
std::vector<double> fit_with_regressor(const Context& ctx, const std::vector<char>& train,
                                       const std::function<double(std::size_t)>& g, double& beta);

Finding not_tested(const Context& ctx, const std::string& effect, const std::string& why);

/// A model-free signature's verdict in words.
std::string describe(const Signature& s);

/// The least held-out gain that names `effect`'s extension by its gain: min_gain_pct, and for
/// creep min_creep_gain_pct. Where the holds differ in length or readings are taken during
/// them, a Kelvin element's lag behind the input in time is rate dependence, which no
/// rate-independent baseline can take up (hold_out sets min_gain_pct for it elsewhere;
/// docs/diagnose-log.md, session 83).
inline double least_gain_pct(const DiagnoseOptions& opt, const std::string& effect) {
  return effect == "creep" ? opt.min_creep_gain_pct : opt.min_gain_pct;
}

// One function per named effect, each in its own file (drift.cpp, creep.cpp, lonely_stroke.cpp,
// load_maps.cpp, noncongruence.cpp, outliers.cpp with its ramp scores in ramp_scores.cpp).

Finding detect_drift(Context& ctx);
Finding detect_creep(Context& ctx);
/// Creep on a test at several loads through one Kelvin element that is not restarted at load
/// changes: after each change the response relaxes from where the last segment left it.
Finding detect_creep_across_loads(Context& ctx);
Finding detect_lonely_stroke(Context& ctx);
Finding detect_noncongruence(Context& ctx);
Finding detect_load_shape_coupling(Context& ctx);
Finding detect_offset_nonlinearity(Context& ctx);
/// Whether offset_nonlinearity's finding, a signature alone below five loads and at five where
/// the cubic maps do not name it (few_loads_signature), is strong enough to name the cause where
/// the residuals are material.
bool maps_miss_by_signature(const Context& ctx, const Finding& offset);
/// The outliers' screen of the residuals `ctx.r` (the in-sample residuals of the first fold's
/// fit on rows never held out), without the robust refit: the readings flagged, how many of
/// them were confirmed off their protocol point, hold-mates or ramp, their largest scores,
/// and the screen's p-value (Bonferroni over the readings).
struct OutlierScreen {
  std::vector<char> flagged;
  int count = 0, confirmed = 0, in_holds = 0;
  double zmax = 0.0;       ///< the largest score off the neighbours
  double repro_max = 0.0;  ///< the largest confirming score
  double p_value = 1.0;
  bool stands_out(double alpha) const { return count > 0 && p_value < alpha; }
};
OutlierScreen screen_outliers(const Context& ctx);
/// Spikes that break a monotone branch, judged on the readings alone (load tests; per row, 0
/// where none): a reading on a ramp outside its neighbours' interval (and off their
/// interpolation), a reading at a turning value of the input that is not the response's
/// extreme among its neighbours, a run of two or three readings inside a ramp outside the
/// interval of the readings either side, a reading at a turning value whose two steps both
/// exceed every other pass's change over their inputs (session 64), a reading inside a ramp off
/// its neighbours' interpolation while they lie off theirs the other way, by its weights in
/// them (a spike smaller than the ramp's step; session 74). In units of the noise along the
/// ramps (ramp_scores.cpp); nothing within two sensor steps (`resolution`) counts.
std::vector<double> ramp_scores(const Record& rec, double resolution);
Finding detect_outliers(Context& ctx);

}  // namespace scpkit::diagnosis
