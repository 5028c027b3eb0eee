#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

#include "detectors.hpp"
#include "scpkit/error.hpp"
#include "stats.hpp"

namespace scpkit::diagnosis {

// A model-free signature's verdict in words.
std::string describe(const Signature& s) {
  return fmt::format("{} differ by {:.3g} (z = {:.1f}, p = {:.2g}, {} comparisons)", s.what,
                     s.estimate, s.z, s.p_value, s.units);
}

namespace {

// A tested finding's held-out numbers and verdict from its score.
void record(Finding& f, const Context& ctx, const Score& s, double p_value) {
  f.tested = true;
  f.p_value = p_value;
  f.heldout_rms_before = ctx.rms_before;
  f.heldout_rms_after = s.rms_after;
  f.gain_pct = s.gain_pct;
  f.detected = f.p_value < ctx.opt.alpha && f.gain_pct >= least_gain_pct(ctx.opt, f.effect);
}

// Whether an extension's `heldout_prediction` takes row t from fold k's fit: held out in k,
// or never held out and k the first fold (in sample, as the outliers' screen reads the
// baseline's residuals there).
bool predicted_by(const Record& rec, std::size_t t, int k) {
  return rec.fold[t] == k || (k == 0 && rec.fold[t] == Record::kAlwaysTrained);
}

}  // namespace

std::vector<std::size_t> identified_scored(const Context& ctx) {
  std::vector<std::size_t> rows;
  for (std::size_t t : ctx.scored) {
    if (ctx.identified[t]) rows.push_back(t);
  }
  return rows;
}

std::string on_identified_readings(std::size_t count) {
  return fmt::format("on the {} held-out readings whose memory their training identified", count);
}

Score heldout_gain(const Context& ctx, const std::vector<double>& after,
                   const std::vector<char>& use, std::vector<double>* block_gains) {
  Score s;
  double ss_before = 0.0, ss_after = 0.0;
  for (const auto& block : ctx.blocks) {
    double g = 0.0;
    for (std::size_t t : block) {
      if (!use.empty() && !use[t]) continue;
      const double e = ctx.rec.y[t] - after[t];
      ss_before += ctx.r[t] * ctx.r[t];
      ss_after += e * e;
      g += ctx.r[t] * ctx.r[t] - e * e;
      ++s.count;
    }
    if (block_gains) block_gains->push_back(g);
  }
  if (s.count == 0) return s;
  const double before = std::sqrt(ss_before / static_cast<double>(s.count));
  s.rms_before = 100.0 * before / ctx.rec.range;
  s.rms_after = 100.0 * std::sqrt(ss_after / static_cast<double>(s.count)) / ctx.rec.range;
  s.gain_pct = before > 0.0 ? 100.0 * (1.0 - std::sqrt(ss_after / ss_before)) : 0.0;
  return s;
}

Score score(Context& ctx, const std::vector<double>& after, const std::vector<char>& use,
            std::mt19937_64* rng) {
  std::vector<double> gains;
  Score s = heldout_gain(ctx, after, use, &gains);
  if (s.count == 0) return s;
  s.p_value = sign_flip_p(gains, ctx.opt.permutations, rng ? *rng : ctx.rng);
  return s;
}

namespace {

/// The largest lag-one noise correlation the floor allows for: at 0.8 the floor is 2.24 times
/// the first differences' spread. A ratio of spreads that reads higher is mostly the residuals'
/// structure: on the held-out residuals of 1308 kept records of the three independent
/// generators it reads beyond 1, which no stationary noise gives, on 4-24 % of each truth's.
constexpr double kMaxNoiseCorrelation = 0.8;

// The noise's lag-one correlation from its variogram. For AR(1) noise of variance s2,
// E (e_t - e_{t-k})^2 = 2 s2 (1 - rho^k): the squared spread of the differences two readings
// apart over that of consecutive ones is 1 + rho (white noise: 1), and the first differences'
// spread, from which `white` is taken, is s2 (1 - rho). Smooth structure in the residuals adds
// four times as much to the second differences as to the first, so the ratio overstates rho
// where the residuals carry structure; the diagnosis takes it on the held-out residuals and on
// the folds' training residuals (whose fit took up part of the structure). Measured on the
// held-out residuals of 212 third-generator records whose noise is known (10-90 %): white noise
// 0.00-0.49, AR(1) at rho 0.6 0.26-0.80; docs/diagnose-log.md, session 31.
double spread_ratio_correlation(const std::vector<double>& d1, const std::vector<double>& d2) {
  if (d1.size() < 10 || d2.size() < 10) return 0.0;
  const double s1 = mad(d1);
  if (!(s1 > 0.0)) return 0.0;
  const double ratio = mad(d2) / s1;
  const double rho = ratio * ratio - 1.0;
  // Beyond 1 no stationary noise gives it: the differences are the residuals' structure, and
  // the first differences' spread overstates the noise already.
  if (rho > 1.0) return 0.0;
  return std::clamp(rho, 0.0, kMaxNoiseCorrelation);
}

/// Differences of the held-out residuals `lag` readings apart, where every reading between is
/// scored too.
std::vector<double> heldout_differences(const Context& ctx, std::size_t lag) {
  std::vector<double> d;
  const std::vector<std::size_t>& s = ctx.scored;
  for (std::size_t i = lag; i < s.size(); ++i) {
    if (s[i - lag] + lag == s[i]) d.push_back(ctx.r[s[i]] - ctx.r[s[i] - lag]);
  }
  return d;
}

double training_noise_correlation(const Context& ctx) {
  const Record& rec = ctx.rec;
  std::vector<double> d1, d2;
  for (int k = 0; k < rec.folds; ++k) {
    const std::vector<double>& p = ctx.by_fold[static_cast<std::size_t>(k)].pred;
    auto e = [&](std::size_t t) { return rec.y[t] - p[t]; };
    auto run = [&](std::size_t t, std::size_t lag) {
      for (std::size_t j = 0; j <= lag; ++j) {
        if (!rec.trains(t - j, k) || rec.seg[t - j] != rec.seg[t]) return false;
      }
      return true;
    };
    for (std::size_t t = 1; t < rec.size(); ++t) {
      if (run(t, 1)) d1.push_back(e(t) - e(t - 1));
      if (t >= 2 && run(t, 2)) d2.push_back(e(t) - e(t - 2));
    }
  }
  return spread_ratio_correlation(d1, d2);
}

}  // namespace

Context::Context(const Record& record, const Baseline& b, const DiagnoseOptions& o)
    : rec(record), base(b), opt(o), rng(o.seed) {
  const std::size_t n = rec.size();
  for (int k = 0; k < rec.folds; ++k) by_fold.push_back(base.fit(train_mask(k)));
  // A held-out reading whose operator memory holds an input beyond every input its fold
  // trained on is an extrapolation of the plane, not a test of the model: not scored. Once an
  // input leaves the training range its turning point stays in the memory (only a further
  // excursion wipes it out), so that is every later reading of the segment. Measured: a damped
  // protocol's final return to the lowest load, met nowhere else after the first rise, was
  // predicted 250 % of the range off and named `outliers`; a damped voltage oscillation at one
  // load, its first peak held out, 564 %.
  std::vector<double> lo(static_cast<std::size_t>(rec.folds), HUGE_VAL),
      hi(static_cast<std::size_t>(rec.folds), -HUGE_VAL);
  for (std::size_t t = 0; t < n; ++t) {
    for (int k = 0; k < rec.folds; ++k) {
      if (!rec.trains(t, k)) continue;
      lo[static_cast<std::size_t>(k)] = std::min(lo[static_cast<std::size_t>(k)], rec.u[t]);
      hi[static_cast<std::size_t>(k)] = std::max(hi[static_cast<std::size_t>(k)], rec.u[t]);
    }
  }
  const auto [umin, umax] = std::minmax_element(rec.u.begin(), rec.u.end());
  const double tol = 1e-9 * (*umax - *umin);
  oof.assign(n, 0.0);
  r.assign(n, 0.0);
  // The input's extremes so far in this segment. The memory starts at negative saturation: the
  // first reading switches hysterons up to its input (an excursion when above the training
  // range) but none down, so it is no excursion below the range.
  double seen_lo = HUGE_VAL, seen_hi = -HUGE_VAL;
  for (std::size_t t = 0; t < n; ++t) {
    const bool start = t == 0 || rec.seg[t] != rec.seg[t - 1];
    if (start) seen_lo = HUGE_VAL;
    if (!start) seen_lo = std::min(seen_lo, rec.u[t]);
    seen_hi = start ? rec.u[t] : std::max(seen_hi, rec.u[t]);
    if (rec.fold[t] < 0) continue;
    const auto k = static_cast<std::size_t>(rec.fold[t]);
    if (seen_lo < lo[k] - tol || seen_hi > hi[k] + tol) continue;
    oof[t] = by_fold[k].pred[t];
    r[t] = rec.y[t] - oof[t];
    scored.push_back(t);
  }
  if (scored.size() < 20) {
    throw TooFewHeldOut(fmt::format(
        "only {} held-out readings lie within the inputs their folds trained on (need >= 20): "
        "the record's extreme inputs occur in one cycle only",
        scored.size()));
  }
  // Blocks: runs of consecutive scored readings of one fold, cut to about 1/24 of the total.
  const std::size_t len = std::max<std::size_t>(4, scored.size() / 24);
  for (std::size_t i = 0; i < scored.size(); ++i) {
    const std::size_t t = scored[i];
    const bool cont = i > 0 && scored[i - 1] + 1 == t && rec.fold[t] == rec.fold[t - 1] &&
                      blocks.back().size() < len;
    if (!cont) blocks.emplace_back();
    blocks.back().push_back(t);
  }
  std::vector<double> rs;
  for (std::size_t t : scored) rs.push_back(r[t]);
  const std::vector<double> dr = heldout_differences(*this, 1);
  white = dr.size() >= 10 ? mad(dr) / std::sqrt(2.0) : mad(rs);
  resolution = quantisation_step(rec.y);
  // The noise of one reading, its white part's lag-one correlation `rho` allowed for.
  auto noise = [&](double rho) {
    return std::sqrt(white * white / (1.0 - rho) + resolution * resolution / 12.0);
  };
  floor = noise(0.0);
  // The mean of the two estimates: either can miss by 0.5 or more on one record, the held-out
  // one reading structure as correlation, the training one missing the noise's slow part. The
  // smaller left the floor low under AR(1) noise, the larger hid a knee the maps miss
  // (docs/diagnose-log.md, sessions 77 and 78).
  noise_rho = 0.5 * (spread_ratio_correlation(dr, heldout_differences(*this, 2)) +
                     training_noise_correlation(*this));
  noise_sd = noise(noise_rho);
  rms_before = 100.0 * rms(rs) / rec.range;
  // The return-point signatures' pairs show the noise's correlation only where cycles repeat
  // reading for reading (signatures.cpp, ar1_difference_cov); elsewhere the floor's stands in.
  return_point = return_point_signatures(rec, floor, noise_rho);
  const CongruencySignatures loops = congruency_signatures(rec);
  congruency = loops.raw;
  congruency_robust = loops.robust;
  holds = hold_signature(rec, floor);
  identified = identified_readings(rec, base.options().levels);
}

std::vector<char> Context::train_mask(int fold) const {
  std::vector<char> m(rec.size());
  for (std::size_t t = 0; t < rec.size(); ++t) m[t] = rec.trains(t, fold) ? 1 : 0;
  return m;
}

Finding not_tested(const Context& ctx, const std::string& effect, const std::string& why) {
  Finding f;
  f.effect = effect;
  f.evidence = why;
  f.heldout_rms_before = f.heldout_rms_after = ctx.rms_before;
  return f;
}

Finding feature_finding(Context& ctx, const std::string& effect, const std::string& extension,
                        const Features& features, const std::string& what, Signature* signature) {
  const Record& rec = ctx.rec;
  Finding f;
  f.effect = effect;
  f.extended_model = extension;
  std::vector<Eigen::MatrixXd> X;
  for (const FoldFit& fit : ctx.by_fold) X.push_back(features(fit));
  const Eigen::Index m = X.front().cols();
  // Signature on the out-of-fold residuals.
  Eigen::VectorXd rs(static_cast<Eigen::Index>(ctx.scored.size()));
  Eigen::MatrixXd Xs(rs.size(), m);
  for (std::size_t i = 0; i < ctx.scored.size(); ++i) {
    const std::size_t t = ctx.scored[i];
    rs[static_cast<Eigen::Index>(i)] = ctx.r[t];
    Xs.row(static_cast<Eigen::Index>(i)) =
        X[static_cast<std::size_t>(rec.fold[t])].row(static_cast<Eigen::Index>(t));
  }
  f.score = r_squared(rs, Xs);
  const std::size_t block = std::max<std::size_t>(4, ctx.scored.size() / 24);
  const double p_signature =
      block_permutation_p(rs, Xs, f.score, block, ctx.opt.permutations, ctx.rng);
  // At the floor of its permutations the signature's p-value is taken again on ten times as
  // many, and that is the one the cause is named by (name_by_signature) and the evidence shows.
  const bool refined = signature && p_signature * (ctx.opt.permutations + 1) < 1.5;
  const int refined_permutations = 10 * ctx.opt.permutations;
  if (signature) {
    signature->available = true;
    signature->what = what;
    signature->estimate = f.score;
    signature->units = static_cast<int>(rs.size() / static_cast<Eigen::Index>(block));
    signature->p_value = p_signature;
    if (refined) {
      std::mt19937_64 own(ctx.opt.seed + 29);
      signature->p_value = block_permutation_p(rs, Xs, f.score, block, refined_permutations, own);
    }
  }
  // The extension, fitted on each fold's training rows.
  std::vector<double> after(ctx.oof);
  for (int k = 0; k < rec.folds; ++k) {
    const FoldFit& fit = ctx.by_fold[static_cast<std::size_t>(k)];
    const Eigen::MatrixXd& Xk = X[static_cast<std::size_t>(k)];
    std::vector<Eigen::Index> train;
    for (std::size_t t = 0; t < rec.size(); ++t) {
      if (rec.trains(t, k)) train.push_back(static_cast<Eigen::Index>(t));
    }
    Eigen::MatrixXd A(static_cast<Eigen::Index>(train.size()), m + 1);
    Eigen::VectorXd b(A.rows());
    for (Eigen::Index i = 0; i < A.rows(); ++i) {
      const Eigen::Index t = train[static_cast<std::size_t>(i)];
      A(i, 0) = 1.0;
      A.row(i).tail(m) = Xk.row(t);
      b[i] = rec.y[static_cast<std::size_t>(t)] - fit.pred[static_cast<std::size_t>(t)];
    }
    // A feature that does not vary on the training rows carries no information there.
    std::vector<bool> dead(static_cast<std::size_t>(m + 1), false);
    for (Eigen::Index c = 1; c <= m; ++c) {
      const double mean = A.col(c).mean();
      if ((A.col(c).array() - mean).abs().maxCoeff() < 1e-12) {
        A.col(c).setZero();
        dead[static_cast<std::size_t>(c)] = true;
      }
    }
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
    qr.setThreshold(1e-10);
    Eigen::VectorXd beta = qr.solve(b);
    for (Eigen::Index c = 1; c <= m; ++c) {
      if (dead[static_cast<std::size_t>(c)]) beta[c] = 0.0;
    }
    for (std::size_t t = 0; t < rec.size(); ++t) {
      if (!predicted_by(rec, t, k)) continue;
      after[t] = fit.pred[t] + beta[0] + Xk.row(static_cast<Eigen::Index>(t)).dot(beta.tail(m));
    }
  }
  const Score s = score(ctx, after);
  f.heldout_prediction = std::move(after);
  record(f, ctx, s, std::max(p_signature, s.p_value));
  f.detected = p_signature < ctx.opt.alpha && s.p_value < ctx.opt.gain_alpha &&
               f.gain_pct >= ctx.opt.min_gain_pct;
  const std::string p_shown =
      refined ? fmt::format("{:.4g} over {} permutations", signature->p_value, refined_permutations)
              : fmt::format("{:.3f}", p_signature);
  f.evidence = fmt::format(
      "{} explains {:.0f} % of the held-out residual variance (block-permutation p = {}); "
      "the extension changes held-out E_RMS from {:.3f} to {:.3f} % of range (sign-flip p = "
      "{:.3f})",
      what, 100.0 * f.score, p_shown, f.heldout_rms_before, f.heldout_rms_after, s.p_value);
  return f;
}

std::vector<double> fit_with_regressor(const Context& ctx, const std::vector<char>& train,
                                       const std::function<double(std::size_t)>& g, double& beta) {
  const Record& rec = ctx.rec;
  // (c, beta) on the training rows of y - prediction.
  auto regress = [&](const std::vector<double>& pred) {
    LineSums line;
    for (std::size_t t = 0; t < rec.size(); ++t) {
      if (train[t]) line.add(g(t), rec.y[t] - pred[t]);
    }
    const double slope = line.slope();
    return std::pair{line.intercept(slope), slope};
  };
  std::vector<double> w(rec.size());
  auto refit = [&](double c, double b, bool quick) {
    for (std::size_t t = 0; t < rec.size(); ++t) w[t] = rec.y[t] - c - b * g(t);
    return ctx.base.fit(train, {{}, &w, quick}).pred;
  };
  std::vector<double> pred = refit(0.0, 0.0, true);
  double c = 0.0, b[3];
  for (double& bk : b) {
    std::tie(c, bk) = regress(pred);
    pred = refit(c, bk, true);
  }
  beta = b[2];
  const double rho = (b[2] - b[1]) / (b[1] - b[0]);
  if (std::isfinite(rho) && rho > 0.0 && rho < 0.95) beta = b[1] + (b[2] - b[1]) / (1.0 - rho);
  pred = refit(c, beta, false);
  // The offset again, with the baseline's own level settled.
  double n = 0.0, offset = 0.0;
  for (std::size_t t = 0; t < rec.size(); ++t) {
    if (!train[t]) continue;
    n += 1.0;
    offset += rec.y[t] - pred[t] - beta * g(t);
  }
  c = offset / n;
  for (std::size_t t = 0; t < rec.size(); ++t) pred[t] += c + beta * g(t);
  return pred;
}

Finding model_finding(Context& ctx, const std::string& effect, const std::string& extension,
                      const std::function<std::vector<double>(int fold)>& fold_prediction,
                      const std::string& what, const std::vector<char>& use) {
  const Record& rec = ctx.rec;
  Finding f;
  f.effect = effect;
  f.extended_model = extension;
  std::vector<double> after(ctx.oof);
  for (int k = 0; k < rec.folds; ++k) {
    const std::vector<double> p = fold_prediction(k);
    for (std::size_t t = 0; t < rec.size(); ++t) {
      if (predicted_by(rec, t, k)) after[t] = p[t];
    }
  }
  const Score s = score(ctx, after, use);
  f.heldout_prediction = std::move(after);
  record(f, ctx, s, s.p_value);
  f.score = f.gain_pct;
  std::string on;
  if (!use.empty()) {
    f.on_identified = true;
    f.heldout_rms_before = s.rms_before;
    on = fmt::format(" {}", on_identified_readings(s.count));
  }
  f.evidence = fmt::format(
      "{}: held-out E_RMS{} from {:.3f} to {:.3f} % of range (sign-flip p = {:.3f} over {} "
      "blocks)",
      what, on, f.heldout_rms_before, f.heldout_rms_after, s.p_value, ctx.blocks.size());
  return f;
}

}  // namespace scpkit::diagnosis
