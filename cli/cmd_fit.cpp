// scpkit fit DATA.csv: identify a Preisach model (and, for paired thread/SCP data, the SCP gain).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "common.hpp"
#include "scpkit/identification/augmented_fit.hpp"
#include "scpkit/identification/gpi_fit.hpp"
#include "scpkit/identification/lonely_fit.hpp"
#include "scpkit/identification/polynomial_fit.hpp"
#include "scpkit/identification/preisach_fit.hpp"
#include "scpkit/io/model_file.hpp"
#include "scpkit/mechanics/ply_mapping.hpp"

namespace scpkit::cli {
namespace {

constexpr const char* kUsage = "scpkit fit DATA.csv [--model preisach] [-o MODEL.json] [options]";
constexpr const char* kAbout =
    "Identifies a Preisach hysteresis model from a measurement file (docs/data-format.md):\n"
    "input = the one varying column of load_g/load_mN/load_N, voltage_V, power_W, temp_C\n"
    "(several: a load changing from reading to reading, else voltage, power, temp; --input);\n"
    "response = strain, strain_pct, or disp_mm (strain when length_mm metadata is given).\n"
    "A paired file (thread_strain_pct and scp_strain_pct) fits the thread model and the\n"
    "SCP/thread gain. By default the number of levels L and the smoothness are chosen by\n"
    "cross-validation on held-out blocks (the `segment` column, else whole cycles).\n"
    "Writes the model as JSON and prints the identification errors (E_max, E_RMS in % of\n"
    "the response range; mean |e| and its sigma in the response's units).";
}  // namespace

int run_fit(const std::vector<std::string>& args) {
  po::options_description opt("options");
  opt.add_options()("help,h", "show this help")(
      "model", po::value<std::string>()->default_value("preisach"),
      "model: preisach, gpi, lonely (Preisach + lonely stroke), linear, poly2")(
      "operators", po::value<int>()->default_value(11), "GPI: number of play operators N + 1")(
      "max-radius", po::value<double>(),
      "GPI: largest play radius, in the input column's units (default: a quarter of the input "
      "range)")("output,o", po::value<std::string>(),
                "model file to write (default: DATA stem + .model.json)")(
      "input", po::value<std::string>()->default_value(""),
      "input quantity when several vary: load, voltage, power, temp")(
      "response", po::value<std::string>()->default_value(""),
      "response: strain, disp_mm, thread or scp (paired files default to thread)")(
      "levels,L", po::value<int>()->default_value(0), "Preisach levels L (0: cross-validate)")(
      "smoothness", po::value<double>()->default_value(-1.0),
      "smoothness weight lambda >= 0 (negative: cross-validate)")(
      "sign", po::value<std::string>()->default_value("auto"),
      "density sign: +1 (rising response), -1 (falling), auto")(
      "lo", po::value<double>(),
      "lowest threshold, in the input column's units (default: data min)")(
      "hi", po::value<double>(),
      "highest threshold, in the input column's units (default: data max)")(
      "folds", po::value<int>()->default_value(5),
      "cross-validation blocks without a segment column")(
      "grid-shifts", po::value<int>()->default_value(4),
      "average of S grids shifted by h/S (1 = one grid, the papers' recipe)")(
      "json", "print one JSON object instead of the report");
  add_threads_option(opt, "Preisach: threads over the shifted grids (same model for any count)");
  po::variables_map vm;
  if (!parse_command_line(args, kUsage, kAbout, opt, {"DATA"}, vm)) return kOk;

  const std::string model_kind = vm["model"].as<std::string>();
  if (model_kind != "preisach" && model_kind != "gpi" && model_kind != "linear" &&
      model_kind != "poly2" && model_kind != "lonely") {
    throw UsageError(
        fmt::format("unknown model '{}' (preisach, gpi, linear, poly2, lonely)", model_kind));
  }
  const std::string data_path = vm["DATA"].as<std::string>();
  const Measurement m = Measurement::read(data_path);
  // Voltage (power, temperature) tests at several constant loads: the augmented model.
  const MeasurementColumn* drive = augmented_drive(m, vm["input"].as<std::string>());
  const bool augmented = drive != nullptr;
  std::string note;
  const Signal in = augmented ? select_input(m, drive->name)
                              : choose_input(m, vm["input"].as<std::string>(), note);
  if (!note.empty()) std::cerr << "scpkit fit: note: " << note << "\n";
  const bool paired = m.find(Quantity::kThreadStrain) && m.find(Quantity::kScpStrain);
  std::string response_choice = vm["response"].as<std::string>();
  if (response_choice.empty() && paired) response_choice = "thread";
  const Signal out = select_response(m, response_choice);

  PreisachFitOptions fo;
  fo.levels = vm["levels"].as<int>();
  fo.smoothness = vm["smoothness"].as<double>();
  fo.folds = vm["folds"].as<int>();
  fo.grid_shifts = vm["grid-shifts"].as<int>();
  fo.threads = threads_from(vm);
  const std::string sign = vm["sign"].as<std::string>();
  if (sign == "auto") {
    fo.sign = 0;
  } else if (sign == "+1" || sign == "1") {
    fo.sign = 1;
  } else if (sign == "-1") {
    fo.sign = -1;
  } else {
    throw UsageError("--sign must be +1, -1 or auto");
  }
  const MeasurementColumn* in_col = column_named(m, in.column);
  const double in_factor = in_col ? in_col->to_canonical : 1.0;
  if (vm.count("lo")) fo.lo = vm["lo"].as<double>() * in_factor;
  if (vm.count("hi")) fo.hi = vm["hi"].as<double>() * in_factor;
  std::string why;
  if (!fo.IsValid(&why)) throw UsageError(why);

  std::vector<int> blocks;
  if (const MeasurementColumn* seg = m.find(Quantity::kSegment)) {
    for (double v : seg->values) blocks.push_back(static_cast<int>(v));
  }
  // Fit the chosen family; every branch yields the operator, its identification errors, a
  // report and the family's JSON details.
  std::optional<HysteresisOperator> op;
  ErrorMetrics train;
  double cv_rms = -1.0;
  std::string report;
  nlohmann::json details = nlohmann::json::object();
  std::optional<AugmentedModel> aug;
  try {
    if (augmented) {
      AugmentedFitOptions ao;
      ao.family = model_kind;
      ao.preisach = fo;
      ao.gpi.operators = vm["operators"].as<int>();
      ao.gpi.sign = fo.sign;
      ao.lonely.sign = fo.sign;
      if (fo.levels > 0) ao.lonely.levels = fo.levels;
      if (vm.count("max-radius")) ao.gpi.max_radius = vm["max-radius"].as<double>() * in_factor;
      const AugmentedFit af = fit_augmented(held_load_N(m), in.values, out.values, blocks, ao);
      aug = af.model;
      op.emplace(af.model.h);
      train = af.train;
      cv_rms = -1.0;
      std::string segs;
      for (const auto& sg : af.segments) {
        segs +=
            fmt::format("\n    load {:7.4g} N: offset {:+.4f}, range {:+.4f}", sg.load,
                        display_scale(out.name) * sg.offset, display_scale(out.name) * sg.range);
      }
      report = fmt::format(
          "augmented {} model over {} constant-load segments (y = f2(F) H[{}] + f1(F)):{}\n"
          "  f1(F) = {:.5g} {:+.5g} F {:+.5g} F^2,  f2(F) = {:.5g} {:+.5g} F {:+.5g} F^2  ({}, F "
          "in N)\n"
          "  H: {}\n  identification: E_max {:.3f} %, E_RMS {:.3f} % of the response range",
          model_kind, af.segments.size(), in.name, segs, af.model.f1.c0, af.model.f1.c1,
          af.model.f1.c2, af.model.f2.c0, af.model.f2.c1, af.model.f2.c2,
          out.name == "strain" ? "strain" : "mm", af.report, train.max_pct_range,
          train.rms_pct_range);
      details["segments"] = af.segments.size();
      details["f1"] = {af.model.f1.c0, af.model.f1.c1, af.model.f1.c2};
      details["f2"] = {af.model.f2.c0, af.model.f2.c1, af.model.f2.c2};
      details["load_range_N"] = {af.model.load_min, af.model.load_max};
    } else if (model_kind == "preisach") {
      const PreisachFit fit = fit_preisach(in.values, out.values, blocks, fo);
      op.emplace(fit.model, fit.input_min, fit.input_max);
      train = fit.summary.train;
      cv_rms = fit.summary.cv_rms_pct_range;
      report = fit.summary.BriefReport();
      details["levels"] = fit.summary.levels;
      details["smoothness"] = fit.summary.smoothness;
      details["grid_shifts"] = fit.summary.grid_shifts;
      details["sign"] = fit.summary.sign;
      details["unexcited_cells"] = fit.summary.unexcited_cells;
      details["unidentified_directions"] = fit.summary.unidentified_directions;
      details["converged"] = fit.summary.termination == PreisachFitSummary::Termination::kConverged;
      details["warnings"] = fit.summary.warnings;
      nlohmann::json cv = nlohmann::json::array();
      for (const auto& p : fit.summary.cross_validation) {
        cv.push_back({{"levels", p.levels},
                      {"smoothness", p.smoothness},
                      {"rms_pct_range", p.rms_pct_range}});
      }
      details["cross_validation"] = cv;
    } else if (model_kind == "lonely") {
      LonelyFitOptions lo;
      lo.sign = fo.sign;
      if (fo.levels > 0) lo.levels = fo.levels;
      lo.lo = fo.lo;
      lo.hi = fo.hi;
      const LonelyFit fit = fit_lonely(in.values, out.values, {}, lo);
      op.emplace(fit.model, fit.input_min, fit.input_max);
      train = fit.train;
      report = fit.report;
      details["levels"] = lo.levels;
      details["running_max_weights"] = fit.model.column_weights;
    } else if (model_kind == "gpi") {
      GpiFitOptions go;
      go.operators = vm["operators"].as<int>();
      go.sign = fo.sign;
      if (vm.count("max-radius")) go.max_radius = vm["max-radius"].as<double>() * in_factor;
      std::string why_gpi;
      if (!go.IsValid(&why_gpi)) throw UsageError(why_gpi);
      const GpiFit fit = fit_gpi(in.values, out.values, {}, go);
      op.emplace(fit.model);
      train = fit.summary.train;
      report = fit.summary.BriefReport();
      details["operators"] = go.operators;
      details["converged"] = fit.summary.converged;
      details["envelopes"] = {{"aR", fit.model.right.a},
                              {"bR", fit.model.right.b},
                              {"aL", fit.model.left.a},
                              {"bL", fit.model.left.b}};
    } else {
      const int degree = model_kind == "linear" ? 1 : 2;
      const PolynomialModel poly = fit_polynomial(in.values, out.values, degree);
      op.emplace(poly);
      const std::vector<double> y = op->simulate(in.values);
      train = error_metrics(out.values, y);
      report = fmt::format(
          "{} fit: coefficients {}\n  identification: E_max {:.3f} %, E_RMS {:.3f} % of the "
          "response range",
          model_kind, fmt::join(poly.coefficients, ", "), train.max_pct_range, train.rms_pct_range);
      details["coefficients"] = poly.coefficients;
    }
  } catch (const IdentificationError& e) {
    rethrow_at_column(m, out.column, std::string("cannot identify the model: ") + e.what());
  }

  ModelFile mf;
  mf.input = in.name;
  mf.response = out.name;
  mf.response_column = out.column;
  mf.op = *op;
  mf.augmented = aug;
  mf.specimen.specimen = m.meta("specimen").value_or("");
  mf.specimen.material = m.meta("material").value_or("");
  mf.specimen.plies = m.meta_positive_int("plies").value_or(0);
  mf.specimen.length_mm = m.meta_number("length_mm").value_or(0.0);
  mf.specimen.coil = coil_from_metadata(m);
  const double scale = display_scale(out.name);
  mf.fit_metrics = train.scaled(scale);
  mf.cv_rms_pct_range = cv_rms;
  mf.data_file = std::filesystem::path(data_path).filename().string();  // portable: no folders
  if (paired) {
    try {
      mf.scp_gain = fit_scp_gain(m.find(Quantity::kThreadStrain)->values,
                                 m.find(Quantity::kScpStrain)->values);
    } catch (const IdentificationError& e) {
      rethrow_at_column(m, m.find(Quantity::kScpStrain)->name, e.what());
    }
  }
  const std::string model_path =
      vm.count("output") ? vm["output"].as<std::string>()
                         : std::filesystem::path(data_path).stem().string() + ".model.json";
  save_model(model_path, mf);

  const std::string unit = display_unit(out.name);
  if (vm.count("json")) {
    nlohmann::json j = metrics_json(mf.fit_metrics);
    j["model_file"] = model_path;
    j["model"] = augmented ? "augmented" : model_kind;
    j["operator"] = model_kind;
    j["input"] = in.name;
    j["response"] = out.name;
    j["response_unit"] = unit;
    j["cv_rms_pct_range"] = cv_rms;
    j.update(details);
    if (mf.scp_gain) {
      j["scp_gain"] = {{"gain", mf.scp_gain->gain},
                       {"offset_pct", 100.0 * mf.scp_gain->offset},
                       {"r2", mf.scp_gain->r2}};
    }
    print_json(j);
  } else {
    std::cout << fmt::format("{}: {} rows, input {} ({}), response {} ({})\n", data_path, m.rows(),
                             in.column, display_unit(in.name), out.column, unit);
    std::cout << report << "\n";
    std::cout << fmt::format("  errors: {}\n", mf.fit_metrics.brief(unit));
    if (mf.scp_gain) {
      std::cout << fmt::format(
          "  SCP gain: scp = {:.4f} * thread {:+.4f} strain-%  (R^2 {:.5f}, {} pairs)\n",
          mf.scp_gain->gain, 100.0 * mf.scp_gain->offset, mf.scp_gain->r2, mf.scp_gain->samples);
    }
    std::cout << "model written to " << model_path << "\n";
  }
  return kOk;
}

}  // namespace scpkit::cli
