#pragma once
// Private helper: typed, located reads from a toml++ table. Every failure is an InputError
// at the offending node's line and column. Kept out of the public headers so that toml++
// is compiled only where a file is read.
#include <fmt/format.h>
#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <string>

#include "scpkit/error.hpp"

namespace scpkit::detail {

class TomlReader {
 public:
  /// Parses the file; syntax errors become located InputErrors.
  static toml::table parse(const std::filesystem::path& path) {
    try {
      return toml::parse_file(path.string());
    } catch (const toml::parse_error& e) {
      const auto& b = e.source().begin;
      throw InputError(path.string(), static_cast<int>(b.line), static_cast<int>(b.column),
                       std::string(e.description()));
    }
  }

  explicit TomlReader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const toml::node* at, const std::string& msg) const {
    if (at) {
      const auto& b = at->source().begin;
      throw InputError(file_, static_cast<int>(b.line), static_cast<int>(b.column), msg);
    }
    throw InputError(file_, 0, 0, msg);
  }

  /// Rejects keys outside `allowed` (catches typos such as 'nosie_mm').
  void only_keys(const toml::table& t, std::initializer_list<const char*> allowed) const {
    for (const auto& [k, v] : t) {
      bool ok = false;
      for (const char* a : allowed) ok = ok || k.str() == a;
      if (!ok) {
        const auto& b = k.source().begin;
        (void)v;
        throw InputError(file_, static_cast<int>(b.line), static_cast<int>(b.column),
                         fmt::format("unknown key '{}'", k.str()));
      }
    }
  }

  std::string text(const toml::table& t, const char* key, const std::string& fallback,
                   bool required = false) const {
    const toml::node* n = t.get(key);
    if (!n) {
      if (required) fail(&t, fmt::format("missing key '{}'", key));
      return fallback;
    }
    if (!n->is_string()) fail(n, fmt::format("'{}' must be a string", key));
    return std::string(*n->value<std::string>());
  }

  double number(const toml::table& t, const char* key, double fallback, double min,
                bool required = false, bool strictly_above = false) const {
    const toml::node* n = t.get(key);
    if (!n) {
      if (required) fail(&t, fmt::format("missing key '{}'", key));
      return fallback;
    }
    const auto v = n->value<double>();
    if (!v || !std::isfinite(*v)) fail(n, fmt::format("'{}' must be a number", key));
    if (strictly_above ? !(*v > min) : !(*v >= min)) {
      fail(n, fmt::format("'{}' must be {} {}", key, strictly_above ? ">" : ">=", min));
    }
    return *v;
  }

  double positive(const toml::table& t, const char* key, double fallback = 0.0,
                  bool required = true) const {
    return number(t, key, fallback, 0.0, required, true);
  }

  long long integer(const toml::table& t, const char* key, long long fallback, long long min,
                    long long max) const {
    const toml::node* n = t.get(key);
    if (!n) return fallback;
    const auto v = n->value<long long>();
    if (!n->is_integer() || !v) fail(n, fmt::format("'{}' must be an integer", key));
    if (*v < min || *v > max) fail(n, fmt::format("'{}' must be in {}..{}", key, min, max));
    return *v;
  }

  bool boolean(const toml::table& t, const char* key, bool fallback) const {
    const toml::node* n = t.get(key);
    if (!n) return fallback;
    if (!n->is_boolean()) fail(n, fmt::format("'{}' must be true or false", key));
    return *n->value<bool>();
  }

  const toml::table* table(const toml::table& t, const char* key, bool required = false) const {
    const toml::node* n = t.get(key);
    if (!n) {
      if (required) fail(&t, fmt::format("missing table [{}]", key));
      return nullptr;
    }
    if (!n->is_table()) fail(n, fmt::format("'{}' must be a table", key));
    return n->as_table();
  }

 private:
  std::string file_;
};

}  // namespace scpkit::detail
