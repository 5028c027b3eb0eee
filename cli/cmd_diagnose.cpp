// scpkit diagnose DATA.csv: what the model gets wrong, the named cause, the extension's gain.
#include <fmt/format.h>

#include <iostream>

#include "commands.hpp"
#include "common.hpp"
#include "scpkit/diagnosis/diagnose.hpp"

namespace scpkit::cli {
namespace {

constexpr const char* kUsage = "scpkit diagnose DATA.csv [--json] [--seed N]";
constexpr const char* kAbout =
    "Fits the baseline (a Preisach model) with held-out validation over whole cycles or the\n"
    "segment column, estimates the noise floor from the data, tests one signature per named\n"
    "effect against a block-permutation null, fits the extension each effect implies and\n"
    "measures its gain on held-out data, and names the cause: the best-supported effect,\n"
    "`none` (residuals at the noise floor) or `unexplained` (structured, but no named effect).\n"
    "Load tests: Preisach baseline held out by cycles. Tests at several constant loads\n"
    "(voltage, power or temperature input with a varying load column): augmented Preisach\n"
    "baseline held out by load segment. Method and measured accuracy: docs/diagnose.md.\n"
    "--json prints the SPEC's object.";

}  // namespace

int run_diagnose(const std::vector<std::string>& args) {
  po::options_description opt("options");
  opt.add_options()("help,h", "show this help")(
      "input", po::value<std::string>()->default_value(""), "input when several vary")(
      "seed", po::value<long long>()->default_value(1), "seed of the permutation tests")(
      "json", "print one JSON object");
  po::variables_map vm;
  if (!parse_command_line(args, kUsage, kAbout, opt, {"DATA"}, vm)) return kOk;
  const Measurement m = Measurement::read(vm["DATA"].as<std::string>());
  const MeasurementColumn* drive = augmented_drive(m, vm["input"].as<std::string>());
  const Signal in =
      drive ? select_input(m, drive->name) : select_input(m, vm["input"].as<std::string>());
  const Signal out = select_response(m);
  DiagnoseData data;
  data.input = in.values;
  data.output = out.values;
  if (const MeasurementColumn* t = m.find(Quantity::kTime)) data.time_s = t->values;
  if (const MeasurementColumn* seg = m.find(Quantity::kSegment)) {
    for (double v : seg->values) data.segments.push_back(static_cast<int>(v));
  }
  if (drive) data.load_N = m.find(Quantity::kLoad)->values;
  DiagnoseOptions o;
  o.seed = static_cast<std::uint64_t>(std::max(0LL, vm["seed"].as<long long>()));
  const Diagnosis d = [&] {
    try {
      return diagnose(data, o);
    } catch (const IdentificationError& e) {
      rethrow_at_column(m, out.column, std::string("cannot diagnose: ") + e.what());
    }
  }();
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
    print_json({{"input", in.column},
                {"baseline",
                 {{"model", d.baseline_model},
                  {"heldout_by", d.heldout_by},
                  {"heldout_rows", d.heldout_rows},
                  {"rms_pct_range", d.rms_pct_range},
                  {"max_pct_range", d.max_pct_range}}},
                {"noise_floor_pct_range", d.noise_floor_pct_range},
                {"findings", findings},
                {"cause", d.cause}});
    return kOk;
  }
  std::cout << fmt::format("{}: {} rows, input {}, response {}\n", m.source(), m.rows(), in.column,
                           out.column);
  std::cout << fmt::format(
      "  baseline {}, held out by {} ({} readings scored): E_RMS {:.3f} %, E_max {:.3f} % of "
      "range; noise floor {:.3f} %\n",
      d.baseline_model, d.heldout_by, d.heldout_rows, d.rms_pct_range, d.max_pct_range,
      d.noise_floor_pct_range);
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
  std::cout << "  cause: " << d.cause << "\n";
  return kOk;
}

}  // namespace scpkit::cli
