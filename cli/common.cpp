#include "common.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <iostream>
#include <set>
#include <sstream>
#include <thread>
#include <vector>

namespace scpkit::cli {

bool parse_command_line(const std::vector<std::string>& args, const char* usage,
                        const char* description, po::options_description& visible,
                        const std::vector<std::string>& positional_names, po::variables_map& vm) {
  po::options_description all;
  all.add(visible);
  po::options_description hidden;
  po::positional_options_description pos;
  for (const auto& name : positional_names) {
    hidden.add_options()(name.c_str(), po::value<std::string>());
    pos.add(name.c_str(), 1);
  }
  all.add(hidden);
  try {
    po::store(po::command_line_parser(args).options(all).positional(pos).run(), vm);
    if (vm.count("help")) {
      std::cout << "usage: " << usage << "\n\n" << description << "\n\n" << visible << "\n";
      return false;
    }
    po::notify(vm);
  } catch (const po::error& e) {
    throw UsageError(e.what());
  }
  for (const auto& name : positional_names) {
    if (!vm.count(name)) throw UsageError(fmt::format("missing {} (usage: {})", name, usage));
  }
  return true;
}

void add_threads_option(po::options_description& options, const char* what) {
  options.add_options()("threads",
                        po::value<int>()->default_value(
                            static_cast<int>(std::max(1u, std::thread::hardware_concurrency()))),
                        what);
}

int threads_from(const po::variables_map& vm) {
  const int threads = vm["threads"].as<int>();
  if (threads < 1 || threads > 1024) throw UsageError("--threads must be 1..1024");
  return threads;
}

nlohmann::json metrics_json(const ErrorMetrics& m) {
  return {{"rms_pct_range", m.rms_pct_range},
          {"max_pct_range", m.max_pct_range},
          {"mean_abs", m.mean_abs},
          {"sd_abs", m.sd_abs},
          {"range", m.range},
          {"count", m.count}};
}

void print_json(const nlohmann::json& j) { std::cout << j.dump(2) << std::endl; }

double to_column_units(double canonical, const MeasurementColumn& column, double length_mm,
                       const std::string& canonical_name) {
  if (canonical_name == "strain" && column.quantity == Quantity::kDisplacement) {
    return canonical * length_mm / column.to_canonical;
  }
  return canonical / column.to_canonical;
}

std::string csv_number(double v) { return fmt::format("{:.8g}", v); }

ResponseColumn find_response(const Measurement& m, const ModelFile& mf) {
  ResponseColumn r;
  r.column = column_named(m, mf.response_column);
  if (r.column) {
    r.signal = Signal{mf.response, r.column->name, r.column->values};
    if (r.column->quantity == Quantity::kDisplacement && mf.response == "strain") {
      r.signal = select_response(m, "");  // disp_mm -> strain through length_mm
    }
    return r;
  }
  try {
    r.signal = select_response(m, mf.response == "disp_mm" ? "disp_mm" : "");
  } catch (const InputError& e) {
    if (e.message().find("no response column") == std::string::npos) throw;
    return r;
  }
  r.column = column_named(m, r.signal->column);
  if (r.signal->name != mf.response) {
    throw InputError(
        m.source(), m.header_line(), 0,
        fmt::format("the model's response is {} but the file's is {} (give length_mm metadata?)",
                    mf.response, r.signal->name));
  }
  return r;
}

namespace {

/// The electrical and thermal inputs, in the order a drive is chosen among those that vary:
/// the voltage is what a test commands; power and temperature follow from it.
constexpr Quantity kDrives[] = {Quantity::kVoltage, Quantity::kPower, Quantity::kTemperature};

}  // namespace

const MeasurementColumn* column_named(const Measurement& m, const std::string& name) {
  for (const MeasurementColumn& c : m.columns()) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

std::string csv_with_appended(const Measurement& m, const std::vector<AppendedColumn>& appended) {
  std::set<std::string> taken;
  std::vector<std::string> header;
  for (const auto& c : m.columns()) {
    taken.insert(c.name);
    header.push_back(c.name);
  }
  for (const AppendedColumn& a : appended) {
    std::string name = a.name;
    for (int suffix = 2; taken.count(name) != 0; ++suffix)
      name = a.name + "_" + std::to_string(suffix);
    taken.insert(name);
    header.push_back(name);
  }
  std::ostringstream csv;
  for (const auto& [key, value] : m.metadata()) csv << "# " << key << ": " << value << "\n";
  auto write_row = [&csv](const std::vector<std::string>& fields) {
    for (std::size_t k = 0; k < fields.size(); ++k) {
      csv << (k ? "," : "") << csv_field(fields[k]);
    }
    csv << "\n";
  };
  write_row(header);
  std::vector<std::string> row;
  for (std::size_t r = 0; r < m.rows(); ++r) {
    row.clear();
    for (const auto& c : m.columns()) row.push_back(m.cell(r, c.position));
    for (const AppendedColumn& a : appended) row.push_back(a.cells.at(r));
    write_row(row);
  }
  return csv.str();
}

const MeasurementColumn* augmented_drive(const Measurement& m, const std::string& wanted_input) {
  const MeasurementColumn* load = m.find(Quantity::kLoad);
  if (!load_is_held(m)) return nullptr;
  if (!wanted_input.empty()) {
    const std::string column = select_input(m, wanted_input).column;
    if (column == load->name) return nullptr;
    return column_named(m, column);
  }
  for (Quantity q : kDrives) {
    if (column_varies(m.find(q))) return m.find(q);
  }
  return nullptr;
}

Signal choose_input(const Measurement& m, const std::string& wanted, std::string& note) {
  if (!wanted.empty()) return select_input(m, wanted);
  const MeasurementColumn* load = m.find(Quantity::kLoad);
  std::vector<const MeasurementColumn*> drives;
  for (Quantity q : kDrives) {
    if (column_varies(m.find(q))) drives.push_back(m.find(q));
  }
  if (drives.empty()) return select_input(m, wanted);
  const MeasurementColumn* chosen = nullptr;
  if (column_varies(load)) {
    if (load_is_held(m)) return select_input(m, wanted);  // several loads: augmented_drive
    chosen = load;  // swept reading to reading: a load test, the others logged alongside
  } else if (drives.size() > 1) {
    chosen = drives.front();
  } else {
    return select_input(m, wanted);
  }
  std::string others;
  for (const MeasurementColumn* c : drives) {
    if (c != chosen) others += (others.empty() ? "" : ", ") + c->name;
  }
  note = fmt::format("several inputs vary; the input is {}{}, not {} (--input to choose)",
                     chosen->name,
                     chosen == load ? " (the load changes from reading to reading)" : "", others);
  return select_input(m, chosen->name);
}

ModelInputs model_inputs(const Measurement& m, const ModelFile& mf) {
  ModelInputs r{select_input(m, mf.input), {}, {}, {}};
  if (!mf.augmented) return r;
  const MeasurementColumn* load = m.find(Quantity::kLoad);
  if (!load) {
    throw InputError(m.source(), m.header_line(), 0,
                     "the model is augmented (several loads): the file needs a load column "
                     "(load_g, load_mN or load_N)");
  }
  r.load_N = held_load_N(m);
  std::vector<int> ids;
  if (const MeasurementColumn* seg = m.find(Quantity::kSegment)) {
    for (double v : seg->values) ids.push_back(static_cast<int>(v));
  }
  r.starts.assign(m.rows(), 0);
  for (std::size_t t = 0; t < m.rows(); ++t) {
    const bool start =
        t == 0 || (!ids.empty() && ids[t] != ids[t - 1]) || r.load_N[t] != r.load_N[t - 1];
    // A restart after a load increase re-arms the lonely stroke with the opposite sign.
    r.starts[t] =
        !start ? kContinue
               : (t > 0 && r.load_N[t] > r.load_N[t - 1] ? kRestartAfterLoadIncrease : kRestart);
    if (mf.augmented->outside_load_range(r.load_N[t]) && (t == 0 || r.starts[t])) {
      r.warnings.push_back(fmt::format(
          "line {}: load {:.4g} N is outside the identified range [{:.4g}, {:.4g}] N "
          "(extrapolated)",
          m.line_of_row(t), r.load_N[t], mf.augmented->load_min, mf.augmented->load_max));
    }
  }
  return r;
}

void rethrow_at_column(const Measurement& m, const std::string& column,
                       const std::string& message) {
  for (const auto& c : m.columns()) {
    if (c.name == column) m.fail_at_column(c, message);
  }
  throw InputError(m.source(), m.header_line(), 0, message);
}

std::optional<CoilGeometry> coil_from_metadata(const Measurement& m) {
  const auto d = m.meta_number("coil_d_mm"), D = m.meta_number("coil_D_mm"),
             n = m.meta_number("coil_n");
  if (!d && !D && !n) return std::nullopt;
  if (!d || !D || !n) {
    throw InputError(m.source(), 0, 0,
                     "coil metadata needs all of coil_d_mm, coil_D_mm and coil_n");
  }
  CoilGeometry c;
  c.wire_d_m = *d * 1e-3;
  c.mean_D_m = *D * 1e-3;
  c.coils = *n;
  c.legs = m.meta_positive_int("legs").value_or(1);
  try {
    c.validate();
  } catch (const InvalidArgument& e) {
    throw InputError(m.source(), 0, 0, std::string("coil metadata: ") + e.what());
  }
  return c;
}

}  // namespace scpkit::cli
