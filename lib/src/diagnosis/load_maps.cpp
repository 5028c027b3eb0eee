// load_shape_coupling and offset_nonlinearity: what the load maps f1, f2 of the augmented model
// miss (PHYSICS.md section 5).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "detectors.hpp"
#include "scpkit/hysteresis/preisach.hpp"
#include "stats.hpp"

namespace scpkit::diagnosis {
namespace {

// The segment's normalised load (F - F_mid) / (F range) for each row.
std::vector<double> centred_load(const Record& rec) {
  const auto [lo, hi] = std::minmax_element(rec.seg_load.begin(), rec.seg_load.end());
  const double mid = 0.5 * (*lo + *hi), span = std::max(*hi - *lo, 1e-300);
  std::vector<double> x(rec.size());
  for (std::size_t t = 0; t < rec.size(); ++t)
    x[t] = (rec.seg_load[static_cast<std::size_t>(rec.seg[t])] - mid) / span;
  return x;
}

// Subtracts each column's mean within each load segment.
void centre_per_segment(const Record& rec, Eigen::MatrixXd& X) {
  for (std::size_t s = 0; s < rec.seg_first.size(); ++s) {
    const auto f = static_cast<Eigen::Index>(rec.seg_first[s]);
    const auto c = static_cast<Eigen::Index>(rec.seg_count[s]);
    for (Eigen::Index j = 0; j < X.cols(); ++j) {
      const double m = X.col(j).segment(f, c).mean();
      X.col(j).segment(f, c).array() -= m;
    }
  }
}

// Below this many distinct loads no map beyond quadratic can be held out (the end loads always
// train, so each fold trains on one fewer).
constexpr std::size_t kLoadsForHeldOutMaps = 5;

std::size_t distinct_loads(const Record& rec) {
  return std::set<double>(rec.seg_load.begin(), rec.seg_load.end()).size();
}

// The share of the scored residuals' sum of squares that an affine map of H within each
// held-out segment explains (least squares of r on [1, h] per segment, about zero).
double segment_map_share(const Context& ctx, const Eigen::VectorXd& r) {
  struct Sums {
    double n = 0, h = 0, hh = 0, r = 0, hr = 0;
  };
  std::map<int, Sums> by_seg;
  double total = 0.0;
  for (std::size_t i = 0; i < ctx.scored.size(); ++i) {
    const std::size_t t = ctx.scored[i];
    const double h = ctx.by_fold[static_cast<std::size_t>(ctx.rec.fold[t])].h[t];
    const double ri = r[static_cast<Eigen::Index>(i)];
    Sums& s = by_seg[ctx.rec.seg[t]];
    s.n += 1.0;
    s.h += h;
    s.hh += h * h;
    s.r += ri;
    s.hr += h * ri;
    total += ri * ri;
  }
  double explained = 0.0;
  for (const auto& [seg, s] : by_seg) {
    const double det = s.n * s.hh - s.h * s.h;
    if (det > 1e-12 * s.n * s.n) {
      const double a = (s.hh * s.r - s.h * s.hr) / det, b = (s.n * s.hr - s.h * s.r) / det;
      explained += a * s.r + b * s.hr;
    } else {
      explained += s.r * s.r / s.n;  // H constant over the segment: its mean alone
    }
  }
  return total > 0.0 ? explained / total : 0.0;
}

// Below five loads the held-out loads leave three (or two) in training, which determine the
// quadratic maps exactly: no map beyond them can be fitted and scored. What the maps miss is
// still seen in the residuals: f1 and f2 wrong at a held-out load make its residuals an
// affine map of H there (delta_a + delta_b H), and no other part of the augmented model is
// constant or proportional to H within a segment. The signature is the share of the held-out
// residuals' sum of squares that such per-segment maps explain, against blocks of the
// residuals permuted across the scored rows. It names no cause here; diagnose() names it when
// the residuals are material and nothing else is detected. From five loads on it is read where
// the held-out maps do not name the effect (detect_offset_nonlinearity).
// few_loads_signature's extended model: none is fitted, the finding is a signature alone.
constexpr const char* kNoMapFitted =
    "none fitted: what the maps miss at the held-out loads, read off the residuals";

Finding few_loads_signature(Context& ctx, std::size_t loads) {
  Finding f = not_tested(ctx, "offset_nonlinearity",
                         "needs five or more loads to fit and hold out a map beyond quadratic");
  Eigen::VectorXd r(static_cast<Eigen::Index>(ctx.scored.size()));
  for (std::size_t i = 0; i < ctx.scored.size(); ++i)
    r[static_cast<Eigen::Index>(i)] = ctx.r[ctx.scored[i]];
  if (r.size() < 20) return f;
  f.tested = true;
  f.score = segment_map_share(ctx, r);
  const std::size_t block = std::max<std::size_t>(4, ctx.scored.size() / 24);
  f.p_value =
      block_permutation_p(r, f.score, block, ctx.opt.permutations, ctx.rng,
                          [&](const Eigen::VectorXd& p) { return segment_map_share(ctx, p); });
  f.extended_model = kNoMapFitted;
  f.evidence = fmt::format(
      "{}an affine map of H within each held-out segment (the maps' error at its load) "
      "explains {:.0f} % of the held-out residuals' sum of squares (block-permutation "
      "p = {:.3f})",
      loads < kLoadsForHeldOutMaps
          ? fmt::format("with {} loads the maps beyond quadratic cannot be held out; ", loads)
          : std::string(),
      100.0 * f.score, f.p_value);
  return f;
}

}  // namespace

Finding detect_load_shape_coupling(Context& ctx) {
  const Record& rec = ctx.rec;
  if (!rec.several_loads)
    return not_tested(ctx, "load_shape_coupling", "needs tests at several constant loads");
  // A coarse Preisach operator G whose weight grows with the load:
  // y = f1 + f2 (H[v] + (F - F_mid) / dF G[v]).
  const auto [umin, umax] = std::minmax_element(rec.u.begin(), rec.u.end());
  const PreisachGrid grid{*umin, *umax, 4};
  Eigen::MatrixXd S(static_cast<Eigen::Index>(rec.size()), grid.cells());
  {
    Eigen::VectorXd row(grid.cells());
    PreisachState st = PreisachState::negative_saturation(grid);
    for (std::size_t t = 0; t < rec.size(); ++t) {
      if (t == 0 || rec.seg[t] != rec.seg[t - 1]) st = PreisachState::negative_saturation(grid);
      st.apply(rec.u[t]);
      signed_area_fractions(grid, st, row);
      S.row(static_cast<Eigen::Index>(t)) = row.transpose();
    }
  }
  const std::vector<double> x = centred_load(rec);
  return feature_finding(
      ctx, "load_shape_coupling",
      "augmented baseline + load-weighted second operator f2(F) (F - F_mid) G[v]",
      [&](const FoldFit& fit) {
        Eigen::MatrixXd X = S;
        for (std::size_t t = 0; t < rec.size(); ++t)
          X.row(static_cast<Eigen::Index>(t)) *= fit.b[static_cast<std::size_t>(rec.seg[t])] * x[t];
        centre_per_segment(rec, X);
        return X;
      },
      "a change of the normalised loop shape with load", &ctx.coupling);
}

Finding detect_offset_nonlinearity(Context& ctx) {
  const Record& rec = ctx.rec;
  if (!rec.several_loads || rec.fold_kind != "load segments")
    return not_tested(ctx, "offset_nonlinearity",
                      "needs tests at three or more constant loads (held out by load)");
  const std::size_t loads = distinct_loads(rec);
  if (loads < kLoadsForHeldOutMaps) return few_loads_signature(ctx, loads);
  // Five loads leave four in training (the end loads always train): a fourth basis function
  // is then exactly determined and no knee width can be chosen; the cubic is the a-priori
  // one (PHYSICS.md section 5: "higher order or softplus knee"). From six loads on, the knee
  // width is chosen by leave-one-load-out over the training loads, 0 being the quadratic.
  const bool cubic = loads == kLoadsForHeldOutMaps;
  // Not a structured binding: the lambdas below capture the highest load, and capturing a
  // binding is C++20 that clang-tidy 14's front end refuses.
  const auto f_range = std::minmax_element(rec.seg_load.begin(), rec.seg_load.end());
  const double f_lo = *f_range.first, f_hi = *f_range.second, f_scale = f_hi - f_lo;
  // The knee widths to choose from (none at five loads).
  const std::vector<double> widths =
      cubic ? std::vector<double>{} : std::vector<double>{0.0, 0.08, 0.15, 0.3};
  Finding f = model_finding(
      ctx, "offset_nonlinearity",
      cubic ? "augmented baseline with cubic maps f1, f2 (five loads)"
            : "augmented baseline with f1, f2 = quadratic + knee exp(-(F - F_lo) / w) at low load",
      [&](int k) {
        const FoldFit& fit = ctx.by_fold[static_cast<std::size_t>(k)];
        std::vector<double> F, A, B;
        for (std::size_t s = 0; s < rec.seg_first.size(); ++s) {
          if (!fit.free[s]) continue;
          F.push_back(rec.seg_load[s]);
          A.push_back(fit.a[s]);
          B.push_back(fit.b[s]);
        }
        // The knee width by leave-one-load-out over the training loads (0 = quadratic).
        double best_w = 0.0, best = std::numeric_limits<double>::infinity();
        for (double w : widths) {
          double err = 0.0;
          for (std::size_t i = 0; i < F.size(); ++i) {
            if (F[i] == f_lo || F[i] == f_hi) continue;  // interpolation only
            std::vector<double> Fi, Ai, Bi;
            for (std::size_t j = 0; j < F.size(); ++j) {
              if (j == i) continue;
              Fi.push_back(F[j]);
              Ai.push_back(A[j]);
              Bi.push_back(B[j]);
            }
            const MapFit m = fit_maps(Fi, Ai, Bi, w, f_lo, f_scale);
            err += std::pow(m.eval(m.coef_a, F[i]) - A[i], 2) +
                   0.25 * std::pow(m.eval(m.coef_b, F[i]) - B[i], 2);
          }
          if (err < best * (1.0 - 1e-9)) {
            best = err;
            best_w = w;
          }
        }
        const MapFit m = fit_maps(F, A, B, best_w, f_lo, f_scale, cubic);
        std::vector<double> p(fit.pred);
        for (std::size_t t = 0; t < rec.size(); ++t) {
          const auto s = static_cast<std::size_t>(rec.seg[t]);
          if (fit.free[s]) continue;
          const double F_s = rec.seg_load[s];
          p[t] = m.eval(m.coef_a, F_s) + m.eval(m.coef_b, F_s) * fit.h[t];
        }
        return p;
      },
      cubic ? "cubic maps through the four training loads predict the held-out loads"
            : "maps with a low-load knee (width by leave-one-load-out) predict the held-out loads");
  // At five loads the a-priori cubic may not be the map the offsets follow (a knee at the
  // lowest load, which always trains, bends the cubic through the four training loads away at
  // a held-out one). Where the cubic does not name it, what the maps miss at the held-out
  // loads is read as below five loads (few_loads_signature), and named the same way where the
  // residuals are material (maps_miss_by_signature; session 38, measured: a 40 % knee of the
  // second generator at loads 20, 50, 60, 140 and 150 g, seed 2600, the cubic losing 17.8 %
  // and the per-segment maps explaining 99 % of the held-out residuals, was `unexplained`; of
  // 58 distinct five-load voltage records of the three generators, the other change was a
  // 12 % drift at loads in increasing order, `unexplained` before and `offset_nonlinearity` now).
  // Likewise from six loads on, where the exponential knee does not name it: a knee of another
  // shape (a hinge, flat above a contact load) is missed by it as by the quadratic (session 86,
  // measured: fourth-generator hinges of 11-30 % at six loads, the knee maps losing up to 72 %
  // and the per-segment maps explaining 89-98 % of the held-out residuals, were `none` or
  // `unexplained`; over 413 voltage records at six or more loads named `none` or `unexplained`,
  // 314 of them clean, six knees are now `offset_nonlinearity` (four such hinges, two softplus
  // knees of the fifth generator), three other effects' misses are named it too (a drift, two
  // creeps), and no clean record changed).
  if (!f.detected) {
    Finding g = few_loads_signature(ctx, loads);
    if (g.tested && maps_miss_by_signature(ctx, g)) {
      g.evidence = f.evidence + "; " + g.evidence;
      return g;
    }
  }
  return f;
}

// Named when more than 60 % of the held-out residuals is what the maps miss, at p < alpha
// (measured on 54 four-load records of the second independent generator: the five offset
// nonlinearities 0.99-1.00, were `unexplained`; the largest of the 41 others without a drift
// 0.50, on residuals below materiality; drifts 0.17-0.93, named drift where material).
bool maps_miss_by_signature(const Context& ctx, const Finding& offset) {
  return offset.tested && offset.extended_model == kNoMapFitted && offset.p_value < ctx.opt.alpha &&
         offset.score > 0.6;
}

}  // namespace scpkit::diagnosis
