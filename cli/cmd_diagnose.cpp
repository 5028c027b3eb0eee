// scpkit diagnose DATA.csv: what the model gets wrong, the named cause, the extension's gain.
#include <fmt/format.h>

#include <cmath>
#include <iostream>

#include "commands.hpp"
#include "common.hpp"
#include "scpkit/diagnosis/diagnose.hpp"
#include "scpkit/diagnosis/ply_mapping_diagnosis.hpp"
#include "scpkit/diagnosis/specimen_change.hpp"
#include "scpkit/io/atomic_file.hpp"
#include "scpkit/mechanics/material.hpp"

namespace scpkit::cli {
namespace {

constexpr const char* kUsage =
    "scpkit diagnose DATA.csv [--json] [--residuals OUT.csv] [--seed N] [--threads N] "
    "[--coil-d MM --coil-D MM --coil-n N --legs K] [--reference REFERENCE.csv]";
constexpr const char* kAbout =
    "Fits the baseline (a Preisach model) with held-out validation over whole cycles or the\n"
    "segment column, estimates the noise floor from the data, tests one signature per named\n"
    "effect against a block-permutation null, fits the extension each effect implies and\n"
    "measures its gain on held-out data, and names the cause: the best-supported effect,\n"
    "`none` (residuals at the noise floor) or `unexplained` (structured, but no named effect).\n"
    "Load tests: Preisach baseline held out by cycles. Tests at several constant loads\n"
    "(voltage, power or temperature input, the load held over runs of readings): augmented\n"
    "Preisach baseline held out by load segment. Method and accuracy: docs/diagnose.md.\n"
    "A paired file (thread_strain_pct and scp_strain_pct under one load sequence) gets the\n"
    "ply-mapping diagnosis instead: the SCP gain predicted from the material card and the coil\n"
    "(metadata coil_d_mm, coil_D_mm, coil_n, legs, or the flags) against the measured one, and\n"
    "the causes spring_index, legs, active_coils, input_scale scored on held-out cycles.\n"
    "With --reference, what changed between two tests of one kind (e.g. a fibre dry and after\n"
    "moisture): the reference's Preisach model predicts DATA.csv, and the changes offset,\n"
    "range, input_shift (nested) and shape (DATA.csv's own model) are scored on contiguous\n"
    "held-out blocks of DATA.csv; the named change is the last one that gains >= 5 % at\n"
    "sign-flip p < 0.05 (docs/diagnose.md, \"What changed between two tests\").\n"
    "--json prints the SPEC's object. --residuals writes, beside the file's own columns, where\n"
    "the model fails: each reading's held-out fold, the baseline's held-out prediction and\n"
    "residual, and the named cause's extended model (in the response column's units; blank\n"
    "where a reading was not scored), and the readings the spike screen flagged (outlier 1).\n"
    "--threads only changes the time the diagnosis takes.";

// The ply-mapping diagnosis of a paired thread/SCP test.
int run_ply_mapping(const Measurement& m, const po::variables_map& vm) {
  std::optional<CoilGeometry> coil = coil_from_metadata(m);
  const int given = static_cast<int>(vm.count("coil-d") + vm.count("coil-D") + vm.count("coil-n"));
  if (given > 0 && given < 3) throw UsageError("give all of --coil-d, --coil-D and --coil-n");
  if (given == 3) {
    CoilGeometry c;
    c.wire_d_m = vm["coil-d"].as<double>() * 1e-3;
    c.mean_D_m = vm["coil-D"].as<double>() * 1e-3;
    c.coils = vm["coil-n"].as<double>();
    c.legs = coil ? coil->legs : 1;
    coil = c;
  }
  if (!coil) {
    throw InputError(m.source(), 0, 0,
                     "the ply-mapping diagnosis needs the SCP's coil: metadata coil_d_mm, "
                     "coil_D_mm, coil_n (and legs), or --coil-d, --coil-D, --coil-n");
  }
  if (vm.count("legs")) coil->legs = vm["legs"].as<int>();
  try {
    coil->validate();
  } catch (const InvalidArgument& e) {
    throw UsageError(std::string("coil: ") + e.what());
  }
  const std::string material_id =
      vm.count("material") ? vm["material"].as<std::string>() : m.meta("material").value_or("");
  if (material_id.empty())
    throw InputError(m.source(), 0, 0, "needs the material (metadata `material` or --material)");
  const Material material = find_material(material_id);
  const auto plies = m.meta_positive_int("plies");
  const auto length = m.meta_number("length_mm");
  if (!plies || !length)
    throw InputError(m.source(), 0, 0, "needs `plies` and `length_mm` metadata");
  PlyMappingData data;
  std::string note;
  const Signal load = choose_input(m, vm["input"].as<std::string>(), note);
  if (!note.empty()) std::cerr << "scpkit diagnose: note: " << note << "\n";
  data.load_N = load.values;
  data.thread_strain = m.find(Quantity::kThreadStrain)->values;
  data.scp_strain = m.find(Quantity::kScpStrain)->values;
  data.plies = *plies;
  data.length_m = *length * 1e-3;
  data.coil = *coil;
  const PlyMappingDiagnosis d = [&] {
    try {
      return diagnose_ply_mapping(data, material);
    } catch (const IdentificationError& e) {
      rethrow_at_column(m, m.find(Quantity::kScpStrain)->name,
                        std::string("cannot diagnose: ") + e.what());
    }
  }();
  const MappingCandidate& physics = d.candidates.front();
  if (vm.count("json")) {
    nlohmann::json findings = nlohmann::json::array();
    for (std::size_t i = 1; i < d.candidates.size(); ++i) {
      const MappingCandidate& c = d.candidates[i];
      findings.push_back({{"effect", c.cause},
                          {"tested", true},
                          {"detected", c.supported},
                          {"score", c.gain},
                          {"evidence", c.evidence},
                          {"extended_model", c.model},
                          {"heldout_rms_before", physics.heldout_rms_pct},
                          {"heldout_rms_after", c.heldout_rms_pct},
                          {"gain_pct", c.gain_pct}});
    }
    print_json({{"input", load.column},
                {"mode", "ply_mapping"},
                {"baseline",
                 {{"model", physics.model},
                  {"heldout_by", "cycles"},
                  {"rms_pct_range", physics.heldout_rms_pct},
                  {"max_pct_range", physics.heldout_max_pct},
                  {"predicted_gain", d.predicted_gain.value},
                  {"predicted_gain_sigma", d.predicted_gain.sigma},
                  {"measured_gain", d.measured_gain},
                  {"measured_r2", d.measured_r2},
                  {"miss_pct", d.miss_pct}}},
                {"findings", findings},
                {"cause", d.cause}});
    return kOk;
  }
  std::cout << fmt::format(
      "{}: ply mapping, {}-ply thread -> SCP (d {:g} mm, D {:g} mm, n {:g}, {} leg(s)), "
      "{} folds of whole cycles\n",
      m.source(), data.plies, data.coil.wire_d_m * 1e3, data.coil.mean_D_m * 1e3, data.coil.coils,
      data.coil.legs, d.folds);
  std::cout << fmt::format(
      "  SCP gain: predicted {:.4g} +- {:.2g} (material card and coil), measured {:.4g} (R^2 "
      "{:.5f}): {:+.1f} %\n",
      d.predicted_gain.value, d.predicted_gain.sigma, d.measured_gain, d.measured_r2, d.miss_pct);
  for (const MappingCandidate& c : d.candidates) {
    std::cout << fmt::format(
        "  {:<13} g {:8.4g}  held-out E_RMS {:7.3f} % of range  gain {:+6.1f} %{}  {}\n", c.cause,
        c.gain, c.heldout_rms_pct, c.gain_pct, c.supported ? "  SUPPORTED" : "", c.evidence);
  }
  std::cout << "  cause: " << d.cause << "\n";
  return kOk;
}

// What changed between a reference test and DATA.csv (the same input and response quantity).
int run_specimen_change(const Measurement& m, const po::variables_map& vm) {
  const Measurement r = Measurement::read(vm["reference"].as<std::string>());
  for (const Measurement* x : {&m, &r}) {
    if (augmented_drive(*x, vm["input"].as<std::string>()))
      throw InputError(x->source(), 0, 0,
                       "a comparison of tests at several constant loads is not built: compare "
                       "load tests, or tests at one load");
  }
  std::string note;
  const Signal in = choose_input(m, vm["input"].as<std::string>(), note);
  if (!note.empty()) std::cerr << "scpkit diagnose: note: " << note << "\n";
  const Signal ref_in = choose_input(r, in.name, note);
  const Signal out = select_response(m);
  const Signal ref_out = select_response(r);
  if (ref_out.name != out.name)
    throw InputError(r.source(), 0, 0,
                     fmt::format("the reference's response is {} ({}), the data's {} ({}): "
                                 "compare tests of one kind (give length_mm to both for strain)",
                                 ref_out.name, ref_out.column, out.name, out.column));
  SpecimenChangeOptions o;
  o.seed = static_cast<std::uint64_t>(std::max(0LL, vm["seed"].as<long long>()));
  const SpecimenChange d = [&] {
    try {
      return diagnose_specimen_change(ref_in.values, ref_out.values, in.values, out.values, o);
    } catch (const IdentificationError& e) {
      const std::string what = e.what();
      const bool reference = what.rfind("the reference: ", 0) == 0;
      rethrow_at_column(reference ? r : m, reference ? ref_out.column : out.column,
                        "cannot compare: " + what);
    }
  }();
  const double f = display_scale(out.name);
  const std::string unit = display_unit(out.name), in_unit = display_unit(in.name);
  if (vm.count("json")) {
    nlohmann::json findings = nlohmann::json::array();
    for (std::size_t i = 1; i < d.candidates.size(); ++i) {
      const SpecimenChangeCandidate& c = d.candidates[i];
      findings.push_back({{"effect", c.change},
                          {"detected", c.accepted},
                          {"score", c.gain_pct},
                          {"p_value", c.p_value},
                          {"evidence", c.evidence},
                          {"extended_model", c.model},
                          {"heldout_rms_before", c.heldout_rms_before_pct},
                          {"heldout_rms_after", c.heldout_rms_pct},
                          {"gain_pct", c.gain_pct},
                          {"g", c.g},
                          {"c", c.c * f},
                          {"d", c.d}});
    }
    const SpecimenChangeCandidate& base = d.candidates.front();
    print_json({{"input", in.column},
                {"mode", "specimen_change"},
                {"reference", r.source()},
                {"baseline",
                 {{"model", d.reference_model},
                  {"heldout_by", "contiguous blocks"},
                  {"heldout_folds", d.blocks},
                  {"reference_rms_pct_range", d.reference_rms_pct},
                  {"rms_pct_range", base.heldout_rms_pct},
                  {"max_pct_range", base.heldout_max_pct}}},
                {"noise_floor_pct_range", d.noise_floor_pct},
                {"findings", findings},
                {"cause", d.change}});
    return kOk;
  }
  std::cout << fmt::format(
      "{} against the reference {}: input {}, response {} ({} held-out blocks of {} rows)\n",
      m.source(), r.source(), in.column, out.column, d.blocks, m.rows());
  std::cout << fmt::format(
      "  reference model: {} (in-sample E_RMS {:.3f} % of its range); noise floor of {} {:.3f} % "
      "of its range\n",
      d.reference_model, d.reference_rms_pct, m.source(), d.noise_floor_pct);
  for (const SpecimenChangeCandidate& c : d.candidates) {
    std::string fitted;  // the parameters a chain step fitted, in display units
    if (c.change == "offset") fitted = fmt::format(" (c = {:.4g} {})", c.c * f, unit);
    if (c.change == "range")
      fitted = fmt::format(" (g = {:.4g}, c = {:.4g} {})", c.g, c.c * f, unit);
    if (c.change == "input_shift")
      fitted = fmt::format(" (d = {:.4g} {}, g = {:.4g}, c = {:.4g} {})", c.d, in_unit, c.g,
                           c.c * f, unit);
    std::cout << fmt::format("  {:<12} held-out E_RMS {:7.3f} %, E_max {:7.3f} % of range{}: {}\n",
                             c.change, c.heldout_rms_pct, c.heldout_max_pct, fitted, c.evidence);
  }
  std::cout << "  change: " << d.change << "\n";
  return kOk;
}

// The file's own columns and, per reading, where the model fails: the fold that held it out,
// whether its training identified its memory, the baseline's held-out prediction and residual,
// the named cause's extended model and its residual (in the response column's units; blank
// where the reading was not scored), and whether the spike screen flagged it.
std::string residuals_csv(const Measurement& m, const Signal& out, const Diagnosis& d) {
  const MeasurementColumn* col = column_named(m, out.column);
  const double length_mm = m.meta_number("length_mm").value_or(1.0);
  auto units = [&](double canonical) {
    return col ? to_column_units(canonical, *col, length_mm, out.name) : canonical;
  };
  const Finding* cause = nullptr;
  const std::vector<char>* spikes = nullptr;
  for (const Finding& f : d.findings) {
    if (f.effect == d.cause && !f.heldout_prediction.empty()) cause = &f;
    if (f.effect == "outliers" && !f.flagged.empty()) spikes = &f.flagged;
  }
  std::vector<AppendedColumn> cols = {{"heldout_fold", {}},
                                      {"identified", {}},
                                      {"baseline_" + out.column, {}},
                                      {"residual_" + out.column, {}}};
  if (cause) {
    cols.push_back({cause->effect + "_" + out.column, {}});
    cols.push_back({cause->effect + "_residual_" + out.column, {}});
  }
  cols.push_back({"outlier", {}});
  for (std::size_t r = 0; r < m.rows(); ++r) {
    const double base = d.baseline_prediction[r];
    const bool scored = std::isfinite(base);
    std::size_t k = 0;  // the next column, in the order above; prediction cells blank unscored
    auto put = [&](std::string cell, bool blank) {
      cols[k++].cells.push_back(blank ? std::string() : std::move(cell));
    };
    put(std::to_string(d.heldout_fold[r] + 1), !scored);
    put(d.identified[r] ? "1" : "0", !scored);
    put(csv_number(units(base)), !scored);
    put(csv_number(units(out.values[r] - base)), !scored);
    if (cause) {
      const double ext = cause->heldout_prediction[r];
      put(csv_number(units(ext)), !scored);
      put(csv_number(units(out.values[r] - ext)), !scored);
    }
    put(spikes && (*spikes)[r] ? "1" : "0", false);
  }
  return csv_with_appended(m, cols);
}

}  // namespace

int run_diagnose(const std::vector<std::string>& args) {
  po::options_description opt("options");
  opt.add_options()("help,h", "show this help")(
      "input", po::value<std::string>()->default_value(""), "input when several vary")(
      "seed", po::value<long long>()->default_value(1), "seed of the permutation tests")(
      "json", "print one JSON object")("residuals", po::value<std::string>(),
                                       "CSV to write: per reading, the held-out "
                                       "prediction and residual")(
      "coil-d", po::value<double>(), "ply mapping: SCP wire diameter d, mm")(
      "coil-D", po::value<double>(), "ply mapping: SCP MEAN coil diameter D, mm")(
      "coil-n", po::value<double>(), "ply mapping: SCP coils n (whole actuator)")(
      "legs", po::value<int>(), "ply mapping: SCP legs (1, or 2 double-backed)")(
      "material", po::value<std::string>(), "ply mapping: material card id")(
      "reference", po::value<std::string>(),
      "a test of the same kind to compare with: what changed from it to DATA");
  add_threads_option(opt, "worker threads (the same diagnosis for any count)");
  po::variables_map vm;
  if (!parse_command_line(args, kUsage, kAbout, opt, {"DATA"}, vm)) return kOk;
  const Measurement m = Measurement::read(vm["DATA"].as<std::string>());
  if (m.find(Quantity::kThreadStrain) && m.find(Quantity::kScpStrain)) {
    if (vm.count("residuals"))
      throw UsageError("--residuals is for a test's diagnosis, not a paired thread/SCP file's");
    return run_ply_mapping(m, vm);
  }
  if (vm.count("reference")) {
    if (vm.count("residuals"))
      throw UsageError("--residuals is for a test's diagnosis, not a comparison of two tests");
    return run_specimen_change(m, vm);
  }
  const MeasurementColumn* drive = augmented_drive(m, vm["input"].as<std::string>());
  std::string note;
  const Signal in =
      drive ? select_input(m, drive->name) : choose_input(m, vm["input"].as<std::string>(), note);
  if (!note.empty()) std::cerr << "scpkit diagnose: note: " << note << "\n";
  const Signal out = select_response(m);
  DiagnoseData data;
  data.input = in.values;
  data.input_is_load = in.name.rfind("load", 0) == 0;
  data.output = out.values;
  if (const MeasurementColumn* t = m.find(Quantity::kTime)) data.time_s = t->values;
  if (const MeasurementColumn* t = m.find(Quantity::kDwell)) data.dwell_s = t->values;
  if (const MeasurementColumn* seg = m.find(Quantity::kSegment)) {
    for (double v : seg->values) data.segments.push_back(static_cast<int>(v));
  }
  if (drive) data.load_N = held_load_N(m);
  DiagnoseOptions o;
  o.seed = static_cast<std::uint64_t>(std::max(0LL, vm["seed"].as<long long>()));
  o.baseline.threads = threads_from(vm);
  const Diagnosis d = [&] {
    try {
      return diagnose(data, o);
    } catch (const IdentificationError& e) {
      rethrow_at_column(m, out.column, std::string("cannot diagnose: ") + e.what());
    }
  }();
  if (vm.count("residuals"))
    write_file_atomically(vm["residuals"].as<std::string>(), residuals_csv(m, out, d));
  if (vm.count("json")) {
    nlohmann::json findings = nlohmann::json::array();
    for (const Finding& f : d.findings) {
      findings.push_back({{"effect", f.effect},
                          {"tested", f.tested},
                          {"detected", f.detected},
                          {"score", f.score},
                          {"p_value", f.p_value},
                          {"evidence", f.evidence},
                          {"extended_model", f.extended_model},
                          {"heldout_rms_before", f.heldout_rms_before},
                          {"heldout_rms_after", f.heldout_rms_after},
                          {"gain_pct", f.gain_pct}});
    }
    nlohmann::json limits = nlohmann::json::array();
    for (const ProtocolLimit& l : d.protocol_limits)
      limits.push_back({{"effect", l.effect}, {"note", l.note}});
    print_json({{"input", in.column},
                {"baseline",
                 {{"model", d.baseline_model},
                  {"heldout_by", d.heldout_by},
                  {"heldout_folds", d.heldout_folds},
                  {"heldout_rows", d.heldout_rows},
                  {"rms_pct_range", d.rms_pct_range},
                  {"max_pct_range", d.max_pct_range},
                  {"sustained_rms_pct_range", d.sustained_rms_pct_range},
                  {"identified_rows", d.identified_rows},
                  {"identified_sustained_rms_pct_range", d.identified_sustained_rms_pct_range}}},
                {"noise_floor_pct_range", d.noise_floor_pct_range},
                {"noise_correlation", d.noise_correlation},
                {"findings", findings},
                {"cause", d.cause},
                {"cause_note", d.cause_note},
                {"protocol_limits", limits}});
    return kOk;
  }
  std::cout << fmt::format("{}: {} rows, input {}, response {}\n", m.source(), m.rows(), in.column,
                           out.column);
  std::cout << fmt::format(
      "  baseline {}, held out by {} in {} folds ({} readings scored): E_RMS {:.3f} %, E_max "
      "{:.3f} % of range (E_RMS without the largest 5 %: {:.3f} %); noise floor {:.3f} % (lag-one "
      "correlation {:.2f})\n",
      d.baseline_model, d.heldout_by, d.heldout_folds, d.heldout_rows, d.rms_pct_range,
      d.max_pct_range, d.sustained_rms_pct_range, d.noise_floor_pct_range, d.noise_correlation);
  for (const Finding& f : d.findings) {
    if (!f.tested) {
      std::cout << fmt::format("  {:<24} not tested: {}\n", f.effect, f.evidence);
      continue;
    }
    std::cout << fmt::format("  {:<24} {:<12} gain {:+6.1f} %  {}\n", f.effect,
                             f.detected ? "DETECTED" : "not detected", f.gain_pct, f.evidence);
  }
  for (const Finding& f : d.findings) {
    if (f.effect != d.cause) continue;
    std::cout << fmt::format(
        "  extended model: {} (held-out E_RMS {:.3f} -> {:.3f} %, gain {:.1f} %)\n",
        f.extended_model, f.heldout_rms_before, f.heldout_rms_after, f.gain_pct);
  }
  for (const ProtocolLimit& l : d.protocol_limits)
    std::cout << fmt::format("  protocol hides {}: {}\n", l.effect, l.note);
  std::cout << "  cause: " << d.cause << (d.cause_note.empty() ? "" : " (" + d.cause_note + ")")
            << "\n";
  if (vm.count("residuals"))
    std::cout << "  held-out predictions and residuals per reading written to "
              << vm["residuals"].as<std::string>() << "\n";
  return kOk;
}

}  // namespace scpkit::cli
