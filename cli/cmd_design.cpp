// scpkit design DESIGN.toml: one actuator design, predicted before it is made.
#include <fmt/format.h>
#include <toml++/toml.h>

#include <iostream>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "scpkit/design/sweep.hpp"
#include "scpkit/io/atomic_file.hpp"

namespace scpkit::cli {
namespace {

constexpr const char* kUsage = "scpkit design DESIGN.toml [-o CURVE.csv] [--json]";
constexpr const char* kAbout =
    "Predicts one SCP actuator from a characterised thread (docs/design.md): stiffness, the\n"
    "SCP gain, the load-strain loop between the working loads, stroke (mm and %) with the band\n"
    "the coil tolerances imply, hysteresis (largest branch gap, % of stroke), feasibility\n"
    "(spring index >= 1, pitch >= d, loads inside the identified range after per-ply scaling)\n"
    "and, with a voltage model, the thermal stroke and the voltage for a target stroke.\n"
    "With protocol_file (a measurement with a load column), the loop follows that protocol and\n"
    "is compared with the file's SCP strain when it has one.";

constexpr double kGram = 9.80665e-3;

}  // namespace

int run_design(const std::vector<std::string>& args) {
  po::options_description opt("options");
  opt.add_options()("help,h", "show this help")("output,o", po::value<std::string>(),
                                                "CSV of the predicted loop")(
      "json", "print one JSON object instead of the report");
  po::variables_map vm;
  if (!parse_command_line(args, kUsage, kAbout, opt, {"DESIGN"}, vm)) return kOk;
  const std::filesystem::path path = vm["DESIGN"].as<std::string>();

  // The design file: the sweep's vocabulary with one value each, loads in grams for this actuator.
  toml::table root;
  try {
    root = toml::parse_file(path.string());
  } catch (const toml::parse_error& e) {
    throw InputError(path.string(), static_cast<int>(e.source().begin.line),
                     static_cast<int>(e.source().begin.column), std::string(e.description()));
  }
  auto located = [&](const toml::node* n, const std::string& msg) -> InputError {
    return n ? InputError(path.string(), static_cast<int>(n->source().begin.line),
                          static_cast<int>(n->source().begin.column), msg)
             : InputError(path.string(), 0, 0, msg);
  };
  for (const auto& [k, v] : root) {
    const std::string key(k.str());
    if (key != "thread_model" && key != "voltage_model" && key != "material" && key != "plies" &&
        key != "coil" && key != "loads" && key != "protocol_file") {
      throw located(&v, "unknown key '" + key + "'");
    }
  }
  auto number = [&](const toml::table& t, const char* key, double fallback, bool required) {
    const toml::node* n = t.get(key);
    if (!n) {
      if (required) throw located(&t, fmt::format("missing key '{}'", key));
      return fallback;
    }
    const auto v = n->value<double>();
    if (!v || !(*v >= 0.0)) throw located(n, fmt::format("'{}' must be a number >= 0", key));
    return *v;
  };
  SweepSpec spec;
  const auto model = root["thread_model"].value<std::string>();
  if (!model) throw located(&root, "missing key 'thread_model'");
  spec.thread_model = path.parent_path() / *model;
  if (const auto v = root["voltage_model"].value<std::string>())
    spec.voltage_model = path.parent_path() / *v;
  spec.material = root["material"].value_or(std::string());
  const SweepContext ctx = prepare_sweep(spec);

  DesignSpec d;
  d.plies = static_cast<int>(number(root, "plies", 0, true));
  const toml::table* coil = root["coil"].as_table();
  if (!coil) throw located(&root, "missing table [coil]");
  const double dmm = number(*coil, "d_mm", 0.0, false);
  d.coil.wire_d_m =
      dmm > 0.0 ? dmm * 1e-3 : wire_diameter_for(ctx.material, ctx.characterisation, d.plies);
  if (coil->get("D_mm")) {
    d.coil.mean_D_m = number(*coil, "D_mm", 0.0, true) * 1e-3;
  } else {
    d.coil.mean_D_m = number(*coil, "spring_index", 0.0, true) * d.coil.wire_d_m;
  }
  d.coil.coils = number(*coil, "n", 0.0, true);
  d.coil.legs = static_cast<int>(number(*coil, "legs", 2, false));
  d.coil.length_m = number(*coil, "length_mm", 0.0, true) * 1e-3;
  if (const toml::table* loads = root["loads"].as_table()) {
    d.load_min_N = number(*loads, "min_g", 0.0, true) * kGram;
    d.load_max_N = number(*loads, "max_g", 0.0, true) * kGram;
    d.protocol_steps = static_cast<int>(number(*loads, "protocol_steps", 100, false));
    d.working_load_N = number(*loads, "working_g", 0.0, false) * kGram;
    d.target_stroke_mm = number(*loads, "target_stroke_mm", 0.0, false);
  }
  std::optional<Measurement> protocol;
  if (const auto pf = root["protocol_file"].value<std::string>()) {
    protocol = Measurement::read(path.parent_path() / *pf);
    d.protocol_N = select_input(*protocol, "load").values;
  } else if (!(d.load_max_N > 0.0)) {
    throw located(&root, "give [loads] min_g and max_g, or a protocol_file");
  }

  DesignWorkspace ws;
  const DesignResult r = evaluate_design(ctx.characterisation, ctx.material, d, ws, true);
  std::optional<ErrorMetrics> err;
  if (protocol) {
    if (const MeasurementColumn* scp = protocol->find(Quantity::kScpStrain)) {
      std::vector<double> meas;
      for (double v : scp->values) meas.push_back(100.0 * v);
      err = error_metrics(meas, r.strain_pct);
    }
  }
  if (vm.count("output")) {
    std::ostringstream csv;
    csv << "load_g,predicted_scp_strain_pct\n";
    for (std::size_t k = 0; k < r.strain_pct.size(); ++k) {
      csv << csv_number(ws.loads[k] / kGram) << "," << csv_number(r.strain_pct[k]) << "\n";
    }
    write_file_atomically(vm["output"].as<std::string>(), csv.str());
  }
  if (vm.count("json")) {
    nlohmann::json j = {
        {"feasible", r.feasible},
        {"reason", r.reason},
        {"plies", d.plies},
        {"d_mm", d.coil.wire_d_m * 1e3},
        {"D_mm", d.coil.mean_D_m * 1e3},
        {"n", d.coil.coils},
        {"legs", d.coil.legs},
        {"length_mm", d.coil.length_m * 1e3},
        {"spring_index", r.spring_index},
        {"pitch_mm", r.pitch_mm},
        {"stiffness_N_per_m",
         {{"value", r.stiffness_N_per_m.value}, {"sigma", r.stiffness_N_per_m.sigma}}},
        {"gain", {{"value", r.gain.value}, {"sigma", r.gain.sigma}}},
        {"stroke_mm", {{"value", r.stroke_mm}, {"sigma", r.stroke_sigma_mm}}},
        {"stroke_pct", r.stroke_pct},
        {"hysteresis_pct", r.hysteresis_pct},
        {"thermal_stroke_mm", r.thermal_stroke_mm},
        {"voltage_for_target_V", r.voltage_for_target_V},
        {"voltage_extrapolated", r.voltage_extrapolated}};
    if (err) j["against_protocol_file"] = metrics_json(*err);
    print_json(j);
    return kOk;
  }
  std::cout << fmt::format(
      "design: {} plies, d {:.3g} mm, D {:.3g} mm (mean, C = {:.2f}), n {:g}, {} legs, {:.4g} mm\n",
      d.plies, d.coil.wire_d_m * 1e3, d.coil.mean_D_m * 1e3, r.spring_index, d.coil.coils,
      d.coil.legs, d.coil.length_m * 1e3);
  std::cout << (r.feasible ? "  feasible\n" : "  INFEASIBLE: " + r.reason + "\n");
  std::cout << fmt::format(
      "  stiffness {:.4g} +- {:.2g} N/m;  SCP gain {:.4g} +- {:.2g} (from the {}-ply "
      "characterisation)\n",
      r.stiffness_N_per_m.value, r.stiffness_N_per_m.sigma, r.gain.value, r.gain.sigma,
      ctx.characterisation.plies);
  std::cout << fmt::format(
      "  stroke {:.3f} +- {:.3f} mm ({:.2f} % strain) {}\n", r.stroke_mm, r.stroke_sigma_mm,
      r.stroke_pct,
      r.hysteresis_pct >= 0.0
          ? fmt::format("between the working loads; hysteresis {:.1f} % of stroke",
                        r.hysteresis_pct)
          : std::string("over the protocol"));
  if (r.thermal_stroke_mm >= 0.0) {
    std::cout << fmt::format(
        "  thermal stroke at {:.4g} g: {:.3f} mm{}\n", d.working_load_N / kGram,
        r.thermal_stroke_mm,
        r.voltage_extrapolated ? " (EXTRAPOLATED: load outside the voltage model's range)" : "");
    if (d.target_stroke_mm > 0.0) {
      std::cout << (r.voltage_for_target_V >= 0.0
                        ? fmt::format("  voltage for {:.3g} mm: {:.3f} V\n", d.target_stroke_mm,
                                      r.voltage_for_target_V)
                        : fmt::format("  {:.3g} mm is beyond the thermal stroke: unreachable\n",
                                      d.target_stroke_mm));
    }
  }
  if (err)
    std::cout << "  against the protocol file's SCP strain: " << err->brief("strain-%") << "\n";
  if (vm.count("output"))
    std::cout << "  loop written to " << vm["output"].as<std::string>() << "\n";
  return kOk;
}

}  // namespace scpkit::cli
