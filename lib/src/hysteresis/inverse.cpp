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

// Solves y(u) = target for u between u0 (current input) and u1 (path end), y monotone.
double PreisachInverter::solve_on_path(const PreisachState& state, double u0, double u1,
                                       double target) {
  const bool up = u1 > u0;
  const PreisachGrid& g = model_->grid();
  const double h = g.step();
  // Breakpoints strictly between u0 and u1, in path order: grid nodes and the earlier
  // extrema of the memory that the move will wipe out.
  breaks_.clear();
  const double lo = std::min(u0, u1), hi = std::max(u0, u1);
  for (int k = 1; k < g.levels; ++k) {
    const double x = g.lo + k * h;
    if (x > lo && x < hi) breaks_.push_back(x);
  }
  const auto pts = state.turning_points();
  for (std::size_t i = 1; i + 1 < pts.size(); ++i) {
    if (pts[i] > lo && pts[i] < hi) breaks_.push_back(pts[i]);
  }
  if (up) {
    std::sort(breaks_.begin(), breaks_.end());
  } else {
    std::sort(breaks_.begin(), breaks_.end(), std::greater<>());
  }
  breaks_.push_back(u1);
  // Direction of the output along the path, and the first breakpoint at or past the target.
  const double y0 = model_->output(state);
  const double y1 = output_at(state, u1);
  const double dir = y1 >= y0 ? 1.0 : -1.0;
  std::size_t a = 0, b = breaks_.size() - 1;  // invariant: the target lies at or before breaks_[b]
  while (a < b) {
    const std::size_t mid = (a + b) / 2;
    if (dir * (output_at(state, breaks_[mid]) - target) >= 0.0) {
      b = mid;
    } else {
      a = mid + 1;
    }
  }
  const double ub = breaks_[b];
  const double ua = b == 0 ? u0 : breaks_[b - 1];
  // y is quadratic on [ua, ub]: through three points, then the root inside.
  const double ya = b == 0 ? y0 : output_at(state, ua);
  const double yb = output_at(state, ub);
  const double ym = output_at(state, 0.5 * (ua + ub));
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

InverseStep PreisachInverter::step(PreisachState& state, double target) {
  const double u0 = std::clamp(state.input(), u_min_, u_max_);
  const double y0 = model_->output(state);
  InverseStep r;
  const double scale = std::abs(model_->total_mass()) + std::abs(model_->bias()) + 1e-300;
  if (std::abs(target - y0) <= 1e-14 * scale) {
    r.input = state.input();
    r.output = y0;
    return r;
  }
  const double y_up = output_at(state, u_max_);
  const double y_down = output_at(state, u_min_);
  auto between = [](double v, double a, double b) {
    return v >= std::min(a, b) && v <= std::max(a, b);
  };
  if (between(target, y0, y_up) && y_up != y0) {
    r.input = solve_on_path(state, u0, u_max_, target);
  } else if (between(target, y0, y_down) && y_down != y0) {
    r.input = solve_on_path(state, u0, u_min_, target);
  } else {
    // Unreachable: go to the limit whose output comes closest.
    r.reached = false;
    const double e_up = std::abs(y_up - target), e_down = std::abs(y_down - target),
                 e0 = std::abs(y0 - target);
    r.input = e_up <= e_down ? (e_up < e0 ? u_max_ : u0) : (e_down < e0 ? u_min_ : u0);
  }
  state.apply(r.input);
  r.output = model_->output(state);
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

}  // namespace scpkit
