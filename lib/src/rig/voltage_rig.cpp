// The rig's voltage side: an SCP actuator under several constant loads, driven by a damped
// voltage oscillation per load (paper 000 protocol), with the truth y = f2(F) H[v] + f1(F).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "scpkit/error.hpp"
#include "scpkit/rig/rig.hpp"
#include "sensor.hpp"

namespace scpkit {
namespace {

constexpr double kGram = 9.80665e-3;

// Normalises an operator so that its first rise from v = 0 to v_max goes from 0 to -1.
HysteresisOperator normalised(const HysteresisOperator& raw, double v_max) {
  std::vector<double> rise;
  for (int k = 0; k <= 200; ++k) rise.push_back(v_max * k / 200.0);
  const std::vector<double> y = raw.simulate(rise);
  const double h0 = y.front(), h1 = y.back();
  if (!(std::abs(h0 - h1) > 0.0)) throw_invalid("rig: degenerate voltage truth");
  return raw.with_output_affine(1.0 / (h0 - h1), -h0 / (h0 - h1));
}

std::vector<double> voltage_protocol(const VoltageProtocol& p) {
  std::vector<double> v{0.0};
  const int turns = 2 * p.cycles;
  auto ramp = [&](double to) {
    const double from = v.back();
    for (int k = 1; k <= p.steps_per_half; ++k)
      v.push_back(from + (to - from) * k / p.steps_per_half);
  };
  const bool damped = p.shape == "damped";
  for (int k = 0; k < turns; ++k) {
    const double f = damped ? static_cast<double>(k) / turns : 0.0;
    ramp(k % 2 == 0 ? p.v_max * (1.0 - 0.3 * f) : p.v_max * 0.3 * f);
  }
  if (v.back() != 0.0) ramp(0.0);
  return v;
}

// The two shapes of H the rig knows, normalised (first rise from 0 to v_max: 0 -> -1).
HysteresisOperator voltage_h(const std::string& shape, double v_max) {
  if (shape == "gpi") {
    GpiModel g;  // paper 000's identified envelopes, radii r_j = j / 10, falling weights
    g.right = {1.100, 0.048};
    g.left = {1.236, 0.088};
    for (int j = 0; j <= 10; ++j) {
      g.radii.push_back(j / 10.0);
      g.weights.push_back(-std::exp(-j / 3.0));
    }
    g.v_min = 0.0;
    g.v_max = v_max;
    return normalised(HysteresisOperator(g), v_max);
  }
  const PreisachGrid grid{0.0, v_max, 30};  // a smooth falling density
  Eigen::VectorXd w(grid.cells());
  for (int i = 0; i < grid.levels; ++i) {
    for (int j = i; j < grid.levels; ++j) {
      const double b = (i + 0.5) / grid.levels, a = (j + 0.5) / grid.levels;
      w[grid.cell_index(i, j)] =
          -PreisachGrid::relative_area(i, j) *
          std::exp(-std::pow((a - b - 0.1) / 0.12, 2) - std::pow((a + b - 1.1) / 0.6, 2));
    }
  }
  return normalised(HysteresisOperator(PreisachModel(grid, w, 0.0)), v_max);
}

}  // namespace

VoltageTruth rig_voltage_truth(const RigSpec& spec) {
  VoltageTruth t{voltage_h(spec.voltage.truth, spec.voltage.v_max), {}, {}};
  // Paper 000 Eqs. 14-15 (F in mN, metres) as strain of a 70 mm actuator, F in N:
  // D(F) = 8.685e-3 F^2 - 2.935e-2 F + 0.045,  P(F) = -2.039e-3 F^2 + 5.527e-3 F - 0.005.
  const double L = 0.070, F0 = 0.294;
  const double D0 = 8.685e-3 * F0 * F0 - 2.935e-2 * F0 + 0.045;
  t.f1 = {-(0.045 - D0) / L, 2.935e-2 / L, -8.685e-3 / L};
  t.f2 = {0.005 / L, -5.527e-3 / L, 2.039e-3 / L};
  return t;
}

RigRun run_voltage_rig(const RigSpec& spec) {
  const VoltageTruth truth = rig_voltage_truth(spec);
  const VoltageProtocol& p = spec.voltage;
  const std::vector<double> v_one = voltage_protocol(p);
  const std::vector<double> dwell =
      detail::dwell_times(v_one.size() * p.loads_g.size(), p.dwell_s, p.dwell_spread, spec.seed);
  std::vector<double> time_s, load_g, volts, strain, segment, dwell_col;
  std::mt19937_64 rng(spec.seed);
  const RigEffects& e = spec.effects;
  double t = 0.0, viscous = 0.0;
  double range = 0.0;  // nominal strain range for drift and outliers: the largest f2
  for (double g : p.loads_g) range = std::max(range, std::abs(truth.f2(g * kGram)));
  const auto [g_lo, g_hi] = std::minmax_element(p.loads_g.begin(), p.loads_g.end());
  const double F_lo = *g_lo * kGram, dF = std::max((*g_hi - *g_lo) * kGram, 1e-9);
  // Effects on the maps and on H's shape.
  const std::vector<double> h2 =
      voltage_h(p.truth == "gpi" ? "preisach" : "gpi", p.v_max).simulate(v_one);
  auto knee = [&](double F) { return std::exp(-(F - F_lo) / (0.2 * dF)); };
  for (std::size_t k = 0; k < p.loads_g.size(); ++k) {
    const double F = p.loads_g[k] * kGram;
    std::vector<double> h = truth.h.simulate(v_one);  // each load from H's initial state
    const double w = e.load_shape_coupling * (F - F_lo) / dF;
    for (std::size_t i = 0; i < h.size(); ++i) h[i] = (1.0 - w) * h[i] + w * h2[i];
    const double f1 = truth.f1(F) + e.offset_nonlinearity * range * knee(F);
    const double f2 = truth.f2(F) * (1.0 - e.offset_nonlinearity * knee(F));
    double running_max = 0.0;
    for (std::size_t i = 0; i < v_one.size(); ++i) {
      const double hold = dwell[k * v_one.size() + i];
      for (int j = 1; j <= p.readings_per_hold; ++j) {
        const double dt = hold / p.readings_per_hold;
        t += dt;
        double y = f2 * h[i] + f1;
        if (e.creep > 0.0) {
          if (i == 0 && j == 1) viscous = y;
          viscous = y + (viscous - y) * std::exp(-dt / e.creep_tau_s);
          y = (1.0 - e.creep) * y + e.creep * viscous;
        }
        // Lonely stroke, re-armed at every load change: the first rise differs from later
        // cycles; after a load increase the repeatable loop may lie on the other side (paper
        // 001's open case, the default), so the offset may change sign.
        running_max = std::max(running_max, v_one[i]);
        const double lonely_sign =
            k > 0 && p.loads_g[k] > p.loads_g[k - 1] ? e.lonely_sign_after_increase : 1.0;
        y -= lonely_sign * e.lonely_stroke * f2 * running_max / p.v_max;
        time_s.push_back(t);
        dwell_col.push_back(hold * j / p.readings_per_hold);
        load_g.push_back(p.loads_g[k]);
        volts.push_back(v_one[i]);
        strain.push_back(y);
        segment.push_back(static_cast<double>(k));
      }
    }
  }
  const std::vector<double> pct = detail::measure_channel(strain, time_s, range, spec, rng);
  RigRun run;
  run.metadata["specimen"] = "scp";
  run.metadata["length_mm"] = fmt::format("{:g}", spec.length_mm);
  run.metadata["synthetic"] =
      fmt::format("scpkit virtual test rig (voltage tests), seed {}", spec.seed);
  run.metadata["truth_h"] =
      p.truth == "gpi"
          ? "gpi: paper 000 envelopes (aR 1.100, bR 0.048, aL 1.236, bL 0.088), r_j = j/10"
          : "preisach: smooth falling density, L 30";
  run.metadata["truth_f1"] = fmt::format("{:.6g} {:+.6g} F {:+.6g} F^2 (strain, F in N)",
                                         truth.f1.c0, truth.f1.c1, truth.f1.c2);
  run.metadata["truth_f2"] = fmt::format("{:.6g} {:+.6g} F {:+.6g} F^2 (strain, F in N)",
                                         truth.f2.c0, truth.f2.c1, truth.f2.c2);
  run.metadata["truth_effects"] = detail::effects_text(e);
  run.metadata["sensor"] =
      fmt::format("resolution {:g} mm, noise {:g} mm", spec.resolution_mm, spec.noise_mm);
  run.columns = {"time_s", "dwell_s", "segment", "load_g", "voltage_V", "disp_mm"};
  for (std::size_t i = 0; i < time_s.size(); ++i) {
    run.rows.push_back({time_s[i], dwell_col[i], segment[i], load_g[i], volts[i],
                        pct[i] * spec.length_mm / 100.0});
  }
  return run;
}

}  // namespace scpkit
