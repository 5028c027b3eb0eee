#include "scpkit/identification/augmented_fit.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "scpkit/error.hpp"
#include "scpkit/identification/lonely_fit.hpp"
#include "scpkit/identification/polynomial_fit.hpp"

namespace scpkit {
namespace {

Quadratic quadratic_through(const std::vector<double>& F, const std::vector<double>& v,
                            int degree) {
  const PolynomialModel p = fit_polynomial(F, v, degree);
  Quadratic q;
  q.c0 = p.coefficients[0];
  q.c1 = p.coefficients[1];
  q.c2 = p.coefficients.size() > 2 ? p.coefficients[2] : 0.0;
  return q;
}

}  // namespace

std::vector<LoadSegment> split_load_segments(std::span<const double> load,
                                             std::span<const int> ids) {
  std::vector<LoadSegment> segs;
  for (std::size_t t = 0; t < load.size(); ++t) {
    const bool cut = t == 0 || (!ids.empty() && ids[t] != ids[t - 1]) ||
                     std::abs(load[t] - load[t - 1]) > 1e-9 * (std::abs(load[t]) + 1e-9);
    if (cut) segs.push_back({t, 0, load[t], 0.0, 0.0});
    ++segs.back().count;
  }
  return segs;
}

AugmentedFit fit_augmented(std::span<const double> load, std::span<const double> input,
                           std::span<const double> output, std::span<const int> ids,
                           const AugmentedFitOptions& options) {
  const std::size_t n = load.size();
  if (input.size() != n || output.size() != n || (!ids.empty() && ids.size() != n)) {
    throw_invalid("augmented fit: sizes differ");
  }
  AugmentedFit fit;
  fit.segments = split_load_segments(load, ids);
  std::set<double> loads;
  std::vector<double> F, D, P;
  for (LoadSegment& s : fit.segments) {
    const auto begin = input.begin() + static_cast<std::ptrdiff_t>(s.first);
    const auto end = begin + static_cast<std::ptrdiff_t>(s.count);
    const std::size_t i_lo =
        s.first + static_cast<std::size_t>(std::min_element(begin, end) - begin);
    const std::size_t i_hi =
        s.first + static_cast<std::size_t>(std::max_element(begin, end) - begin);
    if (!(input[i_hi] > input[i_lo])) {
      throw IdentificationError(
          fmt::format("the input never changes in the segment at load {:.4g} N (sample {})", s.load,
                      s.first + 1));
    }
    s.offset = output[i_lo];
    s.range = output[i_lo] - output[i_hi];
    loads.insert(s.load);
    F.push_back(s.load);
    D.push_back(s.offset);
    P.push_back(s.range);
  }
  if (loads.size() < 2) {
    throw IdentificationError(
        "an augmented model needs tests at two or more loads; fit a single-load file without the "
        "load column");
  }
  const int degree = loads.size() >= 3 ? 2 : 1;
  AugmentedModel& m = fit.model;
  m.f1 = quadratic_through(F, D, degree);
  m.f2 = quadratic_through(F, P, degree);
  m.load_min = *loads.begin();
  m.load_max = *loads.rbegin();
  if (m.f2.crosses_zero(m.load_min, m.load_max)) {
    throw IdentificationError(
        fmt::format("the fitted range f2(F) = {:.4g} + {:.4g} F + {:.4g} F^2 crosses zero inside "
                    "the loads [{:.4g}, {:.4g}] N: "
                    "the hysteresis cannot be normalised there (is one load's range near zero?)",
                    m.f2.c0, m.f2.c1, m.f2.c2, m.load_min, m.load_max));
  }

  // Pooled, normalised data; each segment restarts H.
  std::vector<double> h(n);
  std::vector<char> starts(n, 0);
  std::vector<int> block(n, 0);
  for (std::size_t k = 0; k < fit.segments.size(); ++k) {
    const LoadSegment& s = fit.segments[k];
    starts[s.first] =
        k > 0 && s.load > fit.segments[k - 1].load ? kRestartAfterLoadIncrease : kRestart;
    for (std::size_t t = s.first; t < s.first + s.count; ++t) block[t] = static_cast<int>(k);
  }
  for (std::size_t t = 0; t < n; ++t) h[t] = (output[t] - m.f1(load[t])) / m.f2(load[t]);

  if (options.family == "preisach") {
    PreisachFitOptions po = options.preisach;
    po.restart_at_blocks = true;
    const PreisachFit pf = fit_preisach(input, h, block, po);
    m.h = HysteresisOperator(pf.model, pf.input_min, pf.input_max);
    fit.cv_rms_pct_range = pf.summary.cv_rms_pct_range;
    fit.report = pf.summary.BriefReport();
  } else if (options.family == "gpi") {
    const GpiFit gf = fit_gpi(input, h, starts, options.gpi);
    m.h = HysteresisOperator(gf.model);
    fit.report = gf.summary.BriefReport();
  } else if (options.family == "lonely") {
    const LonelyFit lf = fit_lonely(input, h, starts, options.lonely);
    m.h = HysteresisOperator(lf.model, lf.input_min, lf.input_max);
    fit.report = lf.report;
  } else if (options.family == "linear" || options.family == "poly2") {
    m.h = HysteresisOperator(fit_polynomial(input, h, options.family == "linear" ? 1 : 2));
    fit.report = fmt::format("{} H fit", options.family);
  } else {
    throw_invalid("augmented fit: unknown family '{}'", options.family);
  }
  m.validate();
  fit.train = error_metrics(output, m.simulate(load, input, starts));
  return fit;
}

}  // namespace scpkit
