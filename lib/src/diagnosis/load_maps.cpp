// load_shape_coupling and offset_nonlinearity: what the load maps f1, f2 of the augmented model
// miss (PHYSICS.md section 5).
#include <algorithm>
#include <cmath>
#include <set>

#include "detectors.hpp"
#include "scpkit/hysteresis/preisach.hpp"

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
      "a change of the normalised loop shape with load");
}

Finding detect_offset_nonlinearity(Context& ctx) {
  const Record& rec = ctx.rec;
  if (!rec.several_loads || rec.fold_kind != "load segments")
    return not_tested(ctx, "offset_nonlinearity",
                      "needs tests at three or more constant loads (held out by load)");
  const std::set<double> distinct(rec.seg_load.begin(), rec.seg_load.end());
  if (distinct.size() < 5)
    return not_tested(ctx, "offset_nonlinearity",
                      "needs five or more loads to fit and hold out a map beyond quadratic");
  // Five loads leave four in training (the end loads always train): a fourth basis function
  // is then exactly determined and no knee width can be chosen; the cubic is the a-priori
  // one (PHYSICS.md section 5: "higher order or softplus knee"). From six loads on, the knee
  // width is chosen by leave-one-load-out over the training loads, 0 being the quadratic.
  const bool cubic = distinct.size() == 5;
  const auto [flo, fhi] = std::minmax_element(rec.seg_load.begin(), rec.seg_load.end());
  const double f_lo = *flo, f_scale = *fhi - *flo;
  // The knee widths to choose from (none at five loads).
  const std::vector<double> widths =
      cubic ? std::vector<double>{} : std::vector<double>{0.0, 0.08, 0.15, 0.3};
  return model_finding(
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
            if (F[i] == f_lo || F[i] == *fhi) continue;  // interpolation only
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
}

}  // namespace scpkit::diagnosis
