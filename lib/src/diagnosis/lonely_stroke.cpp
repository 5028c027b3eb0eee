// lonely_stroke: the first rise after a load change differs from later cycles (PHYSICS.md section
// 4).
#include <fmt/format.h>

#include <algorithm>
#include <utility>

#include "detectors.hpp"
#include "util/parallel.hpp"

namespace scpkit::diagnosis {
namespace {

/// How far a fold's free segment offsets lie from a smooth map of the load through them: the
/// residual sum of squares of a quadratic in the load; 0 with fewer than four segments, where
/// it passes through every offset. (With a line through three, a fresh second-generator
/// record at four loads took the kept form in one fold and lost 217 % on held-out data.)
double offset_map_misfit(const Record& rec, const FoldFit& fit) {
  const auto [flo, fhi] = std::minmax_element(rec.seg_load.begin(), rec.seg_load.end());
  std::vector<double> F, a, b;
  for (std::size_t s = 0; s < rec.seg_first.size(); ++s) {
    if (!fit.free[s]) continue;
    F.push_back(rec.seg_load[s]);
    a.push_back(fit.a[s]);
    b.push_back(fit.b[s]);
  }
  if (F.size() < 4) return 0.0;
  const MapFit maps = fit_maps(F, a, b, 0.0, *flo, *fhi - *flo);
  double ss = 0.0;
  for (std::size_t i = 0; i < F.size(); ++i) {
    const double r = a[i] - maps.eval(maps.coef_a, F[i]);
    ss += r * r;
  }
  return ss;
}

/// The running maximum of the input since the last load change (or the start), normalised by
/// the record's input span, and what the term's sign patterns need to know of the segments.
struct RunningMax {
  std::vector<double> m;             ///< per row, in [0, 1]
  std::vector<char> after_increase;  ///< per row: its segment follows a load increase
  std::vector<double> seg_top;       ///< per segment: the running maximum's last value
  bool two_patterns = false;         ///< some segment follows a load increase
  /// Whether reading t is on its segment's first rise (below the segment's top).
  bool rising(const Record& rec, std::size_t t) const {
    return m[t] < seg_top[static_cast<std::size_t>(rec.seg[t])];
  }
};

RunningMax running_max(const Record& rec) {
  const std::size_t n = rec.size();
  const auto [umin, umax] = std::minmax_element(rec.u.begin(), rec.u.end());
  const double span = std::max(*umax - *umin, 1e-300);
  RunningMax r;
  r.m.assign(n, 0.0);
  r.after_increase.assign(n, 0);
  for (std::size_t s = 0; s < rec.seg_first.size(); ++s) {
    const bool up = rec.several_loads && s > 0 && rec.seg_load[s] > rec.seg_load[s - 1];
    double M = rec.u[rec.seg_first[s]];
    for (std::size_t t = rec.seg_first[s]; t < rec.seg_first[s] + rec.seg_count[s]; ++t) {
      M = std::max(M, rec.u[t]);
      r.m[t] = (M - *umin) / span;
      r.after_increase[t] = up ? 1 : 0;
    }
  }
  r.two_patterns =
      std::any_of(r.after_increase.begin(), r.after_increase.end(), [](char c) { return c != 0; });
  r.seg_top.assign(rec.seg_first.size(), 0.0);
  for (std::size_t t = 0; t < n; ++t) {
    const auto s = static_cast<std::size_t>(rec.seg[t]);
    r.seg_top[s] = std::max(r.seg_top[s], r.m[t]);
  }
  return r;
}

/// One candidate term: its size, its sign pattern over load increases and decreases, and its
/// form.
struct Term {
  double lambda = 0.0;
  bool uniform = false;     ///< one sign throughout, not paper 001's pattern
  int untrained = -1;       ///< the class (after an increase: 1, else 0) with no first rise trained
  bool persistent = false;  ///< lambda m (the offset stays after the first rise)
};

/// The term at reading t, in units of the row's scale. Two forms, which differ on each segment
/// by a constant. The first rise's departure from the segment's later cycles, lambda (m -
/// m_top), m_top the segment's final running maximum: 0 once the input has reached the
/// segment's top, so the map f1 that predicts a held-out segment's offset from the trained ones
/// describes the later cycles. Or persistent, lambda m (paper 001's running-maximum term): 0 at
/// the first reading, and the later cycles keep the offset, so f1 describes the first reading.
/// Where the sign alternates with the load changes, only the form of the specimen leaves
/// offsets that a map smooth in the load follows; each fold takes the form whose trained
/// offsets its quadratic map follows more closely (the departure on a tie). (Measured: with
/// lambda m alone, a fresh second-generator record lost 212 % on held-out data through its
/// held-out segment's offset; with the departure alone, the rig's lonely strokes of opposite
/// sign after an increase, whose later cycles keep the offset, went from 11 to 5 of 12 named.)
double term_at(const Record& rec, const RunningMax& rm, const Term& c, std::size_t t) {
  if (rm.after_increase[t] == c.untrained) return 0.0;
  const double d =
      c.persistent ? rm.m[t] : rm.m[t] - rm.seg_top[static_cast<std::size_t>(rec.seg[t])];
  return c.lambda * (rm.after_increase[t] && !c.uniform ? -d : d);
}

/// The response less the term (scaled per row by `scale`).
std::vector<double> without_term(const Record& rec, const RunningMax& rm,
                                 const std::vector<double>& scale, const Term& c) {
  std::vector<double> y(rec.y);
  for (std::size_t t = 0; t < rec.size(); ++t) y[t] -= scale[t] * term_at(rec, rm, c, t);
  return y;
}

/// The sign pattern from a fold baseline's training residuals (cheap, two-stage): the term's
/// coefficient among the segments after an increase against the others'. Only where both
/// classes have a first rise among the training rows: otherwise the data cannot tell (after one
/// load change, each fold holds out one of the two first rises) and paper 001's pattern stands.
/// Returns a Term of lambda 0 carrying the pattern.
Term sign_pattern(const Record& rec, const RunningMax& rm, const std::vector<char>& train,
                  const std::vector<double>& scale, const FoldFit& base) {
  Term pattern;
  if (!rm.two_patterns) return pattern;
  double xr[2] = {0.0, 0.0};
  int rising[2] = {0, 0};
  for (std::size_t t = 0; t < rec.size(); ++t) {
    if (!train[t]) continue;
    const double x = scale[t] * rm.m[t];
    const int c = rm.after_increase[t] ? 1 : 0;
    xr[c] += x * (rec.y[t] - base.pred[t]);
    if (rm.rising(rec, t)) ++rising[c];
  }
  pattern.uniform = rising[0] > 0 && rising[1] > 0 && xr[0] * xr[1] > 0.0;
  // A class whose first rises are all held out gets no term: its sign is what the data cannot
  // tell (paper 001 leaves the increase open). Measured: a fresh second-generator record, loads
  // 120, 60, 30, 100 g, a 3 % lonely stroke of one sign; the fold holding out the one segment
  // after an increase took paper 001's opposite sign and lambda m lost 530 % on held-out data;
  // without a term there, 212 % (the offset, term_at); with lambda (m - m_top) as well, it
  // gains 5.8 %.
  if (rising[0] == 0 || rising[1] == 0) pattern.untrained = rising[1] == 0 ? 1 : 0;
  return pattern;
}

/// The term's size for one fold with its pattern: the candidate on a grid whose refitted
/// baseline (one grid) leaves the least training error, then the vertex of the parabola
/// through it and its two neighbours (one more fit) where it is smaller still and none of the
/// three is lambda = 0 (the baseline's own fit, on four grids, is not like for like with the
/// one-grid candidates). Measured on an independent generator's lonely strokes of 0.06: lambda
/// 0.04 or 0.08 per fold left a Kelvin creep element gaining more than the term.
Term best_term(const Context& ctx, const RunningMax& rm, const std::vector<char>& train,
               const std::vector<double>& scale, const FoldFit& base, const Term& pattern) {
  std::vector<Term> candidates;
  for (double lambda : {-0.15, -0.08, -0.04, -0.02, 0.0, 0.02, 0.04, 0.08, 0.15}) {
    Term c = pattern;
    c.lambda = lambda;
    candidates.push_back(c);
  }
  auto sse = [&](const Term& c) {
    const std::vector<double> y = without_term(ctx.rec, rm, scale, c);
    const std::vector<double> p =
        c.lambda == 0.0 ? base.pred : ctx.base.fit(train, {{}, &y, true}).pred;
    return training_sse(y, p, train);
  };
  std::vector<double> ss(candidates.size());
  detail::parallel_for(static_cast<int>(candidates.size()), ctx.base.options().threads, [&](int i) {
    ss[static_cast<std::size_t>(i)] = sse(candidates[static_cast<std::size_t>(i)]);
  });
  std::size_t i_best = 0;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (ss[i] < ss[i_best] * (1.0 - 1e-9)) i_best = i;
  }
  Term best = candidates[i_best];
  if (i_best > 0 && i_best + 1 < candidates.size() && candidates[i_best - 1].lambda != 0.0 &&
      candidates[i_best].lambda != 0.0 && candidates[i_best + 1].lambda != 0.0) {
    const double x0 = candidates[i_best - 1].lambda, x1 = best.lambda,
                 x2 = candidates[i_best + 1].lambda;
    const double s0 = ss[i_best - 1], s1 = ss[i_best], s2 = ss[i_best + 1];
    const double den = (x1 - x0) * (s1 - s2) - (x1 - x2) * (s1 - s0);
    if (den != 0.0) {
      const double v =
          x1 - 0.5 * ((x1 - x0) * (x1 - x0) * (s1 - s2) - (x1 - x2) * (x1 - x2) * (s1 - s0)) / den;
      Term vertex = pattern;
      vertex.lambda = v;
      if (v > x0 && v < x2 && v != x1 && sse(vertex) < s1) best.lambda = v;
    }
  }
  return best;
}

}  // namespace

Finding detect_lonely_stroke(Context& ctx) {
  const Record& rec = ctx.rec;
  const std::size_t n = rec.size();
  // The sign of the term comes in two patterns: paper 001's (+1 in the first segment and after
  // a load decrease, -1 after an increase, its open case) and one sign throughout. Load tests:
  // one segment, one pattern.
  const RunningMax rm = running_max(rec);
  // The term scales with each segment's range on voltage tests (f2 times the span of H, whose
  // units are the input's), with the output range on load tests; its size lambda (and
  // pattern) is chosen on each fold's training rows.
  auto scales = [&](const FoldFit& fit) {
    std::vector<double> out(n, rec.range);
    if (!rec.several_loads) return out;
    const auto [hlo, hhi] = std::minmax_element(fit.h.begin(), fit.h.end());
    for (std::size_t t = 0; t < n; ++t)
      out[t] = fit.b[static_cast<std::size_t>(rec.seg[t])] * (*hhi - *hlo);
    return out;
  };
  std::string chosen;
  Finding f = model_finding(
      ctx, "lonely_stroke",
      rec.several_loads
          ? "augmented baseline + running-maximum term re-armed at each load change (paper 001)"
          : "baseline + running-maximum term (expanded plane, paper 001)",
      [&](int k) {
        const std::vector<char> train = ctx.train_mask(k);
        const FoldFit& base = ctx.by_fold[static_cast<std::size_t>(k)];
        // Without a training row on a first rise the term is constant on every trained
        // segment, where the offsets take it up: lambda is not identified and stays 0 (a grid
        // value chosen on a tie lost 40 % on one record's held-out first rise).
        bool identified = false;
        for (std::size_t t = 0; t < n && !identified; ++t)
          identified = train[t] && rm.rising(rec, t);
        if (!identified) {
          chosen += fmt::format("{}0 (no first rise trained)", chosen.empty() ? "" : ", ");
          return base.pred;
        }
        const std::vector<double> scale = scales(base);
        Term best =
            best_term(ctx, rm, train, scale, base, sign_pattern(rec, rm, train, scale, base));
        if (best.lambda == 0.0) {
          chosen += fmt::format("{}0", chosen.empty() ? "" : ", ");
          return base.pred;
        }
        ++ctx.lonely_folds_with_term;
        const std::vector<double> y = without_term(rec, rm, scale, best);
        FoldFit fit = ctx.base.fit(train, {{}, &y, false});
        if (rec.several_loads) {
          Term persistent = best;
          persistent.persistent = true;
          const std::vector<double> y_kept = without_term(rec, rm, scale, persistent);
          FoldFit kept = ctx.base.fit(train, {{}, &y_kept, false});
          if (offset_map_misfit(rec, kept) < offset_map_misfit(rec, fit)) {
            fit = std::move(kept);
            best = persistent;
          }
        }
        chosen += fmt::format("{}{:+.3g}{}{}", chosen.empty() ? "" : ", ", best.lambda,
                              best.uniform ? " one sign" : "", best.persistent ? " kept" : "");
        std::vector<double> p(fit.pred);
        for (std::size_t t = 0; t < n; ++t) p[t] += scale[t] * term_at(rec, rm, best, t);
        return p;
      },
      "a term in the running maximum of the input since the last load change (first rise "
      "against later cycles)");
  f.extended_model += " (lambda per fold: " + chosen + ")";
  // On a load test a first stroke that differs from later ones is also what any Preisach
  // plane extending below the lowest tested load gives (the specimen's virgin loading before
  // the record; PHYSICS.md section 4: the expanded plane), so there the model-free offset is
  // no evidence. With voltage, power or temperature as the input (at one load or several) the
  // lowest input (0 V, ambient) resets every hysteron of a plane on the tested inputs: an
  // offset between readings in the same memory state is the lonely stroke.
  const Signature& sig = ctx.return_point.running_max;
  if (sig.available) {
    f.evidence += "; " + describe(sig);
    // Intersection-union, as for the other signatures: the offset significant and the term
    // gaining at least min_gain_pct at gain_alpha (measured: with any gain > 0 a drift record
    // whose trend extension gained 85 % was named a lonely stroke gaining 0.1 %).
    if (!rec.input_is_load && sig.p_value < ctx.opt.alpha && f.p_value < ctx.opt.gain_alpha &&
        f.gain_pct >= ctx.opt.min_gain_pct)
      f.detected = true;
  }
  // Nor is the held-out gain alone evidence on a load test: record() detects on it, but the
  // first rise is never scored there, and a term in the running maximum, which grows through a
  // record of turning points at random, stands in for a trend in time (measured, session 39:
  // three third-generator drift records of 3-12 %, c20 seed 2002 and fresh seeds 6020 and 6030,
  // named `lonely_stroke` on gains of 21.4, 53.7 and 24.5 %; no load record of the rig or the
  // three generators was a right `lonely_stroke`). Reported, not named (docs/diagnose.md,
  // "Lonely stroke on a single load record").
  if (rec.input_is_load && f.detected) {
    f.detected = false;
    f.evidence +=
        "; not named on a load test (the first rise is never scored, and the running "
        "maximum grows with time)";
  }
  return f;
}

}  // namespace scpkit::diagnosis
