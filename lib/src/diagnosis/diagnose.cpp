#include "scpkit/diagnosis/diagnose.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <random>

#include "scpkit/error.hpp"
#include "scpkit/identification/preisach_fit.hpp"

namespace scpkit {
namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

double mad(const std::vector<double>& v) {
  const double m = median(v);
  std::vector<double> d;
  for (double x : v) d.push_back(std::abs(x - m));
  return 1.4826 * median(d);
}

double rms(const std::vector<double>& e) {
  double s = 0.0;
  for (double x : e) s += x * x;
  return e.empty() ? 0.0 : std::sqrt(s / static_cast<double>(e.size()));
}

// Quantisation step of a signal: the smallest gap between distinct values, when nearly every
// gap is a whole multiple of it; 0 when the signal is not quantised.
double quantisation_step(std::span<const double> y) {
  std::vector<double> v(y.begin(), y.end());
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  if (v.size() < 3) return 0.0;
  double q = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < v.size(); ++i) q = std::min(q, v[i] - v[i - 1]);
  int whole = 0;
  for (std::size_t i = 1; i < v.size(); ++i) {
    const double k = (v[i] - v[i - 1]) / q;
    whole += std::abs(k - std::round(k)) < 0.05 ? 1 : 0;
  }
  return whole >= 0.9 * static_cast<double>(v.size() - 1) ? q : 0.0;
}

// R^2 of a least-squares regression of r on [1, X].
double r_squared(const std::vector<double>& r, const Eigen::MatrixXd& X) {
  const auto n = static_cast<Eigen::Index>(r.size());
  Eigen::MatrixXd A(n, X.cols() + 1);
  A.col(0).setOnes();
  A.rightCols(X.cols()) = X;
  const Eigen::Map<const Eigen::VectorXd> y(r.data(), n);
  const Eigen::VectorXd beta = A.colPivHouseholderQr().solve(y);
  const double ss_res = (y - A * beta).squaredNorm();
  const double mean = y.mean();
  const double ss_tot = (y.array() - mean).square().sum();
  return ss_tot > 0.0 ? 1.0 - ss_res / ss_tot : 0.0;
}

// Block permutation: contiguous blocks of r shuffled as units (keeps their autocorrelation).
std::vector<double> block_permuted(const std::vector<double>& r, std::size_t block,
                                   std::mt19937_64& rng) {
  std::vector<std::size_t> starts;
  for (std::size_t s = 0; s < r.size(); s += block) starts.push_back(s);
  std::shuffle(starts.begin(), starts.end(), rng);
  std::vector<double> out;
  out.reserve(r.size());
  for (std::size_t s : starts) {
    for (std::size_t t = s; t < std::min(s + block, r.size()); ++t) out.push_back(r[t]);
  }
  return out;
}

struct Folds {
  std::vector<int> of;  // fold of each row
  int count = 0;
};

struct Baseline {
  PreisachFitOptions options;          // L and lambda chosen once, then fixed
  std::vector<std::vector<double>> p;  // p[k][t]: prediction by the model fitted without fold k
  std::vector<double> oof;             // out-of-fold prediction
};

std::vector<double> fit_and_predict(std::span<const double> u, std::span<const double> y,
                                    const std::vector<int>& blocks, PreisachFitOptions o,
                                    const std::vector<char>& exclude) {
  o.exclude = exclude;
  const PreisachFit f = fit_preisach(u, y, blocks, o);
  PreisachState s = PreisachState::negative_saturation(f.model.grid());
  const Eigen::VectorXd p = f.model.simulate(s, u);
  return {p.data(), p.data() + p.size()};
}

}  // namespace

Diagnosis diagnose(std::span<const double> time_in, std::span<const double> u,
                   std::span<const double> y, std::span<const int> blocks,
                   const DiagnoseOptions& opt) {
  const std::size_t n = u.size();
  if (y.size() != n || (!time_in.empty() && time_in.size() != n) ||
      (!blocks.empty() && blocks.size() != n)) {
    throw_invalid("diagnose: sizes differ");
  }
  if (n < 40)
    throw IdentificationError(fmt::format("{} samples are too few to diagnose (need >= 40)", n));
  const auto [ymin, ymax] = std::minmax_element(y.begin(), y.end());
  const double range = *ymax - *ymin;
  if (!(range > 0.0)) throw IdentificationError("the response never changes: nothing to diagnose");
  std::vector<double> time(time_in.begin(), time_in.end());
  if (time.empty()) {
    for (std::size_t t = 0; t < n; ++t) time.push_back(static_cast<double>(t));
  }
  const double t0 = time.front(),
               t1 = time.back() > time.front() ? time.back() : time.front() + 1.0;

  // Folds: whole cycles (or the given segments), as in the identification's cross-validation.
  Folds folds;
  folds.of =
      blocks.empty() ? cycle_blocks(u, opt.folds) : std::vector<int>(blocks.begin(), blocks.end());
  {
    std::vector<int> ids(folds.of);
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    for (int& f : folds.of)
      f = static_cast<int>(std::lower_bound(ids.begin(), ids.end(), f) - ids.begin());
    folds.count = static_cast<int>(ids.size());
  }
  if (folds.count < 2)
    throw IdentificationError("diagnose needs at least two cycles or segments to hold out");

  // Baseline: L and lambda by cross-validation once, then fixed for the per-fold fits.
  Baseline base;
  {
    const PreisachFit full = fit_preisach(u, y, {}, opt.baseline);
    base.options.levels = full.summary.levels;
    base.options.smoothness = full.summary.smoothness;
    base.options.grid_shifts = full.summary.grid_shifts;
    base.options.sign = full.summary.sign;
    base.options.lo = full.input_min;
    base.options.hi = full.input_max;
  }
  base.p.resize(static_cast<std::size_t>(folds.count));
  base.oof.assign(n, 0.0);
  for (int k = 0; k < folds.count; ++k) {
    std::vector<char> ex(n, 0);
    for (std::size_t t = 0; t < n; ++t) ex[t] = folds.of[t] == k;
    base.p[k] = fit_and_predict(u, y, {}, base.options, ex);
    for (std::size_t t = 0; t < n; ++t) {
      if (folds.of[t] == k) base.oof[t] = base.p[k][t];
    }
  }
  std::vector<double> r(n);
  for (std::size_t t = 0; t < n; ++t) r[t] = y[t] - base.oof[t];

  Diagnosis d;
  d.rms_pct_range = 100.0 * rms(r) / range;
  double rmax = 0.0;
  for (double x : r) rmax = std::max(rmax, std::abs(x));
  d.max_pct_range = 100.0 * rmax / range;

  // Noise floor.
  std::vector<double> dr;
  for (std::size_t t = 1; t < n; ++t) dr.push_back(r[t] - r[t - 1]);
  const double sigma_white = mad(dr) / std::sqrt(2.0);
  const double q = quantisation_step(y);
  const double floor = std::sqrt(sigma_white * sigma_white + q * q / 12.0);
  d.noise_floor_pct_range = 100.0 * floor / range;

  std::mt19937_64 rng(opt.seed);
  const std::size_t block = std::max<std::size_t>(5, n / 20);

  // A feature-based detector: significance of R^2(r ~ X) against the block-permutation null,
  // and the held-out gain of the two-stage extension y = p_k + X beta_k (beta_k on fold k's
  // training rows).
  auto feature_finding = [&](const std::string& effect, const std::string& extension,
                             const std::function<Eigen::MatrixXd(const std::vector<double>& p)>&
                                 features,
                             const std::string& what) {
    Finding f;
    f.effect = effect;
    f.tested = true;
    f.extended_model = extension;
    const Eigen::MatrixXd X = features(base.oof);
    f.score = r_squared(r, X);
    int exceed = 0;
    for (int i = 0; i < opt.permutations; ++i)
      exceed += r_squared(block_permuted(r, block, rng), X) >= f.score ? 1 : 0;
    f.p_value = (1.0 + exceed) / (1.0 + opt.permutations);
    double ss_after = 0.0;
    for (int k = 0; k < folds.count; ++k) {
      const Eigen::MatrixXd Xk = features(base.p[k]);
      std::vector<Eigen::Index> train, test;
      for (std::size_t t = 0; t < n; ++t)
        (folds.of[t] == k ? test : train).push_back(static_cast<Eigen::Index>(t));
      Eigen::MatrixXd A(static_cast<Eigen::Index>(train.size()), Xk.cols() + 1);
      Eigen::VectorXd b(static_cast<Eigen::Index>(train.size()));
      for (std::size_t i = 0; i < train.size(); ++i) {
        A(static_cast<Eigen::Index>(i), 0) = 1.0;
        A.row(static_cast<Eigen::Index>(i)).tail(Xk.cols()) = Xk.row(train[i]);
        b[static_cast<Eigen::Index>(i)] = y[train[i]] - base.p[k][train[i]];
      }
      // Features that do not vary on the training rows carry no information there (e.g. the
      // running maximum after the first rise): they get no coefficient.
      for (Eigen::Index c = 1; c < A.cols(); ++c) {
        const double mean = A.col(c).mean();
        if ((A.col(c).array() - mean).abs().maxCoeff() < 1e-9) A.col(c).setZero();
      }
      Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
      qr.setThreshold(1e-10);
      Eigen::VectorXd beta = qr.solve(b);
      for (Eigen::Index c = 1; c < A.cols(); ++c) {
        if (A.col(c).isZero()) beta[c] = 0.0;
      }
      for (Eigen::Index t : test) {
        const double pred = base.p[k][t] + beta[0] + Xk.row(t).dot(beta.tail(Xk.cols()));
        ss_after += (y[t] - pred) * (y[t] - pred);
      }
    }
    f.heldout_rms_before = d.rms_pct_range;
    f.heldout_rms_after = 100.0 * std::sqrt(ss_after / static_cast<double>(n)) / range;
    f.gain_pct = 100.0 * (1.0 - f.heldout_rms_after / f.heldout_rms_before);
    f.detected = f.p_value < opt.alpha && f.gain_pct >= opt.min_gain_pct;
    f.evidence = fmt::format(
        "{} explains {:.0f} % of the held-out residual variance (block-permutation p = {:.3f}); "
        "the extension changes held-out E_RMS from {:.3f} to {:.3f} % of range",
        what, 100.0 * f.score, f.p_value, f.heldout_rms_before, f.heldout_rms_after);
    return f;
  };

  // drift: a trend in time, independent of the input.
  d.findings.push_back(feature_finding(
      "drift", "preisach + linear trend in time",
      [&](const std::vector<double>&) {
        Eigen::MatrixXd X(static_cast<Eigen::Index>(n), 1);
        for (std::size_t t = 0; t < n; ++t)
          X(static_cast<Eigen::Index>(t), 0) = (time[t] - t0) / (t1 - t0);
        return X;
      },
      "a linear trend in time"));
  // creep: readings lag each change of the (rate-independent) response.
  d.findings.push_back(feature_finding(
      "creep", "preisach + first-order lag of the response (Kelvin term)",
      [&](const std::vector<double>& p) {
        Eigen::MatrixXd X(static_cast<Eigen::Index>(n), 2);
        for (std::size_t t = 0; t < n; ++t) {
          const auto i = static_cast<Eigen::Index>(t);
          X(i, 0) = t >= 1 ? p[t] - p[t - 1] : 0.0;
          X(i, 1) = t >= 2 ? p[t - 1] - p[t - 2] : 0.0;
        }
        return X;
      },
      "the lag of the response behind its last two changes"));
  // lonely stroke: the first rise differs from every later cycle (running-maximum term).
  d.findings.push_back(feature_finding(
      "lonely_stroke", "preisach + running-maximum term (expanded plane, paper 001)",
      [&](const std::vector<double>&) {
        Eigen::MatrixXd X(static_cast<Eigen::Index>(n), 1);
        const auto [umin, umax] = std::minmax_element(u.begin(), u.end());
        double M = u.front();
        for (std::size_t t = 0; t < n; ++t) {
          M = std::max(M, u[t]);
          X(static_cast<Eigen::Index>(t), 0) = (M - *umin) / (*umax - *umin);
        }
        return X;
      },
      "the running maximum of the input (first rise against later cycles)"));

  // outliers: isolated residuals far beyond the noise; extension: refit without them.
  {
    Finding f;
    f.effect = "outliers";
    f.tested = true;
    f.extended_model = "preisach refitted without the flagged readings (robust fit)";
    // Isolated spikes: a reading far from both neighbours' mean, measured against the robust
    // scale of that same quantity (structured residuals, smooth in time, do not produce them).
    std::vector<double> spike(n, 0.0);
    for (std::size_t t = 0; t < n; ++t) {
      const double left = t > 0 ? r[t - 1] : r[t + 1], right = t + 1 < n ? r[t + 1] : r[t - 1];
      spike[t] = r[t] - 0.5 * (left + right);
    }
    const double med = median(spike);
    const double scale = std::max({mad(spike), floor, 1e-300});
    std::vector<char> flagged(n, 0);
    int count = 0;
    double zmax = 0.0;
    const double r_med = median(r), r_scale = std::max({mad(r), floor, 1e-300});
    for (std::size_t t = 0; t < n; ++t) {
      // Input reversals are left out: the model's error may legitimately kink there.
      const bool reversal = t > 0 && t + 1 < n && (u[t] - u[t - 1]) * (u[t + 1] - u[t]) <= 0.0;
      if (reversal) continue;
      const double z = std::abs(spike[t] - med) / scale;
      const double level = std::abs(r[t] - r_med) / r_scale;
      zmax = std::max(zmax, std::min(z, 1.6 * level));
      if (z > 8.0 && level > 5.0) {
        flagged[t] = 1;
        ++count;
      }
    }
    f.score = zmax;
    // Bonferroni-corrected Gaussian tail for the largest |z|.
    f.p_value = std::min(1.0, static_cast<double>(n) * std::erfc(zmax / std::sqrt(2.0)));
    if (count > 0) {
      double before = 0.0, after = 0.0;
      int inliers = 0;
      for (int k = 0; k < folds.count; ++k) {
        std::vector<char> ex(n, 0);
        for (std::size_t t = 0; t < n; ++t) ex[t] = folds.of[t] == k || flagged[t];
        const std::vector<double> pk = fit_and_predict(u, y, {}, base.options, ex);
        for (std::size_t t = 0; t < n; ++t) {
          if (folds.of[t] != k || flagged[t]) continue;
          before += r[t] * r[t];
          after += (y[t] - pk[t]) * (y[t] - pk[t]);
          ++inliers;
        }
      }
      f.heldout_rms_before = 100.0 * std::sqrt(before / std::max(inliers, 1)) / range;
      f.heldout_rms_after = 100.0 * std::sqrt(after / std::max(inliers, 1)) / range;
      f.gain_pct = f.heldout_rms_before > 0.0
                       ? 100.0 * (1.0 - f.heldout_rms_after / f.heldout_rms_before)
                       : 0.0;
    } else {
      f.heldout_rms_before = f.heldout_rms_after = d.rms_pct_range;
    }
    // Removing them must help, unless the spikes are unmistakable (> 20 robust sigmas).
    f.detected = count > 0 && f.p_value < opt.alpha && (f.gain_pct > 1.0 || zmax > 20.0);
    f.evidence = fmt::format(
        "{} reading(s) stand more than 8 robust sigmas off their neighbours (largest {:.1f}); "
        "without them the held-out E_RMS on the other readings goes from {:.3f} to {:.3f} % of "
        "range",
        count, zmax, f.heldout_rms_before, f.heldout_rms_after);
    d.findings.push_back(f);
  }
  for (const char* e : {"minor_loop_noncongruence", "load_shape_coupling", "offset_nonlinearity"}) {
    Finding f;
    f.effect = e;
    f.evidence = "not tested by this version of diagnose";
    f.heldout_rms_before = f.heldout_rms_after = d.rms_pct_range;
    d.findings.push_back(f);
  }

  // The cause. Outliers dominate the residual variance when present, so they are named first;
  // otherwise the detected effect whose extension gains most.
  const Finding* best = nullptr;
  for (const Finding& f : d.findings) {
    if (!f.detected) continue;
    if (f.effect == "outliers") {
      best = &f;
      break;
    }
    if (!best || f.gain_pct > best->gain_pct) best = &f;
  }
  if (best) {
    d.cause = best->effect;
  } else {
    d.cause = d.rms_pct_range <= 2.0 * d.noise_floor_pct_range ? "none" : "unexplained";
  }
  return d;
}

}  // namespace scpkit
