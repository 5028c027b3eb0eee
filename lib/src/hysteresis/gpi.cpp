#include "scpkit/hysteresis/gpi.hpp"

#include <algorithm>
#include <cmath>

#include "scpkit/error.hpp"

namespace scpkit {

void GpiModel::validate() const {
  if (radii.empty() || radii.size() != weights.size()) {
    throw_invalid("GPI model needs one weight per radius ({} radii, {} weights)", radii.size(),
                  weights.size());
  }
  for (std::size_t j = 0; j < radii.size(); ++j) {
    if (!(radii[j] >= 0.0) || (j > 0 && !(radii[j] > radii[j - 1]))) {
      throw_invalid("GPI radii must be >= 0 and strictly ascending (radius {} = {})", j, radii[j]);
    }
    if (!std::isfinite(weights[j])) throw_invalid("GPI weight {} is not finite", j);
  }
  if (!(right.a > 0.0) || !(left.a > 0.0)) {
    throw_invalid("GPI envelopes must be strictly increasing (a_R = {}, a_L = {})", right.a,
                  left.a);
  }
  if (!(v_min < v_max)) throw_invalid("GPI input range [{}, {}] is empty", v_min, v_max);
  for (double v : {v_min, v_max}) {
    if (right(v) - radii.front() > left(v) + radii.front() + 1e-12) {
      throw_invalid(
          "GPI envelopes break order preservation at v = {}: gamma_R - r_0 = {} > gamma_L + r_0 = "
          "{}",
          v, right(v) - radii.front(), left(v) + radii.front());
    }
  }
  bool pos = false, neg = false;
  for (double p : weights) {
    pos = pos || p > 0.0;
    neg = neg || p < 0.0;
  }
  if (pos && neg) throw_invalid("GPI weights must keep one sign for the model to be invertible");
}

int GpiModel::direction() const {
  double s = 0.0;
  for (double p : weights) s += p;
  return s >= 0.0 ? 1 : -1;
}

GpiState GpiState::at_lower_turning_point(const GpiModel& m, double v0) {
  GpiState s;
  s.v = std::clamp(v0, m.v_min, m.v_max);
  s.w.resize(m.radii.size());
  for (std::size_t j = 0; j < m.radii.size(); ++j) s.w[j] = m.left(s.v) + m.radii[j];
  return s;
}

double gpi_output(const GpiModel& m, const GpiState& s) {
  double y = m.bias;
  for (std::size_t j = 0; j < s.w.size(); ++j) y += m.weights[j] * s.w[j];
  return y;
}

double gpi_step(const GpiModel& m, GpiState& s, double v) {
  v = std::clamp(v, m.v_min, m.v_max);
  const double gr = m.right(v), gl = m.left(v);
  double y = m.bias;
  for (std::size_t j = 0; j < s.w.size(); ++j) {
    s.w[j] = std::min(gl + m.radii[j], std::max(gr - m.radii[j], s.w[j]));
    y += m.weights[j] * s.w[j];
  }
  s.v = v;
  return y;
}

std::vector<double> gpi_simulate(const GpiModel& m, GpiState& s, std::span<const double> v) {
  std::vector<double> y;
  y.reserve(v.size());
  for (double x : v) y.push_back(gpi_step(m, s, x));
  return y;
}

}  // namespace scpkit
