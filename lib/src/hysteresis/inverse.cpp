#include "scpkit/hysteresis/inverse.hpp"

#include <algorithm>
#include <cmath>

#include "scpkit/error.hpp"

namespace scpkit {

PreisachInverter::PreisachInverter(const PreisachModel& model)
    : PreisachInverter(model, model.grid().lo, model.grid().hi) {}

PreisachInverter::PreisachInverter(const PreisachModel& model, double u_min, double u_max)
    : model_(&model),
      u_min_(std::max(u_min, model.grid().lo)),
      u_max_(std::min(u_max, model.grid().hi)),
      scratch_(PreisachState::negative_saturation(model.grid())) {
  if (!(u_min_ < u_max_)) throw_invalid("inverse: empty input range [{}, {}]", u_min, u_max);
  breaks_.reserve(static_cast<std::size_t>(model.grid().levels) + 64);
}

double PreisachInverter::output_at(const PreisachState& state, double u) {
  scratch_ = state;  // reuses the scratch buffers: no allocation in steady state
  scratch_.apply(u);
  return model_->output(scratch_);
}

namespace detail {

// Solves y(u) = target on a monotone path from u0 (output y0) to breaks.back(), where y is
// quadratic between consecutive entries of `breaks` (sorted in path order, ending at the path
// end): bisection over the breakpoints, then the piece's quadratic through three points.
template <class OutputAt>
double solve_monotone_path(OutputAt&& y_at, double u0, double y0, const std::vector<double>& breaks,
                           double target) {
  const double y1 = y_at(breaks.back());
  const double dir = y1 >= y0 ? 1.0 : -1.0;
  std::size_t a = 0, b = breaks.size() - 1;  // invariant: the target lies at or before breaks[b]
  while (a < b) {
    const std::size_t mid = (a + b) / 2;
    if (dir * (y_at(breaks[mid]) - target) >= 0.0) {
      b = mid;
    } else {
      a = mid + 1;
    }
  }
  const double ub = breaks[b];
  const double ua = b == 0 ? u0 : breaks[b - 1];
  const double ya = b == 0 ? y0 : y_at(ua);
  const double yb = y_at(ub);
  const double ym = y_at(0.5 * (ua + ub));
  const double C = 2.0 * (yb - 2.0 * ym + ya);
  const double B = yb - ya - C;
  const double c0 = ya - target;
  double t;
  if (std::abs(C) <= 1e-12 * (std::abs(B) + std::abs(c0) + 1e-300)) {
    t = B != 0.0 ? -c0 / B : 0.0;
  } else {
    const double disc = std::max(B * B - 4.0 * C * c0, 0.0);
    const double q = -0.5 * (B + std::copysign(std::sqrt(disc), B));
    const double r1 = q / C, r2 = q != 0.0 ? c0 / q : r1;
    t = std::abs(r1 - 0.5) <= std::abs(r2 - 0.5) ? r1 : r2;  // the root in [0, 1]
  }
  return ua + std::clamp(t, 0.0, 1.0) * (ub - ua);
}

// Breakpoints of a Preisach path from u0 to u1 (exclusive), in path order, then u1: grid nodes
// and the memory's earlier extrema that the move wipes out, plus any `extra` points.
void preisach_path_breaks(const PreisachGrid& g, const PreisachState& state, double u0, double u1,
                          std::initializer_list<double> extra, std::vector<double>& breaks) {
  breaks.clear();
  const double lo = std::min(u0, u1), hi = std::max(u0, u1);
  const double h = g.step();
  for (int k = 1; k < g.levels; ++k) {
    const double x = g.lo + k * h;
    if (x > lo && x < hi) breaks.push_back(x);
  }
  const auto pts = state.turning_points();
  for (std::size_t i = 1; i + 1 < pts.size(); ++i) {
    if (pts[i] > lo && pts[i] < hi) breaks.push_back(pts[i]);
  }
  for (double x : extra) {
    if (x > lo && x < hi) breaks.push_back(x);
  }
  if (u1 > u0) {
    std::sort(breaks.begin(), breaks.end());
  } else {
    std::sort(breaks.begin(), breaks.end(), std::greater<>());
  }
  breaks.push_back(u1);
}

}  // namespace detail

double PreisachInverter::solve_on_path(const PreisachState& state, double u0, double u1,
                                       double target) {
  detail::preisach_path_breaks(model_->grid(), state, u0, u1, {}, breaks_);
  return detail::solve_monotone_path([&](double u) { return output_at(state, u); }, u0,
                                     model_->output(state), breaks_, target);
}

namespace detail {

// One exact compensation step for a path-monotone operator: pick the direction whose path
// reaches the target (rising to u_max, or falling to u_min) and solve on it; otherwise
// saturate at the limit that comes closest and flag. `solve(u_end)` solves on a path.
template <class OutputAt, class Solve>
InverseStep monotone_inverse_step(OutputAt&& y_at, Solve&& solve, double u0, double y0,
                                  double u_min, double u_max, double target, double scale) {
  InverseStep r;
  r.input = u0;
  const bool admissible = u0 >= u_min && u0 <= u_max;  // the memory's input may lie outside
  if (admissible && std::abs(target - y0) <= 1e-14 * scale) return r;
  const double y_up = y_at(u_max), y_down = y_at(u_min);
  auto between = [](double v, double a, double b) {
    return v >= std::min(a, b) && v <= std::max(a, b);
  };
  if (between(target, y0, y_up) && y_up != y0) {
    r.input = solve(u_max);
  } else if (between(target, y0, y_down) && y_down != y0) {
    r.input = solve(u_min);
  } else {
    r.reached = false;
    const double e_up = std::abs(y_up - target), e_down = std::abs(y_down - target),
                 e0 = std::abs(y0 - target);
    r.input = e_up <= e_down ? (e_up < e0 || !admissible ? u_max : u0)
                             : (e_down < e0 || !admissible ? u_min : u0);
  }
  // A path that starts outside the admissible range may solve outside it: saturate, flag.
  const double clamped = std::clamp(r.input, u_min, u_max);
  if (clamped != r.input) {
    r.input = clamped;
    r.reached = false;
  }
  return r;
}

}  // namespace detail

InverseStep PreisachInverter::step(PreisachState& state, double target) {
  const double u0 = state.input();  // the path starts where the memory is
  const double y0 = model_->output(state);
  const double scale = std::abs(model_->total_mass()) + std::abs(model_->bias()) + 1e-300;
  InverseStep r =
      detail::monotone_inverse_step([&](double u) { return output_at(state, u); },
                                    [&](double u1) { return solve_on_path(state, u0, u1, target); },
                                    u0, y0, u_min_, u_max_, target, scale);
  state.apply(r.input);
  r.output = model_->output(state);
  return r;
}

// ---------------------------------------------------------------- lonely stroke

LonelyInverter::LonelyInverter(const LonelyModel& model, double u_min, double u_max)
    : model_(&model),
      u_min_(std::max(u_min, model.preisach.grid().lo)),
      u_max_(std::min(u_max, model.preisach.grid().hi)),
      scratch_(LonelyState::initial(model)) {
  model.validate();
  if (!(u_min_ < u_max_)) throw_invalid("inverse: empty input range [{}, {}]", u_min, u_max);
}

double LonelyInverter::output_at(const LonelyState& state, double u) {
  scratch_.preisach = state.preisach;
  scratch_.running_max = state.running_max;
  scratch_.sigma = state.sigma;
  return lonely_step(*model_, scratch_, u);
}

InverseStep LonelyInverter::step(LonelyState& state, double target) {
  const double u0 = state.preisach.input();
  const double y0 = lonely_output(*model_, state);
  double scale =
      std::abs(model_->preisach.total_mass()) + std::abs(model_->preisach.bias()) + 1e-300;
  for (double w : model_->column_weights) scale += std::abs(w);
  auto y_at = [&](double u) { return output_at(state, u); };
  InverseStep r = detail::monotone_inverse_step(
      y_at,
      [&](double u1) {
        detail::preisach_path_breaks(model_->preisach.grid(), state.preisach, u0, u1,
                                     {state.running_max}, breaks_);
        return detail::solve_monotone_path(y_at, u0, y0, breaks_, target);
      },
      u0, y0, u_min_, u_max_, target, scale);
  r.output = lonely_step(*model_, state, r.input);
  return r;
}

// ---------------------------------------------------------------- GPI

GpiInverter::GpiInverter(const GpiModel& model) : model_(&model) {
  model.validate();
  breaks_.reserve(model.radii.size());
}

std::pair<double, double> GpiInverter::walk(const GpiState& state, bool up, double target) {
  const GpiModel& m = *model_;
  const double g0 = up ? m.right(state.v) : m.left(state.v);
  const double g1 = up ? m.right(m.v_max) : m.left(m.v_min);
  breaks_.clear();
  for (std::size_t j = 0; j < m.radii.size(); ++j) {
    breaks_.emplace_back(up ? state.w[j] + m.radii[j] : state.w[j] - m.radii[j], m.weights[j]);
  }
  if (up) {
    std::sort(breaks_.begin(), breaks_.end());
  } else {
    std::sort(breaks_.begin(), breaks_.end(), std::greater<>());
  }
  double g = g0, H = gpi_output(m, state), slope = 0.0;  // slope: dH/dg of the active operators
  double solution = std::nan("");
  auto segment = [&](double g_end) {
    const double H_end = H + slope * (g_end - g);
    if (std::isnan(solution) && slope != 0.0 && (target - H) * (target - H_end) <= 0.0) {
      solution = g + (target - H) / slope;
    }
    H = H_end;
    g = g_end;
  };
  for (const auto& [gb, p] : breaks_) {
    if (up ? gb >= g1 : gb <= g1) break;
    if (up ? gb > g : gb < g) segment(gb);
    slope += p;
  }
  segment(g1);
  return {H, solution};
}

InverseStep GpiInverter::step(GpiState& state, double target) {
  const GpiModel& m = *model_;
  InverseStep r;
  const double y0 = gpi_output(m, state);
  if (target == y0) {
    r.input = state.v;
    r.output = y0;
    return r;
  }
  const auto [y_up, g_up] = walk(state, true, target);
  double v;
  if (!std::isnan(g_up)) {
    v = m.right.inverse(g_up);
  } else {
    const auto [y_down, g_down] = walk(state, false, target);
    if (!std::isnan(g_down)) {
      v = m.left.inverse(g_down);
    } else {
      r.reached = false;
      const double e_up = std::abs(y_up - target), e_down = std::abs(y_down - target);
      v = e_up <= e_down ? m.v_max : m.v_min;
      if (std::min(e_up, e_down) >= std::abs(y0 - target)) v = state.v;
    }
  }
  r.input = std::clamp(v, m.v_min, m.v_max);
  r.output = gpi_step(m, state, r.input);
  return r;
}

// ---------------------------------------------------------------- labelled comparisons

PaperPiInverse paper_pi_inverse(const std::vector<double>& r, const std::vector<double>& p) {
  if (r.size() != p.size() || p.empty()) throw_invalid("paper_pi_inverse: one weight per radius");
  if (p[0] == 0.0) throw_invalid("paper_pi_inverse: p_0 must not be zero");
  PaperPiInverse inv;
  inv.radii.assign(r.size(), 0.0);
  inv.weights.assign(p.size(), 0.0);
  inv.weights[0] = 1.0 / p[0];
  double partial = p[0];  // p_0 + sum_{j<k} p_j
  for (std::size_t j = 1; j < r.size(); ++j) {
    double rj = p[0] * r[j];
    for (std::size_t k = 1; k < j; ++k) rj += p[k] * (r[j] - r[k]);
    inv.radii[j] = rj;
    const double next = partial + p[j];
    inv.weights[j] = -p[j] / (next * partial);
    partial = next;
  }
  return inv;
}

IterativeInverseResult iterative_inverse_step(const PreisachModel& model, PreisachState& state,
                                              double target, double u_min, double u_max, double d0,
                                              double tolerance, int max_iterations) {
  if (!(d0 > 0.0) || !(tolerance > 0.0) || !(u_min < u_max))
    throw_invalid("iterative inverse: bad settings");
  IterativeInverseResult res;
  PreisachState scratch = state;
  auto y_at = [&](double u) {
    scratch = state;
    scratch.apply(u);
    return model.output(scratch);
  };
  double u = std::clamp(state.input(), u_min, u_max);
  double y = y_at(u);
  // Direction: the one whose path's end lies on the target's side.
  const double y_up = y_at(u_max);
  const double dir = (target - y) * (y_up - y) > 0.0 ? 1.0 : -1.0;
  double step = d0;
  const double floor = 1e-12 * (u_max - u_min);
  while (std::abs(target - y) > tolerance && res.iterations < max_iterations && step > floor) {
    ++res.iterations;
    const double u_try = std::clamp(u + dir * step, u_min, u_max);
    const double y_try = y_at(u_try);
    if ((target - y_try) * (target - y) < 0.0) {
      step *= 0.5;  // would overshoot: halve (the printed version steps by d, not d0)
      continue;
    }
    if (u_try == u) break;  // at the limit
    u = u_try;
    y = y_try;
  }
  res.step.input = u;
  res.step.reached = std::abs(target - y) <= tolerance;
  state.apply(u);
  res.step.output = model.output(state);
  return res;
}

}  // namespace scpkit
