// scpkit invert MODEL TARGET.csv: the input sequence that tracks a target response.
#include <fmt/format.h>

#include <cmath>
#include <iostream>
#include <sstream>

#include "commands.hpp"
#include "common.hpp"
#include "scpkit/io/atomic_file.hpp"
#include "scpkit/io/model_file.hpp"

namespace scpkit::cli {
namespace {

constexpr const char* kUsage = "scpkit invert MODEL.json TARGET.csv [-o INPUT.csv] [--json]";
constexpr const char* kAbout =
    "Open-loop compensation: computes the input sequence that makes the model follow the\n"
    "target response in TARGET.csv (its response column: strain, strain_pct or disp_mm), the\n"
    "inverse's memory tracking the plant's from the model's initial state. Exact wherever the\n"
    "target is reachable; otherwise the input saturates at the model's input limit and the row\n"
    "is flagged (reached = 0). Writes the input column (the model's input, canonical unit), the\n"
    "target (under the response column's own name, so `scpkit predict MODEL INPUT.csv` compares\n"
    "against it), predicted_<response>, error_<response> and reached, to INPUT.csv or stdout.";

}  // namespace

int run_invert(const std::vector<std::string>& args) {
  po::options_description opt("options");
  opt.add_options()("help,h", "show this help")("output,o", po::value<std::string>(),
                                                "CSV to write")(
      "json", "print one JSON object (tracking errors) instead of the report");
  po::variables_map vm;
  if (!parse_command_line(args, kUsage, kAbout, opt, {"MODEL", "TARGET"}, vm)) return kOk;
  const ModelFile mf = load_model(vm["MODEL"].as<std::string>());
  const Measurement m = Measurement::read(vm["TARGET"].as<std::string>());
  const ResponseColumn found = find_response(m, mf);
  if (!found.signal) {
    throw InputError(m.source(), m.header_line(), 0,
                     "no target: need a response column (strain, strain_pct or disp_mm)");
  }
  const Signal& target = *found.signal;
  const MeasurementColumn* target_col = found.column;
  const double length_mm = m.meta_number("length_mm").value_or(mf.specimen.length_mm);
  const ModelInputs mi = model_inputs(m, mf);
  for (const auto& w : mi.warnings) std::cerr << "scpkit invert: warning: " << w << "\n";
  const std::vector<InverseStep> steps =
      mf.augmented ? mf.augmented->invert(mi.load_N, target.values, mi.starts)
                   : mf.op.invert(target.values);

  std::vector<double> achieved(steps.size());
  int unreachable = 0;
  for (std::size_t t = 0; t < steps.size(); ++t) {
    achieved[t] = steps[t].output;
    unreachable += steps[t].reached ? 0 : 1;
  }
  const ErrorMetrics err =
      error_metrics(target.values, achieved).scaled(display_scale(mf.response));

  std::ostringstream csv;
  const MeasurementColumn* seg = m.find(Quantity::kSegment);
  const MeasurementColumn* time = m.find(Quantity::kTime);
  if (time) csv << time->name << ",";
  if (seg) csv << "segment,";
  const MeasurementColumn* load = mf.augmented ? m.find(Quantity::kLoad) : nullptr;
  if (load) csv << load->name << ",";
  csv << mf.input << "," << target.column << ",predicted_" << target.column << ",error_"
      << target.column << ",reached\n";
  for (std::size_t t = 0; t < steps.size(); ++t) {
    if (time) csv << m.cell(t, time->position) << ",";
    if (seg) csv << m.cell(t, seg->position) << ",";
    if (load) csv << m.cell(t, load->position) << ",";
    const double tgt = to_column_units(target.values[t], *target_col, length_mm, mf.response);
    const double got = to_column_units(steps[t].output, *target_col, length_mm, mf.response);
    csv << csv_number(steps[t].input) << "," << m.cell(t, target_col->position) << ","
        << csv_number(got) << "," << csv_number(got - tgt) << "," << (steps[t].reached ? 1 : 0)
        << "\n";
  }
  if (vm.count("output")) write_file_atomically(vm["output"].as<std::string>(), csv.str());

  if (vm.count("json")) {
    nlohmann::json j = metrics_json(err);
    j["model"] = mf.augmented ? "augmented" : mf.op.family();
    j["warnings"] = mi.warnings;
    j["rows"] = steps.size();
    j["unreachable"] = unreachable;
    j["input"] = mf.input;
    if (vm.count("output")) j["output_file"] = vm["output"].as<std::string>();
    print_json(j);
  } else {
    if (!vm.count("output")) std::cout << csv.str();
    std::ostream& report = vm.count("output") ? std::cout : std::cerr;
    report << fmt::format("{}: {} targets, {} unreachable; tracking {}\n", m.source(), steps.size(),
                          unreachable, err.brief(display_unit(mf.response)));
    if (vm.count("output"))
      report << "input sequence written to " << vm["output"].as<std::string>() << "\n";
  }
  return kOk;
}

}  // namespace scpkit::cli
