#include "scpkit/rig/rig.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>

#include "../io/toml_reader.hpp"
#include "scpkit/error.hpp"
#include "sensor.hpp"

namespace scpkit {
namespace {

constexpr double kGram = 9.80665e-3;      // N per gram-force
constexpr double kTruthMaxPerPlyN = 2.0;  // the truth's plane covers 0..2 N per ply (204 g)

}  // namespace

void RigSpec::validate() const {
  if (test != "load" && test != "voltage")
    throw_invalid("test must be load or voltage, got '{}'", test);
  if (test == "voltage") {
    const VoltageProtocol& v = voltage;
    if (v.loads_g.empty()) throw_invalid("voltage tests need at least one load");
    for (double g : v.loads_g) {
      if (!(g > 0.0) || !std::isfinite(g)) throw_invalid("voltage-test loads must be > 0 g");
    }
    if (!(v.v_max > 0.0)) throw_invalid("v_max must be > 0");
    if (v.cycles < 1 || v.steps_per_half < 1 || v.readings_per_hold < 1)
      throw_invalid("voltage protocol counts must be positive");
    if (!(v.dwell_s > 0.0)) throw_invalid("voltage dwell_s must be > 0");
    if (v.shape != "damped" && v.shape != "repeated")
      throw_invalid("voltage protocol shape must be damped or repeated, got '{}'", v.shape);
    if (v.truth != "gpi" && v.truth != "preisach")
      throw_invalid("voltage truth must be gpi or preisach, got '{}'", v.truth);
    if (effects.minor_loop_noncongruence > 0.0)
      throw_invalid("minor_loop_noncongruence applies to load tests only");
    if (!(v.dwell_spread >= 0.0) || !std::isfinite(v.dwell_spread))
      throw_invalid("dwell_spread must be finite and >= 0");
    if (effects.load_shape_coupling > 1.0) throw_invalid("load_shape_coupling must be <= 1");
    if (effects.offset_nonlinearity > 0.9) throw_invalid("offset_nonlinearity must be <= 0.9");
  } else if (effects.load_shape_coupling > 0.0 || effects.offset_nonlinearity > 0.0) {
    throw_invalid(
        "load_shape_coupling and offset_nonlinearity apply to voltage tests (several loads) only");
  }
  if (specimen != "thread" && specimen != "scp" && specimen != "pair") {
    throw_invalid("specimen must be thread, scp or pair, got '{}'", specimen);
  }
  if (plies < 1 || plies > 100) throw_invalid("plies must be 1..100, got {}", plies);
  if (!(length_mm > 0.0)) throw_invalid("length_mm must be > 0");
  if (!(resolution_mm >= 0.0) || !(noise_mm >= 0.0))
    throw_invalid("sensor resolution and noise must be >= 0");
  const LoadProtocol& p = protocol;
  if (!(p.min_g >= 0.0) || !(p.max_g > p.min_g)) throw_invalid("protocol needs 0 <= min_g < max_g");
  if (p.cycles < 1 || p.steps_per_half < 1 || p.minor_loops < 0 || p.readings_per_hold < 1)
    throw_invalid("protocol counts must be positive");
  if (p.shape != "damped" && p.shape != "repeated")
    throw_invalid("protocol shape must be damped or repeated, got '{}'", p.shape);
  if (!(p.dwell_s > 0.0)) throw_invalid("dwell_s must be > 0");
  if (!(p.dwell_spread >= 0.0) || !std::isfinite(p.dwell_spread))
    throw_invalid("dwell_spread must be finite and >= 0");
  const RigEffects& e = effects;
  for (double v : {e.creep, e.drift, e.lonely_stroke, e.outliers, e.minor_loop_noncongruence,
                   e.load_shape_coupling, e.offset_nonlinearity}) {
    if (!(v >= 0.0) || !std::isfinite(v))
      throw_invalid("effect magnitudes must be finite and >= 0");
  }
  if (e.lonely_sign_after_increase != 1.0 && e.lonely_sign_after_increase != -1.0)
    throw_invalid("lonely_sign_after_increase must be -1 or +1");
  if (e.creep > 1.0) throw_invalid("creep is a fraction of the strain, <= 1");
  if (e.minor_loop_noncongruence > 1.0)
    throw_invalid("minor_loop_noncongruence must be <= 1 (the output map stays monotone)");
  if (!(e.creep_tau_s > 0.0)) throw_invalid("creep_tau_s must be > 0");
  if (coil) coil->validate();
  if (load_sequence_g) {
    if (load_sequence_g->size() < 2) throw_invalid("load_sequence_g needs at least 2 loads");
    for (double g : *load_sequence_g) {
      if (!(g >= 0.0) || !std::isfinite(g)) throw_invalid("loads must be finite and >= 0 g");
      if (g * kGram / plies > kTruthMaxPerPlyN)
        throw_invalid("load {} g exceeds the rig's {} N per ply", g, kTruthMaxPerPlyN);
    }
  }
  const double scale = p.scale_with_plies ? plies / 2.0 : 1.0;
  if (p.max_g * scale * kGram / plies > kTruthMaxPerPlyN) {
    throw_invalid("protocol max load exceeds the rig's {} N per ply", kTruthMaxPerPlyN);
  }
}

RigSpec load_rig_spec(const std::filesystem::path& path) {
  using detail::TomlReader;
  const toml::table root = TomlReader::parse(path);
  const TomlReader r(path.string());
  r.only_keys(root, {"seed", "test", "specimen", "plies", "material", "length_mm", "scp_offset_pct",
                     "coil", "protocol", "voltage", "sensor", "effects", "load_sequence_g"});
  RigSpec s;
  s.seed = static_cast<std::uint64_t>(r.integer(root, "seed", 1, 0, 1LL << 62));
  s.test = r.text(root, "test", s.test);
  s.specimen = r.text(root, "specimen", s.specimen);
  if (const toml::table* v = r.table(root, "voltage")) {
    r.only_keys(*v, {"loads_g", "v_max", "shape", "cycles", "steps_per_half", "dwell_s",
                     "dwell_spread", "readings_per_hold", "truth"});
    VoltageProtocol& q = s.voltage;
    if (const toml::node* n = v->get("loads_g")) {
      const toml::array* a = n->as_array();
      if (!a) r.fail(n, "'loads_g' must be an array of numbers");
      q.loads_g.clear();
      for (const toml::node& x : *a) {
        const auto g = x.value<double>();
        if (!g) r.fail(&x, "'loads_g' must hold numbers");
        q.loads_g.push_back(*g);
      }
    }
    q.v_max = r.positive(*v, "v_max", q.v_max, false);
    q.shape = r.text(*v, "shape", q.shape);
    if (q.shape != "damped" && q.shape != "repeated")
      r.fail(v->get("shape"), fmt::format("'shape' must be damped or repeated, got '{}'", q.shape));
    q.cycles = static_cast<int>(r.integer(*v, "cycles", q.cycles, 1, 1000));
    q.steps_per_half =
        static_cast<int>(r.integer(*v, "steps_per_half", q.steps_per_half, 1, 10000));
    q.dwell_s = r.positive(*v, "dwell_s", q.dwell_s, false);
    q.dwell_spread = r.number(*v, "dwell_spread", q.dwell_spread, 0.0);
    q.readings_per_hold =
        static_cast<int>(r.integer(*v, "readings_per_hold", q.readings_per_hold, 1, 1000));
    q.truth = r.text(*v, "truth", q.truth);
  }
  s.plies = static_cast<int>(r.integer(root, "plies", s.plies, 1, 100));
  s.material = r.text(root, "material", s.material);
  s.length_mm = r.positive(root, "length_mm", s.length_mm, false);
  s.scp_offset_pct = r.number(root, "scp_offset_pct", s.scp_offset_pct, -100.0);
  if (const toml::table* c = r.table(root, "coil")) {
    r.only_keys(*c, {"d_mm", "D_mm", "n", "legs"});
    CoilGeometry g;
    g.wire_d_m = r.positive(*c, "d_mm") * 1e-3;
    g.mean_D_m = r.positive(*c, "D_mm") * 1e-3;
    g.coils = r.positive(*c, "n");
    g.legs = static_cast<int>(r.integer(*c, "legs", 2, 1, 2));
    s.coil = g;
  }
  if (const toml::table* p = r.table(root, "protocol")) {
    r.only_keys(*p, {"min_g", "max_g", "scale_with_plies", "shape", "cycles", "steps_per_half",
                     "minor_loops", "congruency", "readings_per_hold", "dwell_s", "dwell_spread"});
    LoadProtocol& q = s.protocol;
    q.min_g = r.number(*p, "min_g", q.min_g, 0.0);
    q.max_g = r.positive(*p, "max_g", q.max_g, false);
    q.scale_with_plies = r.boolean(*p, "scale_with_plies", q.scale_with_plies);
    q.cycles = static_cast<int>(r.integer(*p, "cycles", q.cycles, 1, 10000));
    q.steps_per_half =
        static_cast<int>(r.integer(*p, "steps_per_half", q.steps_per_half, 1, 10000));
    q.minor_loops = static_cast<int>(r.integer(*p, "minor_loops", q.minor_loops, 0, 10000));
    q.dwell_s = r.positive(*p, "dwell_s", q.dwell_s, false);
    q.dwell_spread = r.number(*p, "dwell_spread", q.dwell_spread, 0.0);
    q.shape = r.text(*p, "shape", q.shape);
    if (q.shape != "damped" && q.shape != "repeated")
      r.fail(p->get("shape"), fmt::format("'shape' must be damped or repeated, got '{}'", q.shape));
    q.congruency = r.boolean(*p, "congruency", q.congruency);
    q.readings_per_hold =
        static_cast<int>(r.integer(*p, "readings_per_hold", q.readings_per_hold, 1, 1000));
  }
  if (const toml::table* p = r.table(root, "sensor")) {
    r.only_keys(*p, {"resolution_mm", "noise_mm"});
    s.resolution_mm = r.number(*p, "resolution_mm", s.resolution_mm, 0.0);
    s.noise_mm = r.number(*p, "noise_mm", s.noise_mm, 0.0);
  }
  if (const toml::table* p = r.table(root, "effects")) {
    r.only_keys(
        *p, {"creep", "creep_tau_s", "drift", "lonely_stroke", "lonely_sign_after_increase",
             "outliers", "minor_loop_noncongruence", "load_shape_coupling", "offset_nonlinearity"});
    RigEffects& e = s.effects;
    e.creep = r.number(*p, "creep", 0.0, 0.0);
    e.creep_tau_s = r.positive(*p, "creep_tau_s", e.creep_tau_s, false);
    e.drift = r.number(*p, "drift", 0.0, 0.0);
    e.lonely_stroke = r.number(*p, "lonely_stroke", 0.0, 0.0);
    e.lonely_sign_after_increase =
        r.number(*p, "lonely_sign_after_increase", e.lonely_sign_after_increase, -1.0);
    e.outliers = r.number(*p, "outliers", 0.0, 0.0);
    e.minor_loop_noncongruence = r.number(*p, "minor_loop_noncongruence", 0.0, 0.0);
    e.load_shape_coupling = r.number(*p, "load_shape_coupling", 0.0, 0.0);
    e.offset_nonlinearity = r.number(*p, "offset_nonlinearity", 0.0, 0.0);
  }
  if (const toml::node* n = root.get("load_sequence_g")) {
    const toml::array* a = n->as_array();
    if (!a) r.fail(n, "'load_sequence_g' must be an array of numbers");
    std::vector<double> loads;
    for (const toml::node& x : *a) {
      const auto v = x.value<double>();
      if (!v) r.fail(&x, "'load_sequence_g' must hold numbers");
      loads.push_back(*v);
    }
    s.load_sequence_g = loads;
  }
  try {
    s.validate();
  } catch (const InvalidArgument& e) {
    r.fail(nullptr, e.what());
  }
  return s;
}

PreisachModel rig_thread_truth(const Material& material) {
  // A fine Preisach plane over the per-ply load: a ridge of loop width ~0.25 N and an
  // elastic band along the diagonal, softer at low load (textile threads stiffen as the
  // filaments straighten). Scaled so that the rising branch from 0 to 125 g per ply spans
  // F / (E A), the elastic strain of the card's thread.
  const PreisachGrid grid{0.0, kTruthMaxPerPlyN, 40};
  Eigen::VectorXd w(grid.cells());
  const double h = grid.step();
  for (int i = 0; i < grid.levels; ++i) {
    for (int j = i; j < grid.levels; ++j) {
      const double beta = (i + 0.5) * h, alpha = (j + (i == j ? 0.75 : 0.5)) * h;
      const double width = alpha - beta, mean = 0.5 * (alpha + beta);
      const double hysteretic = std::exp(-std::pow((width - 0.3) / 0.3, 2));
      const double elastic = 3.0 * std::exp(-std::pow(width / 0.06, 2));
      const double softening = 1.0 + 0.8 * std::exp(-mean / 0.4);
      w[grid.cell_index(i, j)] =
          PreisachGrid::relative_area(i, j) * (hysteretic + elastic) * softening;
    }
  }
  PreisachModel unit(grid, w, 0.0);
  const double f_ref = 125.0 * kGram;
  PreisachState s = PreisachState::negative_saturation(grid);
  const double y0 = unit.step(s, 0.0);
  const double y1 = unit.step(s, f_ref);
  const double target = f_ref / (material.tensile_modulus_Pa.value * material.ply_area_m2());
  const double scale = target / (y1 - y0);
  return PreisachModel(grid, w * scale, unit.total_mass() * scale);  // zero strain at 0 N
}

std::vector<double> rig_load_protocol(const RigSpec& spec) {
  if (spec.load_sequence_g) return *spec.load_sequence_g;
  const LoadProtocol& p = spec.protocol;
  const double scale = p.scale_with_plies ? spec.plies / 2.0 : 1.0;
  const double lo = p.min_g * scale, hi = p.max_g * scale;
  const double mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  std::vector<double> loads{lo};
  auto ramp = [&](double to) {
    const double from = loads.back();
    for (int k = 1; k <= p.steps_per_half; ++k)
      loads.push_back(from + (to - from) * k / p.steps_per_half);
  };
  const int turns = 2 * p.cycles;
  if (p.shape == "repeated") {
    for (int k = 1; k <= turns; ++k) ramp(k % 2 == 1 ? hi : lo);
  } else {
    // Damped oscillation: amplitude falls geometrically to 15 % over the cycles.
    const double decay = std::pow(0.15, 1.0 / std::max(turns - 1, 1));
    double amp = half;
    for (int k = 1; k <= turns; ++k) {
      ramp(k % 2 == 1 ? mid + amp : mid - amp);
      amp *= decay;
    }
  }
  // Minor loops, each traversed twice, inside the range: after a common maximum, and (with
  // `congruency`) once more after the minimum (the loop's upper turning point b then reached
  // from below, so the two runs of the loop start from different memories).
  std::mt19937_64 rng(spec.seed * 7919 + 17);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  for (int m = 0; m < p.minor_loops; ++m) {
    const double a = lo + (hi - lo) * 0.6 * U(rng);
    const double b = a + (hi - a) * (0.3 + 0.6 * U(rng));
    auto loop = [&] {
      for (int rep = 0; rep < 2; ++rep) {
        ramp(a);
        ramp(b);
      }
    };
    ramp(hi);
    loop();
    if (p.congruency) {
      ramp(lo);
      loop();
    }
  }
  ramp(lo);
  return loads;
}

RigRun run_voltage_rig(const RigSpec& spec);  // voltage_rig.cpp

RigRun run_rig(const RigSpec& spec, const Material& material) {
  spec.validate();
  if (spec.test == "voltage") return run_voltage_rig(spec);
  CoilGeometry coil;
  if (spec.coil) {
    coil = *spec.coil;
  } else if (const ReferenceGeometry* g = material.geometry_for(spec.plies)) {
    coil = g->coil;
  } else if (spec.specimen != "thread") {
    throw_invalid("no coil given and material '{}' has no geometry for {} plies", material.id,
                  spec.plies);
  }
  const double length_m = spec.length_mm * 1e-3;
  double gain = 0.0;
  if (spec.specimen != "thread") {
    coil.length_m = length_m;
    gain = material.thread_stiffness(spec.plies, length_m) /
           spring_stiffness(material.shear_modulus_Pa.value, coil);
  }
  const PreisachModel truth = rig_thread_truth(material);
  const std::vector<double> loads_g = rig_load_protocol(spec);
  std::mt19937_64 rng(spec.seed);

  // Nominal ranges for scaling the effects.
  const auto [lmin, lmax] = std::minmax_element(loads_g.begin(), loads_g.end());
  const double f_lo = *lmin * kGram / spec.plies, f_hi = *lmax * kGram / spec.plies;
  const double f_range = std::max(f_hi - f_lo, 1e-9);
  const double y_range = f_range / (material.tensile_modulus_Pa.value * material.ply_area_m2());
  const RigEffects& e = spec.effects;

  const std::vector<double> dwell = detail::dwell_times(loads_g.size(), spec.protocol.dwell_s,
                                                        spec.protocol.dwell_spread, spec.seed);
  const detail::Readings readings =
      detail::readings_during_holds(dwell, spec.protocol.readings_per_hold);
  const std::size_t n = readings.step.size();
  std::vector<double> material_strain(n), time_s(n);
  PreisachState state = PreisachState::negative_saturation(truth.grid());
  double viscous = 0.0, running_max = f_lo, t = 0.0, y_ref = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    t += readings.dt[k];
    time_s[k] = t;
    const double f = loads_g[readings.step[k]] * kGram / spec.plies;
    double y = truth.step(state, f);
    if (k == 0) y_ref = y;
    if (e.minor_loop_noncongruence > 0.0) {
      // Output-dependent loop height: a monotone quadratic map of the Preisach output keeps
      // wiping-out but scales each loop's height by 1 + 2 a z at its output level z, so loops
      // between the same extrema after different histories differ (congruency fails).
      const double z = std::max(0.0, (y - y_ref) / y_range);
      y += e.minor_loop_noncongruence * y_range * z * z;
    }
    if (e.creep > 0.0) {
      viscous = y + (viscous - y) * std::exp(-readings.dt[k] / e.creep_tau_s);
      y = (1.0 - e.creep) * y + e.creep * viscous;
    }
    running_max = std::max(running_max, f);
    y += e.lonely_stroke * y_range * (running_max - f_lo) / f_range;
    material_strain[k] = y;
  }

  // One measured channel: strain -> drift, outliers, sensor noise and quantisation.
  auto measure = [&](double g, double offset) {
    std::vector<double> strain(n);
    for (std::size_t k = 0; k < n; ++k) strain[k] = g * material_strain[k] + offset;
    return detail::measure_channel(strain, time_s, std::abs(g) * y_range, spec, rng);
  };

  RigRun run;
  run.true_gain = gain;
  run.metadata["specimen"] = spec.specimen;
  run.metadata["plies"] = std::to_string(spec.plies);
  run.metadata["length_mm"] = fmt::format("{:g}", spec.length_mm);
  run.metadata["material"] = material.id;
  if (spec.specimen != "thread") {
    run.metadata["coil_d_mm"] = fmt::format("{:g}", coil.wire_d_m * 1e3);
    run.metadata["coil_D_mm"] = fmt::format("{:g}", coil.mean_D_m * 1e3);
    run.metadata["coil_n"] = fmt::format("{:g}", coil.coils);
    run.metadata["legs"] = std::to_string(coil.legs);
    run.metadata["truth_gain"] = fmt::format("{:.6g}", gain);
  }
  run.metadata["synthetic"] = fmt::format("scpkit virtual test rig, seed {}", spec.seed);
  run.metadata["truth_effects"] = detail::effects_text(e);
  run.metadata["sensor"] =
      fmt::format("resolution {:g} mm, noise {:g} mm", spec.resolution_mm, spec.noise_mm);

  const std::vector<double> thread =
      spec.specimen != "scp" ? measure(1.0, 0.0) : std::vector<double>{};
  const std::vector<double> scp = spec.specimen != "thread"
                                      ? measure(gain, spec.scp_offset_pct / 100.0)
                                      : std::vector<double>{};
  if (spec.specimen == "pair") {
    run.columns = {"time_s", "dwell_s", "load_g", "thread_strain_pct", "scp_strain_pct"};
  } else {
    run.columns = {"time_s", "dwell_s", "load_g", "disp_mm"};
  }
  for (std::size_t k = 0; k < n; ++k) {
    std::vector<double> row{time_s[k], readings.held[k], loads_g[readings.step[k]]};
    if (spec.specimen == "pair") {
      row.push_back(thread[k]);
      row.push_back(scp[k]);
    } else {
      row.push_back((spec.specimen == "thread" ? thread[k] : scp[k]) * spec.length_mm / 100.0);
    }
    run.rows.push_back(std::move(row));
  }
  return run;
}

std::string RigRun::to_csv() const {
  std::ostringstream out;
  for (const auto& [k, v] : metadata) out << "# " << k << ": " << v << "\n";
  for (std::size_t c = 0; c < columns.size(); ++c) out << (c ? "," : "") << columns[c];
  out << "\n";
  for (const auto& row : rows) {
    for (std::size_t c = 0; c < row.size(); ++c)
      out << (c ? "," : "") << fmt::format("{:.10g}", row[c]);
    out << "\n";
  }
  return out.str();
}

}  // namespace scpkit
