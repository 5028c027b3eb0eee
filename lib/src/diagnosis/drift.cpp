// drift: a slow trend in time, independent of the input (PHYSICS.md section 5).
#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>
#include <tuple>
#include <utility>

#include "detectors.hpp"
#include "stats.hpp"

namespace scpkit::diagnosis {

namespace {

// Each segment's mean reading time (s).
std::vector<double> segment_mean_times(const Record& rec) {
  std::vector<double> mean(rec.seg_first.size(), 0.0);
  for (std::size_t s = 0; s < mean.size(); ++s) {
    for (std::size_t t = rec.seg_first[s]; t < rec.seg_first[s] + rec.seg_count[s]; ++t)
      mean[s] += rec.time[t];
    mean[s] /= static_cast<double>(rec.seg_count[s]);
  }
  return mean;
}

// Drift on tests at several loads: the per-segment offsets the baseline frees absorb a drift on
// the training segments, so a trend fitted to training residuals sees nothing. The drift lives
// in the offset map instead: a_s = f1(F_s) + beta t_s (t_s the segment's mean time), through
// which the held-out segments are predicted; separable from f1 when the loads were not tested
// in the order of their size.
Finding drift_in_offset_map(Context& ctx) {
  const Record& rec = ctx.rec;
  const auto [flo, fhi] = std::minmax_element(rec.seg_load.begin(), rec.seg_load.end());
  const double f_lo = *flo, f_scale = std::max(*fhi - *flo, 1e-300);
  const double t0 = rec.time.front(), t1 = std::max(rec.time.back(), t0 + 1e-300);
  std::vector<double> seg_time = segment_mean_times(rec);
  for (double& t : seg_time) t = (t - t0) / (t1 - t0);
  std::string betas;
  Finding f = model_finding(
      ctx, "drift", "augmented baseline with offset map f1(F) + beta t (linear drift in time)",
      [&](int k) {
        const FoldFit& fit = ctx.by_fold[static_cast<std::size_t>(k)];
        std::vector<std::size_t> train;
        for (std::size_t s = 0; s < rec.seg_first.size(); ++s) {
          if (fit.free[s]) train.push_back(s);
        }
        const auto m = static_cast<Eigen::Index>(train.size());
        // A quadratic and a trend need four offsets: exactly determined at five loads (four
        // train in each fold, as for the cubic maps of load_maps.cpp), which is enough to
        // predict the held-out loads (measured, session 28: 82 voltage records of five loads
        // from the three independent generators, four drifts named `none` or `unexplained`
        // before named `drift`, no clean record changed).
        if (m < 4) return fit.pred;
        Eigen::MatrixXd A(m, 4);
        Eigen::VectorXd a(m);
        for (Eigen::Index i = 0; i < m; ++i) {
          const std::size_t s = train[static_cast<std::size_t>(i)];
          const double x = (rec.seg_load[s] - f_lo) / f_scale;
          A.row(i) << 1.0, x, x * x, seg_time[s];
          a[i] = fit.a[s];
        }
        const Eigen::VectorXd c = A.colPivHouseholderQr().solve(a);
        betas += fmt::format("{}{:.3g}", betas.empty() ? "" : ", ", c[3]);
        const MapFit maps = maps_through_trained(rec, fit, fit.a);
        std::vector<double> p(fit.pred);
        for (std::size_t t = 0; t < rec.size(); ++t) {
          const auto s = static_cast<std::size_t>(rec.seg[t]);
          if (fit.free[s]) continue;
          const double x = (rec.seg_load[s] - f_lo) / f_scale;
          const double off = c[0] + c[1] * x + c[2] * x * x + c[3] * (rec.time[t] - t0) / (t1 - t0);
          p[t] = off + maps.eval(maps.coef_b, rec.seg_load[s]) * fit.h[t];
        }
        return p;
      },
      "offsets that follow the time of each load segment as well as its load");
  f.extended_model += betas.empty()
                          ? " (not fitted: every fold trains fewer than four segments' offsets)"
                          : " (beta per fold: " + betas + ")";
  return f;
}

// Drift at several loads held out by load segment, sized inside the training segments. When
// the loads were tested in the order of their size, a drift in the offsets is a smooth function
// of the load and the offset map takes it up; and a drift that settles (a warm-up) is no line in
// the segments' mean times. Inside each training segment it is still a trend in time, which the
// segment's own offset and range do not follow: its size beta and shape g (a line, or a warm-up
// exp(-t / T) settling with T of 0.1-0.8 of the record) are fitted on the training rows'
// residuals about each segment's mean, the offset map through the training offsets less the
// drift's mean over each, and each held-out reading predicted as f1(F) + f2(F) H + beta g(t).
// The map cannot take up the drift here: beta comes from inside the segments only.
std::optional<Finding> drift_sized_within_segments(Context& ctx) {
  const Record& rec = ctx.rec;
  const double t0 = rec.time.front(), t1 = std::max(rec.time.back(), t0 + 1e-300);
  constexpr double kSettling[] = {0.0, 0.1, 0.2, 0.4, 0.8};  // 0: a line
  const auto g = [&](double T, std::size_t t) {
    const double x = (rec.time[t] - t0) / (t1 - t0);
    return T > 0.0 ? -std::exp(-x / T) : x;
  };
  const std::size_t S = rec.seg_first.size();
  std::string chosen;
  bool fitted = false;
  Finding f = model_finding(
      ctx, "drift",
      "augmented baseline + drift beta g(t) (a line or a warm-up exp(-t / T)) sized inside the "
      "training segments, the offset map fitted through the offsets less it",
      [&](int k) {
        const FoldFit& fit = ctx.by_fold[static_cast<std::size_t>(k)];
        // Four training offsets, as for the map's trend above (five loads or more): with three
        // the quadratic is exactly determined, and the drift's correction moves the held-out
        // offsets freely (measured, four loads: a fourth-generator knee and lonely stroke named
        // `drift`, their folds choosing a line in one and a warm-up of T 0.1 in the other).
        if (std::count(fit.free.begin(), fit.free.end(), 1) < 4) return fit.pred;
        // The training rows: each one's segment, and each segment's mean of g.
        auto trained = [&](std::size_t t) {
          return rec.trains(t, k) && fit.free[static_cast<std::size_t>(rec.seg[t])];
        };
        double best_sse = std::numeric_limits<double>::infinity(), beta = 0.0, shape = 0.0;
        std::vector<double> best_mean;
        for (double T : kSettling) {
          std::vector<double> mean(S, 0.0), count(S, 0.0);
          for (std::size_t t = 0; t < rec.size(); ++t) {
            if (!trained(t)) continue;
            mean[static_cast<std::size_t>(rec.seg[t])] += g(T, t);
            count[static_cast<std::size_t>(rec.seg[t])] += 1.0;
          }
          for (std::size_t s = 0; s < S; ++s) mean[s] = count[s] > 0.0 ? mean[s] / count[s] : 0.0;
          double zz = 0.0, zr = 0.0, rr = 0.0;
          for (std::size_t t = 0; t < rec.size(); ++t) {
            if (!trained(t)) continue;
            const double z = g(T, t) - mean[static_cast<std::size_t>(rec.seg[t])];
            const double r = rec.y[t] - fit.pred[t];
            zz += z * z;
            zr += z * r;
            rr += r * r;
          }
          if (!(zz > 0.0)) continue;
          const double sse = rr - zr * zr / zz;
          if (sse < best_sse) {
            best_sse = sse;
            beta = zr / zz;
            shape = T;
            best_mean = std::move(mean);
          }
        }
        if (best_mean.empty()) return fit.pred;
        fitted = true;
        chosen +=
            fmt::format("{}{} {:.3g}", chosen.empty() ? "" : "; ",
                        shape > 0.0 ? fmt::format("T {:g},", shape) : std::string("line,"), beta);
        std::vector<double> offsets(fit.a);
        for (std::size_t s = 0; s < S; ++s) offsets[s] -= beta * best_mean[s];
        const MapFit maps = maps_through_trained(rec, fit, offsets);
        std::vector<double> p(fit.pred);
        for (std::size_t t = 0; t < rec.size(); ++t) {
          const auto s = static_cast<std::size_t>(rec.seg[t]);
          if (fit.free[s]) continue;
          p[t] = maps.eval(maps.coef_a, rec.seg_load[s]) +
                 maps.eval(maps.coef_b, rec.seg_load[s]) * fit.h[t] + beta * g(shape, t);
        }
        return p;
      },
      "a drift sized inside the training segments");
  if (!fitted) return std::nullopt;
  f.extended_model += " (per fold: " + chosen + ")";
  return f;
}

// Load tests: the trend fitted with the baseline. The two-stage extension fits the trend to the
// training residuals of a baseline that has already taken up part of it: where the history of
// the input changes through the record a Preisach plane fits part of a trend, and the held-out
// residuals carry more of the trend than the training residuals show. Here each fold's
// baseline is fitted with the trend (fit_with_regressor: backfitting, Aitken's extrapolation
// of three rounds, a final fit on every grid). Measured (session 39): on two
// rig load records of a 3 % drift at 0.02 mm noise (TheTrendFittedWithTheBaselineIsTheHiddenDrift)
// three plain rounds recovered 0.38-0.78 of the drift per fold, ten 0.74-0.96, the three
// extrapolated 0.79-1.05.
// Fitted where the two-stage trend is detected or its signature is at alpha (detect_drift); its
// permutation test draws from a stream of its own, so whether it runs does not move the
// p-values of the detectors run after it. Detected where the held-out gain is at alpha too (the
// two-stage extension's gain is taken at gain_alpha: this
// one refits the baseline, and a clean third-generator record, damped, AR(1) noise, gained
// 12.3 % at p = 0.030 with per-fold trends of 0.04-0.66 % of the range; the right drifts it
// names were at p <= 0.005), the gain at least min_gain_pct, and the trend over the record
// at least the noise of one reading: the backfitted trend gains more than the two-stage one on
// clean records too where that signature sits at alpha (two clean independent-generator
// records, trends of 0.6 and 0.3 % of the range against floors of 0.68 and 0.50 %, gained 9.4
// and 7.8 % at p = 0.001 and 0.004; the two-stage trend 4.8 %).
// The trend's shape: a line, or a drift that settles (a warm-up) as exp(-k x), x the time in
// units of the record, k chosen on each fold baseline's training residuals among
// kSettlingRates: the shape that relaxes over a half to an eighth of the record.
enum class TrendShape { kLine, kSettling };
constexpr double kSettlingRates[] = {2.0, 3.0, 5.0, 8.0};

Finding trend_fitted_with_baseline(Context& ctx, TrendShape shape) {
  const bool settling = shape == TrendShape::kSettling;
  const OwnStream own(ctx, settling ? 19 : 11);
  const Record& rec = ctx.rec;
  const double t0 = rec.time.front(), t1 = std::max(rec.time.back(), t0 + 1e-300);
  auto x = [&](std::size_t t) { return (rec.time[t] - t0) / (t1 - t0); };
  std::string trends;
  double trend_sum = 0.0;
  Finding f = model_finding(
      ctx, "drift",
      settling ? "baseline fitted with a settling trend in time, exp(-k t / T) over the record's "
                 "duration T (k chosen in-fold)"
               : "baseline fitted with a linear trend in time",
      [&](int k) {
        const std::vector<char> train = ctx.train_mask(k);
        double beta = 0.0, rate = 0.0;
        std::vector<double> pred;
        if (!settling) {
          pred = fit_with_regressor(ctx, train, x, beta);
        } else {
          const std::vector<double>& base = ctx.by_fold[static_cast<std::size_t>(k)].pred;
          std::vector<double> r(rec.size());
          for (std::size_t t = 0; t < rec.size(); ++t) r[t] = rec.y[t] - base[t];
          double best = std::numeric_limits<double>::infinity();
          for (double candidate : kSettlingRates) {
            LineSums line;
            for (std::size_t t = 0; t < rec.size(); ++t) {
              if (train[t]) line.add(std::exp(-candidate * x(t)), r[t]);
            }
            const double sse = line.sse();
            if (sse < best) {
              best = sse;
              rate = candidate;
            }
          }
          pred = fit_with_regressor(
              ctx, train, [&](std::size_t t) { return std::exp(-rate * x(t)); }, beta);
          beta *= std::exp(-rate) - 1.0;  // the trend's change over the record
        }
        trends += fmt::format("{}{:.3g}{}", trends.empty() ? "" : ", ", 100.0 * beta / rec.range,
                              settling ? fmt::format(" (k {:g})", rate) : "");
        trend_sum += beta;
        return pred;
      },
      settling ? "a settling trend in time fitted with the baseline (backfitted)"
               : "a linear trend in time fitted with the baseline (backfitted)");
  f.extended_model += " (trend over the record per fold, % of range: " + trends + ")";
  const double trend = std::abs(trend_sum) / rec.folds;
  f.detected =
      f.p_value < ctx.opt.alpha && f.gain_pct >= ctx.opt.min_gain_pct && trend >= ctx.noise_sd;
  f.evidence += fmt::format("; the trend over the record {:.2f} % of range, the noise {:.2f} %",
                            100.0 * trend / rec.range, 100.0 * ctx.noise_sd / rec.range);
  return f;
}

// The trend in the training residuals: each fold baseline's residuals on its training rows
// regressed on a line in time, the slope's t (white-noise standard error), averaged over the
// folds.
double training_trend_t(const Context& ctx) {
  const Record& rec = ctx.rec;
  const double t0 = rec.time.front(), t1 = std::max(rec.time.back(), t0 + 1e-300);
  double sum = 0.0;
  for (int k = 0; k < rec.folds; ++k) {
    const FoldFit& fit = ctx.by_fold[static_cast<std::size_t>(k)];
    LineSums line;
    for (std::size_t t = 0; t < rec.size(); ++t) {
      if (rec.trains(t, k)) line.add((rec.time[t] - t0) / (t1 - t0), rec.y[t] - fit.pred[t]);
    }
    const double vxx = line.n > 2.0 ? line.sxx - line.sx * line.sx / line.n : 0.0;
    if (!(vxx > 0.0)) continue;
    const double se = std::sqrt(line.sse() / (line.n - 2.0) / vxx);
    if (se > 0.0) sum += line.slope() / se;
  }
  return sum / std::max(rec.folds, 1);
}

}  // namespace

Finding detect_drift(Context& ctx) {
  const Record& rec = ctx.rec;
  // Readings in one memory state within a segment that differ with the time between them.
  const Signature& sig = ctx.return_point.time;
  const double t0 = rec.time.front(), t1 = std::max(rec.time.back(), t0 + 1e-300);
  // Load tests: one trend over the record. Tests held out by load segment: the drift lives in
  // the offset map, and when the loads were tested in the order of their size the map's trend
  // is a function of the load, which f1 absorbs; the drift inside each segment remains (a trend
  // about the segment's mean time, one slope for all). The one that gains more is reported.
  const bool by_segment = rec.several_loads && rec.fold_kind == "load segments";
  Finding map;
  if (by_segment) map = drift_in_offset_map(ctx);
  std::vector<double> origin(rec.seg_first.size(), t0);  // each segment's time origin
  if (by_segment) origin = segment_mean_times(rec);
  // Powers 1 .. degree of the time since each segment's origin, in units of the record.
  const auto powers_of_time = [&](int degree) {
    return [&rec, &origin, t0, t1, degree](const FoldFit&) {
      Eigen::MatrixXd X(static_cast<Eigen::Index>(rec.size()), degree);
      for (std::size_t t = 0; t < rec.size(); ++t) {
        const double x = (rec.time[t] - origin[static_cast<std::size_t>(rec.seg[t])]) / (t1 - t0);
        double power = 1.0;
        for (Eigen::Index j = 0; j < degree; ++j) X(static_cast<Eigen::Index>(t), j) = power *= x;
      }
      return X;
    };
  };
  Signature line_signature;
  Finding f = feature_finding(
      ctx, "drift",
      by_segment ? "augmented baseline + linear trend in time within each load segment"
                 : "baseline + linear trend in time",
      powers_of_time(1),
      by_segment ? "a trend in time within each load segment" : "a linear trend in time",
      &line_signature);
  // Whether the reported extension sizes the drift inside the segments (the line about each
  // segment's mean time, or drift_sized_within_segments), which no map of the load can do.
  bool within_segments = by_segment;
  if (by_segment && !(f.gain_pct > map.gain_pct)) {
    f = map;
    within_segments = false;
  }
  // The drift sized inside the training segments (drift_sized_within_segments) where it gains
  // more than both (session 49); its sign-flip test on a stream of its own, so the detectors
  // after it keep their p-values.
  if (by_segment) {
    std::optional<Finding> sized;
    {
      const OwnStream own(ctx, 17);
      sized = drift_sized_within_segments(ctx);
    }
    if (sized && sized->gain_pct > f.gain_pct) {
      f = std::move(*sized);
      within_segments = true;
    }
  }
  ctx.drift_within_segments = within_segments && f.detected;
  if (!by_segment) {
    // Records held out by cycles (load tests; tests at one to three loads): a trend that turns
    // or settles as well (PHYSICS.md section 5, "low-order trend in time"). A line fitted on the
    // folds around a held-out block mispredicts a drift that rises and falls back: a
    // fourth-generator half-sine swing at a 0.04 mm step (seed 4102) gained -37.6 % with a
    // line, 25.6 % with the quadratic. Reported where it is detected and gains more than the line;
    // its permutation test draws from a stream of its own, so the detectors after it keep their
    // p-values. Measured (session 47): the 100 load records of the five independent generators'
    // standing sets, load drifts 17/20 -> 19/20 and no other name changed; fresh load drifts (seeds
    // 4600-4609) 39/50 -> 40/50; fresh load creeps 22/40 and 100 fresh clean load records as
    // before; the rig's load cells as before; the seven voltage records of three loads in those
    // sets as before.
    {
      const OwnStream own(ctx, 13);
      Finding curved = feature_finding(ctx, "drift", "baseline + quadratic trend in time",
                                       powers_of_time(2), "a quadratic trend in time");
      if (curved.detected && !(f.detected && f.gain_pct >= curved.gain_pct)) f = std::move(curved);
    }
    // The line fitted with the baseline: where the two-stage trend is detected, or where its
    // signature (the line's share of the held-out residual variance) is at alpha though the
    // two-stage extension gains too little: the baseline refitted in each fold takes up part
    // of a drift, so the trend left in the training residuals undersizes it (session 57: six
    // third- and fifth-generator drifts, the signature at p = 0.001-0.008, the two-stage trend
    // gaining 2.6-9.3 %, under 5 % or not at gain_alpha, the line fitted with the baseline
    // 23-71 % at p <= 0.007; none of 597 clean records changed). Reported where detected and
    // it gains more. It also takes up a baseline's misfit that follows the protocol and so time: a
    // clean third-generator record, a damped protocol whose turning points rise through the record,
    // gained 18.7 % at p = 0.001, its trend 1.15 % of the range against 0.45 % noise (the two-stage
    // trend 1.6 %); most of its held-out readings are guesses, and the training residuals' trend
    // below keeps it `none` (t = 1.53, p = 0.063). Fitted only there: five more baseline fits per
    // fold. And a drift that settles (a warm-up) fitted as one, exp(-k t / T)
    // (trend_fitted_with_baseline), kept where detected and gaining more than the line: a line
    // takes up a warm-up only in part, and a Kelvin element relaxing over the record takes up
    // more of it (session 53: fresh fourth-generator drift 5602, the line 35.9 %, the element
    // 54.2 %, the settling trend 55.1 %). Only where readings in one memory state differ with
    // time (the return-point time signature at alpha): without it a fast exp(-k t / T) takes up
    // a Kelvin element relaxing from the record's start
    // (CreepMuchSlowerThanTheHoldsReadDuringHolds). Where that signature is not available (no
    // memory state met twice, a decaying sine), where the line's signature is at gain_alpha
    // (session 62: a fresh fifth-generator warm-up of 9.9 %, seed 8217, line signature p = 0.024,
    // the settling trend gaining 17.1 % at p = 0.001; on 540 fresh load records of clean data,
    // creep and non-congruence no name changed). Load tests only: at one to three loads held out
    // by cycles it was not measured. The measurements are in the log, "Session 53".
    const bool try_settling =
        rec.input_is_load &&
        (sig.available ? sig.p_value < ctx.opt.alpha : line_signature.p_value < ctx.opt.gain_alpha);
    const bool fit_line = f.detected || line_signature.p_value < ctx.opt.alpha;
    if (fit_line || try_settling) {
      Finding joint;
      if (fit_line) joint = trend_fitted_with_baseline(ctx, TrendShape::kLine);
      if (try_settling) {
        Finding settled = trend_fitted_with_baseline(ctx, TrendShape::kSettling);
        if (settled.detected && !(joint.detected && joint.gain_pct >= settled.gain_pct))
          joint = std::move(settled);
      }
      if (joint.detected && joint.gain_pct > f.gain_pct) {
        joint.evidence = f.evidence + "; " + joint.evidence;
        f = std::move(joint);
      }
    }
  }
  // A drift is in the readings the baseline is fitted to as well, so the trend is named only
  // where the training residuals carry it too: their slope in time (training_trend_t),
  // one-sided in the direction of the extension's correction, at gain_alpha.
  // - Since session 56 where fewer than half the held-out readings are identified: the held-out
  //   gain is then measured on the baseline's guesses, whose errors follow the protocol and so
  //   time. Two clean third-generator load records of random turning points (4 and 8 readings
  //   identified) were named `drift` on gains of 5.7 and 5.2 %, with t of 1.36 and -1.09
  //   (p = 0.086, 0.139). On the 76 load records of drift and clean data of the five
  //   generators' sets with fewer than half identified, the other clean ones had t of -1.31 to
  //   1.46, the drifts named `drift` 2.57-5.49. On 130 fresh load drift, clean and creep
  //   records (19 third-generator drifts with under half identified, t 1.76-7.16) no name
  //   changed.
  // - Since session 87 everywhere: under correlated sensor noise the held-out residuals carry
  //   offsets constant over each fold that follow the protocol, and a trend takes them up on
  //   held-out cycles (clean first-generator load records under AR(1) noise of rho 0.7, seeds
  //   98400-98459: 7 of 60 named `drift`, gains 4-11 % at sign-flip p 0.001-0.049; two had t of
  //   1.02 and 0.49). The 29 load drifts of the fresh set (seeds 98000-98007) named `drift` had
  //   t of 2.1 or more in size (p <= 0.018), 24 of them beyond 4.5.
  if (f.detected && !rec.several_loads && f.heldout_prediction.size() == rec.size()) {
    const double t = training_trend_t(ctx);
    LineSums correction;
    for (std::size_t i : ctx.scored)
      correction.add(rec.time[i], f.heldout_prediction[i] - ctx.oof[i]);
    const double dir = correction.slope() >= 0.0 ? 1.0 : -1.0;
    const double p = 0.5 * std::erfc(dir * t / std::sqrt(2.0));
    const bool guesses = 2 * identified_scored(ctx).size() < ctx.scored.size();
    f.evidence += fmt::format(
        "; {}the training residuals' trend in time has t = {:.2f} (one-sided p = {:.3f})",
        guesses ? "most held-out readings are guesses (memory not identified by training), and "
                : "",
        t, p);
    if (!(p < ctx.opt.gain_alpha)) f.detected = false;
  }
  if (sig.available) {
    f.evidence += "; " + describe(sig);
    // Readings in the same state that drift apart with time are a drift whatever the model:
    // beyond alpha / 10 with any gain, at alpha with a gain above 1 % (the outliers' tiers).
    // At alpha alone about one clean record in a hundred passes, as the test is calibrated:
    // on 276 clean records of both independent generators two came below 0.01 (p = 0.0064,
    // 0.0088), the first named `drift` on a gain of 0.6 % (and in session 17 another, p =
    // 0.0029, gain 0.4 %), while the trend's gain reached 1 % on 16 of the 276. Of 165 drift
    // records, the one this loses (p = 0.0056, a 6 % drift gaining 0.8 %) is the only one
    // named by the signature between alpha / 10 and alpha on a gain of 1 % or less. At alpha the
    // gain must also hold at gain_alpha (the intersection-union the other signatures use;
    // session 77): over 2 200 clean load records two third-generator ones under AR(1) noise
    // passed the signature at p = 0.0012 and 0.007 on gains of 1.1 and 2.1 % at p = 0.21, and of
    // 265 kept records with the drift detected one true drift was lost (a second-generator
    // drift, signature p = 0.0033, gain 8.3 % at p = 0.11); on 350 fresh records (clean, drift;
    // seeds 97000-97129) no cause changed. Not at several loads: there each segment's free
    // offset takes up most of a drift, so its extension can gain little while the signature
    // stands (the rig's voltage drift of 0.12 at seven loads in increasing order, seed 1049:
    // signature p = 0.0012, the trend within the segments gaining 1.8 % at p = 0.061, from a
    // held-out E_RMS of 0.109 % of range; test VoltageDriftInLoadOrderAndSpikesAnywhere).
    const bool gain_holds = rec.several_loads || f.p_value < ctx.opt.gain_alpha;
    if ((sig.p_value < ctx.opt.alpha / 10.0 && f.gain_pct > 0.0) ||
        (sig.p_value < ctx.opt.alpha && f.gain_pct > kSignatureGainPct && gain_holds))
      f.detected = true;
  }
  return f;
}

}  // namespace scpkit::diagnosis
