#include "scpkit/hysteresis/operator.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "scpkit/error.hpp"

namespace scpkit {

double PolynomialModel::operator()(double v) const {
  v = std::clamp(v, v_min, v_max);
  double y = 0.0;
  for (std::size_t k = coefficients.size(); k-- > 0;) y = y * v + coefficients[k];
  return y;
}

InverseStep PolynomialModel::inverse(double target, double previous) const {
  const double c0 = !coefficients.empty() ? coefficients[0] : 0.0;
  const double c1 = coefficients.size() > 1 ? coefficients[1] : 0.0;
  const double c2 = coefficients.size() > 2 ? coefficients[2] : 0.0;
  std::vector<double> roots;
  if (c2 == 0.0) {
    if (c1 != 0.0) roots.push_back((target - c0) / c1);
  } else {
    const double disc = c1 * c1 - 4.0 * c2 * (c0 - target);
    if (disc >= 0.0) {
      const double q = -0.5 * (c1 + std::copysign(std::sqrt(disc), c1));
      if (q != 0.0) roots.push_back((c0 - target) / q);
      roots.push_back(q / c2);
    }
  }
  InverseStep r;
  double best = std::nan("");
  for (double v : roots) {
    if (v >= v_min - 1e-12 && v <= v_max + 1e-12 &&
        (std::isnan(best) || std::abs(v - previous) < std::abs(best - previous))) {
      best = std::clamp(v, v_min, v_max);
    }
  }
  if (std::isnan(best)) {
    r.reached = false;
    best = std::abs((*this)(v_min)-target) <= std::abs((*this)(v_max)-target) ? v_min : v_max;
  }
  r.input = best;
  r.output = (*this)(best);
  return r;
}

std::string HysteresisOperator::family() const {
  if (std::holds_alternative<PreisachModel>(model_)) return "preisach";
  if (std::holds_alternative<GpiModel>(model_)) return "gpi";
  if (std::holds_alternative<LonelyModel>(model_)) return "lonely";
  return std::get<PolynomialModel>(model_).coefficients.size() > 2 ? "poly2" : "linear";
}

namespace {
std::pair<double, double> own_range(const HysteresisOperator::Variant& v) {
  return std::visit(
      [](const auto& m) -> std::pair<double, double> {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, PreisachModel>) {
          return {m.grid().lo, m.grid().hi};
        } else if constexpr (std::is_same_v<T, LonelyModel>) {
          return {m.preisach.grid().lo, m.preisach.grid().hi};
        } else {
          return {m.v_min, m.v_max};
        }
      },
      v);
}
}  // namespace

HysteresisOperator::HysteresisOperator(Variant model) : model_(std::move(model)) {
  std::tie(input_min_, input_max_) = own_range(model_);
}

HysteresisOperator::HysteresisOperator(Variant model, double input_min, double input_max)
    : model_(std::move(model)) {
  const auto [lo, hi] = own_range(model_);
  input_min_ = std::max(lo, input_min);
  input_max_ = std::min(hi, input_max);
  if (!(input_min_ < input_max_))
    throw_invalid("operator input range [{}, {}] is empty", input_min, input_max);
}

double HysteresisOperator::input_min() const { return input_min_; }
double HysteresisOperator::input_max() const { return input_max_; }

std::vector<double> HysteresisOperator::simulate(std::span<const double> u,
                                                 std::span<const char> starts) const {
  std::vector<double> y(u.size());
  auto restart = [&](std::size_t t) { return t == 0 || (!starts.empty() && starts[t]); };
  if (const auto* p = std::get_if<PreisachModel>(&model_)) {
    PreisachState s = PreisachState::negative_saturation(p->grid());
    for (std::size_t t = 0; t < u.size(); ++t) {
      if (restart(t)) s = PreisachState::negative_saturation(p->grid());
      y[t] = p->step(s, u[t]);
    }
  } else if (const auto* g = std::get_if<GpiModel>(&model_)) {
    GpiState s;
    for (std::size_t t = 0; t < u.size(); ++t) {
      if (restart(t)) s = GpiState::at_lower_turning_point(*g, g->v_min);
      y[t] = gpi_step(*g, s, u[t]);
    }
  } else if (const auto* l = std::get_if<LonelyModel>(&model_)) {
    LonelyState s = LonelyState::initial(*l);
    for (std::size_t t = 0; t < u.size(); ++t) {
      if (restart(t))
        s = LonelyState::initial(*l, starts.empty() ? static_cast<char>(kRestart) : starts[t]);
      y[t] = lonely_step(*l, s, u[t]);
    }
  } else {
    const auto& poly = std::get<PolynomialModel>(model_);
    for (std::size_t t = 0; t < u.size(); ++t) y[t] = poly(u[t]);
  }
  return y;
}

std::vector<InverseStep> HysteresisOperator::invert(std::span<const double> targets,
                                                    std::span<const char> starts) const {
  std::vector<InverseStep> out(targets.size());
  auto restart = [&](std::size_t t) { return t == 0 || (!starts.empty() && starts[t]); };
  if (const auto* p = std::get_if<PreisachModel>(&model_)) {
    PreisachInverter inv(*p, input_min_, input_max_);
    PreisachState s = PreisachState::negative_saturation(p->grid());
    for (std::size_t t = 0; t < targets.size(); ++t) {
      if (restart(t)) s = PreisachState::negative_saturation(p->grid());
      out[t] = inv.step(s, targets[t]);
    }
  } else if (const auto* g = std::get_if<GpiModel>(&model_)) {
    GpiInverter inv(*g);
    GpiState s;
    for (std::size_t t = 0; t < targets.size(); ++t) {
      if (restart(t)) s = GpiState::at_lower_turning_point(*g, g->v_min);
      out[t] = inv.step(s, targets[t]);
    }
  } else if (const auto* l = std::get_if<LonelyModel>(&model_)) {
    LonelyInverter inv(*l, input_min_, input_max_);
    LonelyState s = LonelyState::initial(*l);
    for (std::size_t t = 0; t < targets.size(); ++t) {
      if (restart(t))
        s = LonelyState::initial(*l, starts.empty() ? static_cast<char>(kRestart) : starts[t]);
      out[t] = inv.step(s, targets[t]);
    }
  } else {
    const auto& poly = std::get<PolynomialModel>(model_);
    double prev = poly.v_min;
    for (std::size_t t = 0; t < targets.size(); ++t) {
      if (restart(t)) prev = poly.v_min;
      out[t] = poly.inverse(targets[t], prev);
      prev = out[t].input;
    }
  }
  return out;
}

HysteresisOperator HysteresisOperator::with_output_affine(double gain, double offset) const {
  if (const auto* p = std::get_if<PreisachModel>(&model_)) {
    return HysteresisOperator(p->with_output_affine(gain, offset), input_min_, input_max_);
  }
  if (const auto* g = std::get_if<GpiModel>(&model_)) {
    GpiModel m = *g;
    for (double& w : m.weights) w *= gain;
    m.bias = m.bias * gain + offset;
    return HysteresisOperator(m);
  }
  if (const auto* l = std::get_if<LonelyModel>(&model_)) {
    LonelyModel m{l->preisach.with_output_affine(gain, offset), l->column_weights};
    for (double& w : m.column_weights) w *= gain;
    return HysteresisOperator(m, input_min_, input_max_);
  }
  PolynomialModel poly = std::get<PolynomialModel>(model_);
  for (double& c : poly.coefficients) c *= gain;
  poly.coefficients[0] += offset;
  return HysteresisOperator(poly);
}

}  // namespace scpkit
