#include "scpkit/io/measurement.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>
#include <utility>

#include "scpkit/error.hpp"
#include "scpkit/io/atomic_file.hpp"

namespace scpkit {
namespace {

struct UnitRule {
  const char* name;  // exact column name
  Quantity quantity;
  double factor;
};

// Every column name scpkit understands, with its factor to canonical units.
constexpr UnitRule kUnits[] = {
    {"time_s", Quantity::kTime, 1.0},
    {"time_ms", Quantity::kTime, 1e-3},
    {"time_min", Quantity::kTime, 60.0},
    {"time_h", Quantity::kTime, 3600.0},
    {"dwell_s", Quantity::kDwell, 1.0},
    {"dwell_min", Quantity::kDwell, 60.0},
    {"load_g", Quantity::kLoad, 9.80665e-3},
    {"load_mN", Quantity::kLoad, 1e-3},
    {"load_N", Quantity::kLoad, 1.0},
    {"load_kg", Quantity::kLoad, 9.80665},
    {"voltage_V", Quantity::kVoltage, 1.0},
    {"voltage_mV", Quantity::kVoltage, 1e-3},
    {"power_W", Quantity::kPower, 1.0},
    {"power_mW", Quantity::kPower, 1e-3},
    {"temp_C", Quantity::kTemperature, 1.0},
    {"strain", Quantity::kStrain, 1.0},
    {"strain_pct", Quantity::kStrain, 0.01},
    {"disp_mm", Quantity::kDisplacement, 1.0},
    {"disp_um", Quantity::kDisplacement, 1e-3},
    {"disp_m", Quantity::kDisplacement, 1e3},
    {"thread_strain", Quantity::kThreadStrain, 1.0},
    {"thread_strain_pct", Quantity::kThreadStrain, 0.01},
    {"scp_strain", Quantity::kScpStrain, 1.0},
    {"scp_strain_pct", Quantity::kScpStrain, 0.01},
    {"segment", Quantity::kSegment, 1.0},
};

// Prefixes that name a quantity, with the quantities a column of that prefix may be (the
// response is strain or displacement). A column starting with one but not in kUnits has an
// unknown unit, which is an error rather than a silently ignored column, when its rest reads
// as one unit (no '_') and no column of that quantity is there: then it is the quantity the
// file meant to give. Otherwise it is another column (`temp_ambient_C`, `load_cell_raw`, or a
// `time_stamp` beside `time_s`), ignored as SPEC.md has unknown columns.
struct PrefixRule {
  const char* prefix;
  const char* units;
  Quantity quantity;
  Quantity also;
};
constexpr PrefixRule kPrefixes[] = {
    {"time_", "s, ms, min or h", Quantity::kTime, Quantity::kTime},
    {"dwell_", "s or min", Quantity::kDwell, Quantity::kDwell},
    {"load_", "g, mN, N or kg", Quantity::kLoad, Quantity::kLoad},
    {"voltage_", "V or mV", Quantity::kVoltage, Quantity::kVoltage},
    {"power_", "W or mW", Quantity::kPower, Quantity::kPower},
    {"temp_", "C", Quantity::kTemperature, Quantity::kTemperature},
    {"disp_", "mm, um or m", Quantity::kDisplacement, Quantity::kStrain},
    {"strain_", "pct (or plain 'strain' for a fraction)", Quantity::kStrain,
     Quantity::kDisplacement},
};

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

/// The fields of one line and the 1-based character column where each starts. A field may be
/// quoted as RFC 4180 has it ("load_g", "a, b", "say ""x""": spreadsheets and CSV writers quote
/// when told to); a quoted field does not span lines.
std::pair<std::vector<std::string>, std::vector<int>> split_fields(std::string_view line,
                                                                   const std::string& source,
                                                                   int line_no) {
  std::vector<std::string> fields;
  std::vector<int> starts;
  std::size_t f0 = 0;
  while (true) {
    starts.push_back(static_cast<int>(f0) + 1);
    std::size_t comma = line.find(',', f0);
    const std::size_t open = line.find_first_not_of(" \t", f0);
    if (open != std::string_view::npos && line[open] == '"' && open < comma) {
      std::string text;
      std::size_t i = open + 1;
      for (;; ++i) {
        if (i >= line.size())
          throw InputError(source, line_no, static_cast<int>(open) + 1,
                           "a quoted field has no closing quote on its line");
        if (line[i] != '"') {
          text += line[i];
        } else if (i + 1 < line.size() && line[i + 1] == '"') {
          text += '"';
          ++i;
        } else {
          break;
        }
      }
      comma = line.find(',', i + 1);
      const std::size_t f1 = comma == std::string_view::npos ? line.size() : comma;
      if (!trim(line.substr(i + 1, f1 - i - 1)).empty())
        throw InputError(source, line_no, static_cast<int>(i) + 2,
                         "text after the closing quote of a quoted field");
      fields.push_back(std::move(text));
    } else {
      const std::size_t f1 = comma == std::string_view::npos ? line.size() : comma;
      fields.emplace_back(trim(line.substr(f0, f1 - f0)));
    }
    if (comma == std::string_view::npos) break;
    f0 = comma + 1;
  }
  return {std::move(fields), std::move(starts)};
}

const char* quantity_word(Quantity q) {
  switch (q) {
    case Quantity::kTime:
      return "time";
    case Quantity::kDwell:
      return "dwell";
    case Quantity::kLoad:
      return "load";
    case Quantity::kVoltage:
      return "voltage";
    case Quantity::kPower:
      return "power";
    case Quantity::kTemperature:
      return "temperature";
    case Quantity::kStrain:
    case Quantity::kDisplacement:
      return "response";
    case Quantity::kThreadStrain:
      return "thread strain";
    case Quantity::kScpStrain:
      return "SCP strain";
    case Quantity::kSegment:
      return "segment";
    case Quantity::kUnknown:
      return "unknown";
  }
  return "unknown";
}

}  // namespace

Measurement Measurement::read(const std::filesystem::path& path) {
  return parse(read_text_file(path), path.string());
}

Measurement Measurement::parse(std::string_view text, const std::string& source) {
  Measurement m;
  m.source_ = source;
  if (text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  int line_no = 0;
  bool have_header = false;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (trim(line).empty()) {
      if (end == text.size()) break;
      continue;
    }
    if (trim(line).front() == '#') {
      if (!have_header) {
        std::string_view body = trim(trim(line).substr(1));
        const std::size_t colon = body.find(':');
        if (colon != std::string_view::npos && colon > 0) {
          const std::string_view key = trim(body.substr(0, colon));
          const bool word = std::all_of(key.begin(), key.end(), [](char c) {
            return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
          });
          if (word) {
            m.metadata_[std::string(key)] = std::string(trim(body.substr(colon + 1)));
            m.metadata_lines_[std::string(key)] = line_no;
          }
        }
      }
      if (end == text.size()) break;
      continue;
    }
    auto [fields, starts] = split_fields(line, source, line_no);
    if (!have_header) {
      have_header = true;
      m.header_line_ = line_no;
      m.header_columns_ = starts;
      std::set<std::string> names;
      std::set<Quantity> seen;
      for (std::size_t i = 0; i < fields.size(); ++i) {
        const std::string& name = fields[i];
        // An unnamed column is an unknown one (pandas writes its row index so).
        if (!name.empty() && !names.insert(name).second) {
          throw InputError(source, line_no, starts[i],
                           fmt::format("column '{}' appears twice", name));
        }
        MeasurementColumn c;
        c.name = name;
        c.position = static_cast<int>(i);
        for (const auto& u : kUnits) {
          if (name == u.name) {
            c.quantity = u.quantity;
            c.to_canonical = u.factor;
          }
        }
        if (c.quantity != Quantity::kUnknown && !seen.insert(c.quantity).second &&
            c.quantity != Quantity::kStrain && c.quantity != Quantity::kDisplacement) {
          throw InputError(source, line_no, starts[i],
                           fmt::format("a second {} column '{}'", quantity_word(c.quantity), name));
        }
        m.columns_.push_back(std::move(c));
      }
      for (const MeasurementColumn& c : m.columns_) {
        if (c.quantity != Quantity::kUnknown) continue;
        for (const PrefixRule& r : kPrefixes) {
          if (c.name.rfind(r.prefix, 0) != 0) continue;
          const std::string unit = c.name.substr(std::string_view(r.prefix).size());
          if (unit.find('_') != std::string::npos || seen.count(r.quantity) || seen.count(r.also))
            continue;
          throw InputError(
              source, line_no, starts[static_cast<std::size_t>(c.position)],
              fmt::format("unknown unit '{}' in column '{}' (use {})", unit, c.name, r.units));
        }
      }
      if (end == text.size()) break;
      continue;
    }
    if (fields.size() != m.columns_.size()) {
      const int col = fields.size() < m.columns_.size() ? static_cast<int>(line.size()) + 1
                                                        : starts[m.columns_.size()];
      throw InputError(
          source, line_no, col,
          fmt::format("{} fields, the header has {}", fields.size(), m.columns_.size()));
    }
    for (auto& c : m.columns_) {
      if (c.quantity == Quantity::kUnknown) continue;
      const std::string& cell = fields[c.position];
      const int col = starts[c.position];
      if (cell.empty()) {
        throw InputError(source, line_no, col, fmt::format("empty value in column '{}'", c.name));
      }
      double v = 0.0;
      const char* b = cell.data();
      const char* e = cell.data() + cell.size();
      if (*b == '+') ++b;
      const auto [ptr, ec] = std::from_chars(b, e, v);
      if (ec != std::errc() || ptr != e) {
        throw InputError(source, line_no, col,
                         fmt::format("'{}' is not a number (column '{}')", cell, c.name));
      }
      if (!std::isfinite(v)) {
        throw InputError(source, line_no, col,
                         fmt::format("'{}' is not a finite number (column '{}')", cell, c.name));
      }
      if (c.quantity == Quantity::kSegment && v != std::floor(v)) {
        throw InputError(source, line_no, col, fmt::format("segment '{}' is not an integer", cell));
      }
      c.values.push_back(v * c.to_canonical);
    }
    m.cells_.push_back(std::move(fields));
    m.row_lines_.push_back(line_no);
    if (end == text.size()) break;
  }
  if (!have_header) throw InputError(source, std::max(line_no, 1), 0, "empty file: no header row");
  if (m.rows() == 0) throw InputError(source, m.header_line_, 0, "no data rows after the header");
  return m;
}

const MeasurementColumn* Measurement::find(Quantity q) const {
  for (const auto& c : columns_) {
    if (c.quantity == q) return &c;
  }
  return nullptr;
}

std::optional<std::string> Measurement::meta(const std::string& key) const {
  const auto it = metadata_.find(key);
  if (it == metadata_.end()) return std::nullopt;
  return it->second;
}

std::optional<double> Measurement::meta_number(const std::string& key) const {
  const auto s = meta(key);
  if (!s) return std::nullopt;
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(s->data(), s->data() + s->size(), v);
  if (ec != std::errc() || ptr != s->data() + s->size() || !std::isfinite(v)) {
    throw InputError(source_, metadata_lines_.at(key), 0,
                     fmt::format("metadata '{}' must be a number, got '{}'", key, *s));
  }
  return v;
}

std::optional<int> Measurement::meta_positive_int(const std::string& key) const {
  const auto v = meta_number(key);
  if (!v) return std::nullopt;
  if (*v < 1 || *v != std::floor(*v) || *v > 1e6) {
    throw InputError(
        source_, metadata_lines_.at(key), 0,
        fmt::format("metadata '{}' must be a positive integer, got '{}'", key, *meta(key)));
  }
  return static_cast<int>(*v);
}

void Measurement::fail_at_column(const MeasurementColumn& c, const std::string& message) const {
  throw InputError(source_, header_line_, header_columns_[c.position], message);
}

namespace {

struct InputKind {
  Quantity quantity;
  const char* canonical;
};
constexpr InputKind kInputs[] = {{Quantity::kLoad, "load_N"},
                                 {Quantity::kVoltage, "voltage_V"},
                                 {Quantity::kPower, "power_W"},
                                 {Quantity::kTemperature, "temp_C"}};

}  // namespace

bool column_varies(const MeasurementColumn* column) {
  if (!column || column->values.empty()) return false;
  const auto [lo, hi] = std::minmax_element(column->values.begin(), column->values.end());
  return *hi > *lo;
}

Signal select_input(const Measurement& m, const std::string& wanted) {
  std::vector<const InputKind*> present;
  for (const auto& k : kInputs) {
    const MeasurementColumn* c = m.find(k.quantity);
    if (!c) continue;
    if (!wanted.empty()) {
      const std::string stem =
          std::string(k.canonical).substr(0, std::string(k.canonical).find('_'));
      if (wanted == k.canonical || wanted == c->name || wanted == stem)
        return {k.canonical, c->name, c->values};
      continue;
    }
    if (column_varies(c)) present.push_back(&k);
  }
  if (!wanted.empty()) {
    throw InputError(
        m.source(), m.header_line(), 0,
        fmt::format("no input column for '{}' (load_g/mN/N, voltage_V, power_W, temp_C)", wanted));
  }
  if (present.empty()) {
    throw InputError(m.source(), m.header_line(), 0,
                     "no varying input column: need one of load_g, load_mN, load_N, voltage_V, "
                     "power_W, temp_C");
  }
  if (present.size() > 1) {
    throw InputError(m.source(), m.header_line(), 0,
                     fmt::format("several inputs vary ({} and {}); choose one with --input",
                                 present[0]->canonical, present[1]->canonical));
  }
  const MeasurementColumn* c = m.find(present[0]->quantity);
  return {present[0]->canonical, c->name, c->values};
}

Signal select_response(const Measurement& m, const std::string& wanted) {
  if (wanted == "thread" || wanted == "scp") {
    const MeasurementColumn* c =
        m.find(wanted == "thread" ? Quantity::kThreadStrain : Quantity::kScpStrain);
    if (!c) {
      throw InputError(m.source(), m.header_line(), 0,
                       fmt::format("no {}_strain_pct column", wanted));
    }
    return {"strain", c->name, c->values};
  }
  if (!wanted.empty() && wanted != "strain" && wanted != "disp_mm") {
    throw InvalidArgument(
        fmt::format("unknown response '{}' (strain, disp_mm, thread, scp)", wanted));
  }
  const MeasurementColumn* strain = nullptr;
  const MeasurementColumn* disp = nullptr;
  for (const auto& c : m.columns()) {
    if (c.quantity == Quantity::kStrain && !strain) strain = &c;
    if (c.quantity == Quantity::kDisplacement && !disp) disp = &c;
  }
  if (strain && wanted != "disp_mm") return {"strain", strain->name, strain->values};
  if (disp) {
    const auto length = m.meta_number("length_mm");
    if (length && wanted != "disp_mm") {
      if (!(*length > 0.0)) {
        throw InputError(m.source(), 0, 0, "metadata 'length_mm' must be positive");
      }
      Signal s{"strain", disp->name, disp->values};
      for (double& v : s.values) v /= *length;
      return s;
    }
    return {"disp_mm", disp->name, disp->values};
  }
  // A test of one specimen written with its paired-test column (`scp_strain_pct` alone).
  const MeasurementColumn* thread = m.find(Quantity::kThreadStrain);
  const MeasurementColumn* scp = m.find(Quantity::kScpStrain);
  if (wanted.empty() && (thread == nullptr) != (scp == nullptr)) {
    const MeasurementColumn* c = thread ? thread : scp;
    return {"strain", c->name, c->values};
  }
  throw InputError(m.source(), m.header_line(), 0,
                   "no response column: need strain, strain_pct or disp_mm");
}

std::string display_unit(const std::string& n) {
  if (n == "load_N") return "N";
  if (n == "voltage_V") return "V";
  if (n == "power_W") return "W";
  if (n == "temp_C") return "C";
  if (n == "strain") return "strain-%";
  if (n == "disp_mm") return "mm";
  return "";
}

double display_scale(const std::string& n) { return n == "strain" ? 100.0 : 1.0; }

std::string csv_field(const std::string& text) {
  const bool blank_edge = trim(text).size() != text.size();  // the reader would trim them
  if (!blank_edge && text.find_first_of(",\"") == std::string::npos) return text;
  std::string q = "\"";
  for (char c : text) {
    if (c == '"') q += '"';
    q += c;
  }
  return q + '"';
}

}  // namespace scpkit
