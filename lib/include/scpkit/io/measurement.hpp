#pragma once
// Measurement files, version 1 (SPEC.md "Measurement files"): UTF-8 CSV, one header row,
// `#` comments, `# key: value` metadata before the header, columns named with their unit.
// Values are converted to canonical units on read:
//   load -> N, voltage -> V, power -> W, temperature -> C, time -> s,
//   strain / strain_pct / thread_strain_pct / scp_strain_pct -> fraction, displacement -> mm.
// Every error names file, line and column (InputError).
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace scpkit {

enum class Quantity {
  kTime,
  kDwell,
  kLoad,
  kVoltage,
  kPower,
  kTemperature,
  kStrain,
  kDisplacement,
  kThreadStrain,
  kScpStrain,
  kSegment,
  kUnknown,  ///< a column scpkit does not use; kept verbatim, never parsed
};

struct MeasurementColumn {
  std::string name;  ///< as in the header, e.g. "load_g"
  Quantity quantity = Quantity::kUnknown;
  double to_canonical = 1.0;   ///< factor from file units to canonical units
  int position = 0;            ///< 0-based field index
  std::vector<double> values;  ///< canonical units; empty for kUnknown
};

class Measurement {
 public:
  /// Reads and validates a file. Throws InputError naming file, line and column.
  static Measurement read(const std::filesystem::path& path);
  /// Parses text; `source` is the name used in error messages.
  static Measurement parse(std::string_view text, const std::string& source);

  const std::string& source() const { return source_; }
  std::size_t rows() const { return row_lines_.size(); }
  const std::vector<MeasurementColumn>& columns() const { return columns_; }
  /// The column holding a quantity, or nullptr.
  const MeasurementColumn* find(Quantity q) const;
  /// Text of a cell, unquoted (for echoing unknown columns; csv_field quotes it again).
  const std::string& cell(std::size_t row, int position) const { return cells_[row][position]; }
  int header_line() const { return header_line_; }
  int line_of_row(std::size_t row) const { return row_lines_[row]; }
  /// 1-based character column where a header field starts (for error messages).
  int header_char_column(int position) const { return header_columns_[position]; }

  const std::map<std::string, std::string>& metadata() const { return metadata_; }
  std::optional<std::string> meta(const std::string& key) const;
  /// A numeric metadata value; InputError at the metadata line when it is not a number.
  std::optional<double> meta_number(const std::string& key) const;
  /// A positive integer metadata value (e.g. plies).
  std::optional<int> meta_positive_int(const std::string& key) const;

  /// An InputError located at a column's header cell.
  [[noreturn]] void fail_at_column(const MeasurementColumn& c, const std::string& message) const;

 private:
  std::string source_;
  std::map<std::string, std::string> metadata_;
  std::map<std::string, int> metadata_lines_;
  std::vector<MeasurementColumn> columns_;
  std::vector<std::vector<std::string>> cells_;
  std::vector<int> row_lines_;
  std::vector<int> header_columns_;
  int header_line_ = 0;
};

/// A canonical input or response series picked from a measurement.
struct Signal {
  std::string name;    ///< canonical name: load_N, voltage_V, power_W, temp_C, strain, disp_mm
  std::string column;  ///< the file's column it came from
  std::vector<double> values;
};

/// True when the column is present and its values are not all equal.
bool column_varies(const MeasurementColumn* column);

/// The hysteresis input: `wanted` (a canonical name) when given, else the one input column
/// that varies. InputError when none or several qualify.
Signal select_input(const Measurement& m, const std::string& wanted = "");
/// The response: strain if present (fraction), else disp_mm / length_mm when the length is
/// known (strain), else disp_mm in mm. `wanted` may ask for "thread" or "scp" paired columns.
Signal select_response(const Measurement& m, const std::string& wanted = "");
/// Canonical unit of a signal for humans: "N", "V", "W", "C", "strain-%" or "mm".
std::string display_unit(const std::string& canonical_name);
/// Factor from canonical to display units (strain fraction -> %, others 1).
double display_scale(const std::string& canonical_name);
/// A cell as a CSV field that Measurement::parse reads back as `text`: quoted (RFC 4180) when
/// it holds a comma, a quote or surrounding blanks, else as it is.
std::string csv_field(const std::string& text);

}  // namespace scpkit
