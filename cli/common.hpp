#pragma once
// Shared pieces of the scpkit subcommands: option parsing, exit codes, output.
#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "scpkit/error.hpp"
#include "scpkit/io/held_load.hpp"
#include "scpkit/io/measurement.hpp"
#include "scpkit/io/model_file.hpp"
#include "scpkit/mechanics/coil.hpp"
#include "scpkit/metrics.hpp"

namespace scpkit::cli {

namespace po = boost::program_options;

/// Exit codes (docs/cli.md).
enum ExitCode : int {
  kOk = 0,
  kInternalError = 1,
  kUsageError = 2,
  kInputError = 3,  ///< bad or unusable input data (file:line:column on stderr)
};

/// A command-line mistake: printed with a hint to --help, exit code 2.
class UsageError : public Error {
 public:
  using Error::Error;
};

struct Command {
  const char* name;
  const char* summary;
  int (*run)(const std::vector<std::string>& args);
};

/// Parses `args` against `visible` options plus positionals. Returns false when --help was
/// printed. Throws UsageError on unknown options or missing positionals.
bool parse_command_line(const std::vector<std::string>& args, const char* usage,
                        const char* description, po::options_description& visible,
                        const std::vector<std::string>& positional_names, po::variables_map& vm);

/// `--threads N` (default: the machine's hardware threads), for commands whose result is the
/// same for any count; threads_from reads it back, UsageError outside 1..1024.
void add_threads_option(po::options_description& options, const char* what);
int threads_from(const po::variables_map& vm);

/// Metrics as JSON fields (rms_pct_range, max_pct_range, mean_abs, sd_abs, range, count).
nlohmann::json metrics_json(const ErrorMetrics& m);

/// Prints exactly one JSON object on stdout.
void print_json(const nlohmann::json& j);

/// Converts a canonical response value to the units of the column it came from
/// (strain fraction -> the column's strain unit, or mm via length_mm).
double to_column_units(double canonical, const MeasurementColumn& column, double length_mm,
                       const std::string& canonical_name);

/// "12.34" style number for CSV output.
std::string csv_number(double v);

/// The response a model was fitted to, found in another file: the same column when present,
/// else the file's usual response (InputError when its kind differs from the model's).
/// Empty when the file holds no response at all.
struct ResponseColumn {
  std::optional<Signal> signal;
  const MeasurementColumn* column = nullptr;
};
ResponseColumn find_response(const Measurement& m, const ModelFile& mf);

/// How a model runs on a file: the inputs, and for an augmented model the loads (N) and
/// the segment starts (new segment id or load change). Warnings for loads outside the
/// identified range.
struct ModelInputs {
  Signal input;
  std::vector<double> load_N;  ///< empty unless augmented
  std::vector<char> starts;    ///< empty unless augmented
  std::vector<std::string> warnings;
};
/// The file's column of that name (names are unique in a file); nullptr when none.
const MeasurementColumn* column_named(const Measurement& m, const std::string& name);

/// A column a command writes beside the file's own: its name and one cell per row (blank where
/// it has no value).
struct AppendedColumn {
  std::string name;
  std::vector<std::string> cells;
};
/// The file's metadata (`# key: value`, in key order), columns and rows, its cells echoed as
/// read, with `appended` after them, so the file reads back as the one it came from. An
/// appended name the file (or an earlier appended column) already has gets the first free
/// suffix _2, _3, ..., so no column is lost and every header name is unique.
std::string csv_with_appended(const Measurement& m, const std::vector<AppendedColumn>& appended);

/// Tests at several constant loads: the drive column (voltage, power, temperature; the one asked
/// for, else the first that varies in that order) while the load varies held in segments (runs
/// of readings at one load), unless the user asked for the load as input; else nullptr.
const MeasurementColumn* augmented_drive(const Measurement& m, const std::string& wanted_input);

/// The input of a model with one input (not augmented_drive's case): the one asked for, else
/// the one that varies. Where several vary, a load swept from reading to reading is the input
/// (a load test logging voltage or temperature alongside), else the voltage, then power, then
/// temperature; `note` then says which was chosen. InputError as select_input.
Signal choose_input(const Measurement& m, const std::string& wanted, std::string& note);

ModelInputs model_inputs(const Measurement& m, const ModelFile& mf);

/// The coil of the file's metadata (coil_d_mm, coil_D_mm, coil_n, legs; legs default 1), or
/// nullopt when it gives none. InputError when it gives part of one or an impossible one.
std::optional<CoilGeometry> coil_from_metadata(const Measurement& m);

/// IdentificationError -> InputError located at a column of the data file.
[[noreturn]] void rethrow_at_column(const Measurement& m, const std::string& column,
                                    const std::string& message);

}  // namespace scpkit::cli
