#include "scpkit/design/design.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "scpkit/error.hpp"

namespace scpkit {
namespace {

constexpr double kGram = 9.80665e-3;

void ramp(std::vector<double>& out, double from, double to, int steps) {
  for (int k = 1; k <= steps; ++k) out.push_back(from + (to - from) * k / steps);
}

}  // namespace

double wire_diameter_for(const Material& material, const ThreadCharacterisation& ch, int plies) {
  if (const ReferenceGeometry* g = material.geometry_for(plies)) return g->coil.wire_d_m;
  return ch.coil.wire_d_m * std::sqrt(static_cast<double>(plies) / ch.plies);
}

DesignResult evaluate_design(const ThreadCharacterisation& ch, const Material& material,
                             const DesignSpec& spec, DesignWorkspace& ws, bool keep_curve) {
  if (ch.plies < 1 || ch.scp_gain.gain == 0.0)
    throw_invalid("design: the characterisation needs plies and an SCP gain");
  DesignResult r;
  auto infeasible = [&](std::string why) {
    if (r.feasible) {
      r.feasible = false;
      r.reason = std::move(why);
    }
  };
  const CoilGeometry& c = spec.coil;
  const int q = spec.plies;
  if (q < 1) {
    infeasible("ply count below 1");
    return r;
  }
  if (!(c.wire_d_m > 0.0) || !(c.mean_D_m > 0.0) || !(c.coils > 0.0) ||
      (c.legs != 1 && c.legs != 2) || !(c.length_m > 0.0)) {
    infeasible("incomplete coil (d, D, n, legs 1/2 and length are needed)");
    return r;
  }
  r.spring_index = c.spring_index();
  r.pitch_mm = c.length_m * 1e3 * c.legs / c.coils;  // each leg carries n / legs coils
  if (r.spring_index < 1.0) {
    infeasible(fmt::format("spring index {:.3g} < 1: the mean diameter is below the wire diameter",
                           r.spring_index));
    return r;
  }
  if (r.pitch_mm < c.wire_d_m * 1e3) {
    infeasible(
        fmt::format("pitch {:.3g} mm < wire diameter {:.3g} mm: {} coils do not fit in {:.4g} mm",
                    r.pitch_mm, c.wire_d_m * 1e3, c.coils, c.length_m * 1e3));
  }
  r.stiffness_N_per_m = spring_stiffness(material.shear_modulus_Pa, c, spec.tolerances);
  const Uncertain gq = predict_scp_gain(ch.scp_gain.gain, ch.plies, ch.coil, q, c, spec.tolerances);
  r.gain = gq;
  const double scale =
      static_cast<double>(ch.plies) / q;  // per-ply load of the q-ply thread, in p-ply terms
  const double allowed_lo = ch.load_min_N / scale, allowed_hi = ch.load_max_N / scale;
  const double tol = 1e-6 * allowed_hi;
  const double lo = spec.protocol_N.empty()
                        ? spec.load_min_N
                        : *std::min_element(spec.protocol_N.begin(), spec.protocol_N.end());
  const double hi = spec.protocol_N.empty()
                        ? spec.load_max_N
                        : *std::max_element(spec.protocol_N.begin(), spec.protocol_N.end());
  if (!(hi > lo)) {
    infeasible("the working loads are empty (max <= min)");
    return r;
  }
  if (lo < allowed_lo - tol || hi > allowed_hi + tol) {
    infeasible(
        fmt::format("loads {:.4g}-{:.4g} g lie outside the identified {:.4g}-{:.4g} g for {} plies "
                    "(per-ply scaling)",
                    lo / kGram, hi / kGram, allowed_lo / kGram, allowed_hi / kGram, q));
  }

  // Protocol: warm-up cycle, then the measured major-loop cycle (or the given sequence).
  ws.loads.clear();
  std::size_t k0 = 0;
  const int half = std::max(1, spec.protocol_steps / 2);
  const PreisachGrid& grid = ch.thread.grid();
  if (spec.protocol_N.empty()) {
    // The memory a warm-up cycle lo -> hi -> lo leaves, written down directly: negative
    // saturation, the maximum hi, the minimum lo (exactly what applying them would give).
    ws.loads.push_back(lo);
    k0 = 0;
    ramp(ws.loads, lo, hi, half);
    ramp(ws.loads, hi, lo, half);
    const double a = std::clamp(scale * hi, grid.lo, grid.hi),
                 b = std::clamp(scale * lo, grid.lo, grid.hi);
    ws.state.reset(grid);
    ws.state.apply(a);
    ws.state.apply(b);
  } else {
    ws.loads.assign(spec.protocol_N.begin(), spec.protocol_N.end());
    ws.state.reset(grid);
  }
  const double g = gq.value, offset = ch.scp_gain.offset * gq.value / ch.scp_gain.gain;
  ws.strain.resize(ws.loads.size());
  for (std::size_t k = 0; k < ws.loads.size(); ++k) {
    ws.strain[k] = g * ch.thread.step(ws.state, scale * ws.loads[k]) + offset;
  }
  double stroke;
  if (spec.protocol_N.empty()) {
    const auto h = static_cast<std::size_t>(half);
    stroke = ws.strain[k0 + h] - ws.strain[k0];
    double gap = 0.0;
    for (std::size_t i = 0; i <= h; ++i) {
      gap = std::max(gap, std::abs(ws.strain[k0 + 2 * h - i] - ws.strain[k0 + i]));
    }
    r.hysteresis_pct = stroke != 0.0 ? 100.0 * gap / std::abs(stroke) : 0.0;
  } else {
    const auto [mn, mx] = std::minmax_element(ws.strain.begin(), ws.strain.end());
    stroke = *mx - *mn;
    r.hysteresis_pct = -1.0;  // defined on the major loop only
  }
  r.stroke_pct = 100.0 * stroke;
  r.stroke_mm = stroke * c.length_m * 1e3;
  r.stroke_sigma_mm = std::abs(r.stroke_mm) * gq.relative();
  double peak = 0.0;
  for (double e : ws.strain) peak = std::max(peak, std::abs(e));
  if (100.0 * peak > spec.max_strain_pct) {
    infeasible(
        fmt::format("predicted strain {:.3g} % beyond the {:g} % SCP actuators reach (spring-model "
                    "extrapolation)",
                    100.0 * peak, spec.max_strain_pct));
  }
  if (keep_curve) {
    r.strain_pct.resize(ws.strain.size());
    for (std::size_t k = 0; k < ws.strain.size(); ++k) r.strain_pct[k] = 100.0 * ws.strain[k];
  }

  // Voltage side.
  if (ch.voltage && spec.working_load_N > 0.0) {
    const AugmentedModel& v = *ch.voltage;
    const int p_ref = ch.voltage_plies > 0 ? ch.voltage_plies : ch.plies;
    const double F_ref = spec.working_load_N * p_ref / q;
    r.voltage_extrapolated = v.outside_load_range(F_ref);
    const double f2q = v.f2(F_ref) * gq.value / ch.scp_gain.gain;
    r.thermal_stroke_mm = f2q * c.length_m * 1e3;
    if (100.0 * std::abs(f2q) > spec.max_strain_pct) {
      infeasible(fmt::format(
          "thermal strain {:.3g} % beyond the {:g} % SCP actuators reach (transfer extrapolation)",
          100.0 * std::abs(f2q), spec.max_strain_pct));
    }
    if (spec.target_stroke_mm > 0.0 && ch.voltage_length_mm > 0.0) {
      const double h_target =
          -spec.target_stroke_mm / r.thermal_stroke_mm;  // H runs 0 -> -1 on the first rise
      const std::vector<InverseStep> s = v.h.invert(std::span<const double>(&h_target, 1));
      if (s.front().reached && h_target >= -1.0 && h_target <= 0.0) {
        r.voltage_for_target_V = s.front().input * (c.length_m * 1e3) / ch.voltage_length_mm;
      }
    }
  }
  return r;
}

}  // namespace scpkit
