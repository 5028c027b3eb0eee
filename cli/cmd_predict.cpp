// scpkit predict MODEL DATA.csv: run a model on an input sequence; errors when measured.
#include <fmt/format.h>

#include <iostream>

#include "commands.hpp"
#include "common.hpp"
#include "scpkit/io/atomic_file.hpp"
#include "scpkit/io/model_file.hpp"

namespace scpkit::cli {
namespace {

constexpr const char* kUsage = "scpkit predict MODEL.json DATA.csv [-o OUT.csv] [--json]";
constexpr const char* kAbout =
    "Runs an identified model over the input column of DATA.csv, starting from the model's\n"
    "initial state (negative saturation). Writes the file's columns plus\n"
    "predicted_<response column> to OUT.csv (or to stdout without -o). When DATA.csv also holds\n"
    "the measured response, reports E_max and E_RMS (% of range) and mean |e| +- sigma.\n"
    "With --json, stdout is one JSON object (rms_pct_range, max_pct_range, mean_abs, sd_abs at\n"
    "its top level) and the CSV is written only with -o.";

}  // namespace

int run_predict(const std::vector<std::string>& args) {
  po::options_description opt("options");
  opt.add_options()("help,h", "show this help")("output,o", po::value<std::string>(),
                                                "CSV to write")(
      "json", "print one JSON object (metrics) instead of the report");
  po::variables_map vm;
  if (!parse_command_line(args, kUsage, kAbout, opt, {"MODEL", "DATA"}, vm)) return kOk;
  const ModelFile mf = load_model(vm["MODEL"].as<std::string>());
  const Measurement m = Measurement::read(vm["DATA"].as<std::string>());
  const ModelInputs mi = model_inputs(m, mf);
  const Signal& in = mi.input;
  const std::vector<double> y = mf.augmented
                                    ? mf.augmented->simulate(mi.load_N, in.values, mi.starts)
                                    : mf.op.simulate(in.values);
  for (const auto& w : mi.warnings) std::cerr << "scpkit predict: warning: " << w << "\n";

  const ResponseColumn found = find_response(m, mf);
  const std::optional<Signal>& measured = found.signal;
  const MeasurementColumn* out_col = found.column;
  const double length_mm = m.meta_number("length_mm").value_or(mf.specimen.length_mm);
  std::string predicted_name;
  std::vector<double> predicted_col(m.rows());
  if (out_col) {
    predicted_name = "predicted_" + out_col->name;
    for (std::size_t r = 0; r < m.rows(); ++r) {
      predicted_col[r] = to_column_units(y[r], *out_col, length_mm, mf.response);
    }
  } else {
    predicted_name = mf.response == "strain" ? "predicted_strain_pct" : "predicted_disp_mm";
    for (std::size_t r = 0; r < m.rows(); ++r) {
      predicted_col[r] = y[r] * display_scale(mf.response);
    }
  }

  AppendedColumn predicted{predicted_name, {}};
  for (double v : predicted_col) predicted.cells.push_back(csv_number(v));
  const std::string csv = csv_with_appended(m, {predicted});
  if (vm.count("output")) write_file_atomically(vm["output"].as<std::string>(), csv);

  std::optional<ErrorMetrics> err;
  if (measured) {
    err = error_metrics(measured->values, y).scaled(display_scale(mf.response));
  }
  if (vm.count("json")) {
    nlohmann::json j = err ? metrics_json(*err) : nlohmann::json::object();
    j["rows"] = m.rows();
    j["model"] = mf.augmented ? "augmented" : mf.op.family();
    j["warnings"] = mi.warnings;
    j["input"] = in.name;
    j["response"] = mf.response;
    j["response_unit"] = display_unit(mf.response);
    j["measured"] = err.has_value();
    if (vm.count("output")) j["output_file"] = vm["output"].as<std::string>();
    print_json(j);
  } else {
    if (!vm.count("output")) std::cout << csv;
    // The report goes to stdout only when stdout does not carry the CSV.
    std::ostream& report = vm.count("output") ? std::cout : std::cerr;
    if (err) {
      report << fmt::format("{}: {} rows; {}\n", m.source(), m.rows(),
                            err->brief(display_unit(mf.response)));
    }
    if (vm.count("output"))
      report << "predictions written to " << vm["output"].as<std::string>() << "\n";
  }
  return kOk;
}

}  // namespace scpkit::cli
