// scpkit design DESIGN.toml: one actuator design, predicted before it is made.
#include <fmt/format.h>

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

  DesignFile file = load_design_file(path);
  const SweepContext& ctx = file.context;
  const DesignSpec& d = file.design;
  const std::optional<Measurement>& protocol = file.protocol;

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
