#include "scpkit/diagnosis/specimen_change.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include "scpkit/error.hpp"
#include "scpkit/identification/preisach_fit.hpp"
#include "stats.hpp"

namespace scpkit {
namespace {

// The noise of one reading from second differences (robust to the few large ones at turning
// points): 1.4826 median |y[t+1] - 2 y[t] + y[t-1]| / sqrt(6), and at least the rounding error
// of a quantised sensor (its step / sqrt(12)), where most second differences are 0. A smooth
// response's curvature adds to it, so it errs high: a change must then be larger to be named.
double noise_floor(std::span<const double> y) {
  std::vector<double> d2;
  for (std::size_t t = 1; t + 1 < y.size(); ++t)
    d2.push_back(std::abs(y[t + 1] - 2.0 * y[t] + y[t - 1]));
  const double white = d2.empty() ? 0.0 : 1.4826 * diagnosis::median(d2) / std::sqrt(6.0);
  return std::max(white, diagnosis::quantisation_step(y) / std::sqrt(12.0));
}

}  // namespace

SpecimenChange diagnose_specimen_change(std::span<const double> ref_u,
                                        std::span<const double> ref_y, std::span<const double> u,
                                        std::span<const double> y,
                                        const SpecimenChangeOptions& opt) {
  if (ref_u.size() != ref_y.size())
    throw_invalid("the reference's input and response differ in length");
  if (u.size() != y.size()) throw_invalid("the second test's input and response differ in length");
  if (opt.blocks < 4) throw_invalid("need at least 4 held-out blocks, got {}", opt.blocks);
  const std::size_t n = u.size();
  const auto blocks = static_cast<std::size_t>(opt.blocks);
  if (n < 4 * blocks)
    throw IdentificationError(
        fmt::format("the second test has {} readings, too few for {} held-out blocks (need {})", n,
                    blocks, 4 * blocks));
  const auto [ylo, yhi] = std::minmax_element(y.begin(), y.end());
  const double range = *yhi - *ylo;
  if (!(range > 0.0)) throw IdentificationError("the second test's response does not vary");

  // The reference's model: L, lambda and the reversible term by cross-validation over its cycles.
  PreisachFitOptions fo;
  fo.reversible = PreisachFitOptions::Reversible::kChosen;
  const PreisachFit ref = [&] {
    try {
      return fit_preisach(ref_u, ref_y, {}, fo);
    } catch (const IdentificationError& e) {
      throw IdentificationError(std::string("the reference: ") + e.what());
    }
  }();
  SpecimenChange out;
  out.reference_model = fmt::format("Preisach L = {}{} on the reference", ref.summary.levels,
                                    ref.summary.reversible ? " with a reversible term" : "");
  out.reference_rms_pct = ref.summary.train.rms_pct_range;
  out.blocks = opt.blocks;
  out.noise_floor_pct = 100.0 * noise_floor(y) / range;

  // Gamma[u - d] on the second test's history, from negative saturation as the reference was
  // identified; the reversible term clamped to the identified range as the operator is.
  auto gamma = [&](double d) {
    std::vector<double> v(n);
    for (std::size_t t = 0; t < n; ++t) v[t] = u[t] - d;
    PreisachState st = PreisachState::negative_saturation(ref.model.grid());
    const Eigen::VectorXd g = ref.model.simulate(st, v);
    std::vector<double> p(n);
    for (std::size_t t = 0; t < n; ++t)
      p[t] = g[static_cast<Eigen::Index>(t)] +
             ref.reversible_term(std::clamp(v[t], ref.input_min, ref.input_max));
    return p;
  };
  const double span = ref.input_max - ref.input_min;
  const int steps = 60;  // shifts of max_shift / 60 of the span each way
  std::vector<double> shifts;
  std::vector<std::vector<double>> shifted;
  for (int k = -steps; k <= steps; ++k) {
    shifts.push_back(opt.max_shift * span * k / steps);
    shifted.push_back(gamma(shifts.back()));
  }
  const std::vector<double>& unshifted = shifted[static_cast<std::size_t>(steps)];

  // A candidate: the second test's response it predicts from the training rows, and the
  // parameters it chose there.
  struct Fitted {
    std::vector<double> p;
    double g = 1.0, c = 0.0, d = 0.0;
  };
  using Predict = std::function<Fitted(const std::vector<char>& train)>;
  const Predict none = [&](const std::vector<char>&) { return Fitted{unshifted, 1.0, 0.0, 0.0}; };
  auto through = [&](const std::vector<double>& x, const std::vector<char>& train, bool fixed_g,
                     double d) {
    const auto [g, c] =
        diagnosis::masked_line(x, y, train, fixed_g ? std::optional(1.0) : std::nullopt);
    Fitted f{std::vector<double>(n), g, c, d};
    for (std::size_t t = 0; t < n; ++t) f.p[t] = g * x[t] + c;
    return f;
  };
  const Predict offset = [&](const std::vector<char>& train) {
    return through(unshifted, train, true, 0.0);
  };
  const Predict scaled = [&](const std::vector<char>& train) {
    return through(unshifted, train, false, 0.0);
  };
  const Predict shift = [&](const std::vector<char>& train) {
    Fitted best;
    double best_sse = HUGE_VAL;
    for (std::size_t k = 0; k < shifts.size(); ++k) {
      Fitted f = through(shifted[k], train, false, shifts[k]);
      const double sse = diagnosis::training_sse(y, f.p, train);
      // ties (a flat stretch of the operator, or inputs beyond its grid) go to the smallest |d|
      const bool nearer = std::abs(shifts[k]) < std::abs(best.d);
      if (sse < best_sse * (1.0 - 1e-12) || (sse <= best_sse && nearer)) {
        best_sse = sse;
        best = std::move(f);
      }
    }
    return best;
  };
  const Predict own = [&](const std::vector<char>& train) {
    PreisachFitOptions o;
    o.levels = ref.summary.levels;
    o.smoothness = ref.summary.smoothness;
    o.grid_shifts = ref.summary.grid_shifts;
    o.reversible = ref.summary.reversible ? PreisachFitOptions::Reversible::kOn
                                          : PreisachFitOptions::Reversible::kOff;
    o.exclude.assign(n, 0);
    for (std::size_t t = 0; t < n; ++t) o.exclude[t] = train[t] ? 0 : 1;
    const PreisachFit fit = fit_preisach(u, y, {}, o);
    PreisachState st = PreisachState::negative_saturation(fit.model.grid());
    const Eigen::VectorXd g = fit.model.simulate(st, u);
    Fitted f{std::vector<double>(n), 1.0, 0.0, 0.0};
    for (std::size_t t = 0; t < n; ++t)
      f.p[t] = g[static_cast<Eigen::Index>(t)] +
               fit.reversible_term(std::clamp(u[t], fit.input_min, fit.input_max));
    return f;
  };

  // Held out by contiguous blocks of rows: per block, the squared error of its prediction.
  std::vector<std::size_t> block(n);
  for (std::size_t t = 0; t < n; ++t) block[t] = t * blocks / n;
  struct Scored {
    std::vector<double> block_sse;
    double rms = 0.0, max = 0.0;
  };
  auto heldout = [&](const Predict& predict) {
    Scored s;
    s.block_sse.assign(blocks, 0.0);
    double ss = 0.0;
    for (std::size_t k = 0; k < blocks; ++k) {
      std::vector<char> train(n);
      for (std::size_t t = 0; t < n; ++t) train[t] = block[t] != k ? 1 : 0;
      const Fitted f = predict(train);
      for (std::size_t t = 0; t < n; ++t) {
        if (train[t]) continue;
        const double e = y[t] - f.p[t];
        s.block_sse[k] += e * e;
        s.max = std::max(s.max, std::abs(e));
      }
      ss += s.block_sse[k];
    }
    s.rms = 100.0 * std::sqrt(ss / static_cast<double>(n)) / range;
    s.max = 100.0 * s.max / range;
    return s;
  };

  std::vector<char> all(n, 1);
  std::mt19937_64 rng(opt.seed);
  // A candidate scored held out, then (a chain step) its parameters fitted on every reading.
  auto add = [&](const std::string& change, const std::string& model, const Predict& predict,
                 bool parameters) {
    Scored s = heldout(predict);
    SpecimenChangeCandidate c;
    c.change = change;
    c.model = model;
    if (parameters) {
      const Fitted f = predict(all);
      c.g = f.g;
      c.c = f.c;
      c.d = f.d;
    }
    out.candidates.push_back(c);
    return s;
  };

  // The chain: each candidate against the last one accepted.
  const Scored s_none = add("none", "y = Gamma[u], the reference's model unchanged", none, false);
  out.candidates.back().heldout_rms_pct = s_none.rms;
  out.candidates.back().heldout_max_pct = s_none.max;
  out.candidates.back().heldout_rms_before_pct = s_none.rms;
  out.candidates.back().accepted = true;
  out.candidates.back().evidence = fmt::format(
      "the reference's model predicts the second test to {:.3f} % of its range", s_none.rms);
  std::size_t current = 0;
  Scored s_current = s_none;
  auto judge = [&](const Scored& s) {
    SpecimenChangeCandidate& c = out.candidates.back();
    const SpecimenChangeCandidate& base = out.candidates[current];
    c.heldout_rms_pct = s.rms;
    c.heldout_max_pct = s.max;
    c.heldout_rms_before_pct = s_current.rms;
    c.gain_pct = s_current.rms > 0.0 ? 100.0 * (1.0 - s.rms / s_current.rms) : 0.0;
    std::vector<double> gains(blocks);
    for (std::size_t k = 0; k < blocks; ++k) gains[k] = s_current.block_sse[k] - s.block_sse[k];
    c.p_value = diagnosis::sign_flip_p(gains, opt.permutations, rng);
    const bool material = s_current.rms > opt.floor_factor * out.noise_floor_pct;
    c.accepted = material && c.gain_pct >= opt.min_gain_pct && c.p_value < opt.alpha;
    const std::string verdict =
        c.accepted ? "accepted"
        : material
            ? fmt::format("not accepted (needs {:g} % at p < {:g})", opt.min_gain_pct, opt.alpha)
            : fmt::format(
                  "not accepted: `{}` is within {:g} times the noise floor ({:.3f} "
                  "% of range)",
                  base.change, opt.floor_factor, out.noise_floor_pct);
    return fmt::format(
        "held-out E_RMS {:.3f} -> {:.3f} % of range against `{}` ({:+.1f} %, "
        "sign-flip p = {:.3f} over {} blocks): {}",
        s_current.rms, s.rms, base.change, c.gain_pct, c.p_value, blocks, verdict);
  };
  auto step = [&](const std::string& change, const std::string& model, const Predict& predict,
                  const std::function<std::string(const SpecimenChangeCandidate&)>& what,
                  bool extends_chain) {
    const Scored s = add(change, model, predict, extends_chain);
    const std::string verdict = judge(s);
    SpecimenChangeCandidate& c = out.candidates.back();
    c.evidence = what(c) + "; " + verdict;
    if (c.accepted && extends_chain) {
      current = out.candidates.size() - 1;
      s_current = s;
    }
    return c.accepted;
  };

  step(
      "offset", "y = Gamma[u] + c", offset,
      [](const SpecimenChangeCandidate&) {
        return std::string("a constant added to the response");
      },
      true);
  step(
      "range", "y = g Gamma[u] + c", scaled,
      [](const SpecimenChangeCandidate& c) {
        return fmt::format("the response's range times g = {:.4g}", c.g);
      },
      true);
  step(
      "input_shift", "y = g Gamma[u - d] + c", shift,
      [&](const SpecimenChangeCandidate& c) {
        return fmt::format(
            "the reference's response moved along the input by d = {:.4g} ({:+.1f} % of its "
            "input span), range times g = {:.4g}",
            c.d, span > 0.0 ? 100.0 * c.d / span : 0.0, c.g);
      },
      true);
  const std::string own_model =
      fmt::format("the second test's own Preisach model (L = {})", ref.summary.levels);
  bool reshaped = false;
  try {
    reshaped = step(
        "shape", own_model, own,
        [](const SpecimenChangeCandidate&) {
          return std::string("the hysteresis identified on the second test's own training blocks");
        },
        false);
  } catch (const IdentificationError& e) {
    SpecimenChangeCandidate& c = out.candidates.emplace_back();
    c.change = "shape";
    c.model = own_model;
    c.evidence =
        std::string("not tested: the second test alone does not identify it (") + e.what() + ")";
  }
  out.change = reshaped ? "shape" : out.candidates[current].change;
  // Only the named change stays marked: the chain's earlier steps are its evidence.
  for (SpecimenChangeCandidate& c : out.candidates) c.accepted = c.change == out.change;
  return out;
}

}  // namespace scpkit
