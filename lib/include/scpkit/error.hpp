#pragma once
// Error types of scpkit. Programming errors (a precondition of the API broken) are
// InvalidArgument; bad data in a file is InputError and names file, line and column;
// a fit that cannot be made from the data is IdentificationError. The CLI catches all three
// in one place and maps them to exit codes (docs/cli.md).
#include <fmt/format.h>

#include <stdexcept>
#include <string>
#include <utility>

namespace scpkit {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A precondition of a library call was broken (wrong sizes, non-finite parameter, ...).
class InvalidArgument : public Error {
 public:
  using Error::Error;
};

/// The data cannot identify the requested model (too few rows, no excitation, ...).
class IdentificationError : public Error {
 public:
  using Error::Error;
};

/// Bad input data. what() reads "FILE:LINE:COLUMN: message" (line and column 1-based;
/// 0 when not applicable).
class InputError : public Error {
 public:
  InputError(std::string file, int line, int column, const std::string& message)
      : Error(format_where(file, line, column) + message),
        file_(std::move(file)),
        line_(line),
        column_(column),
        message_(message) {}
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  int column() const { return column_; }
  const std::string& message() const { return message_; }

 private:
  static std::string format_where(const std::string& file, int line, int column) {
    if (line <= 0) return file + ": ";
    if (column <= 0) return fmt::format("{}:{}: ", file, line);
    return fmt::format("{}:{}:{}: ", file, line, column);
  }
  std::string file_;
  int line_;
  int column_;
  std::string message_;
};

/// Throws InvalidArgument with a formatted message. Cold path, kept out of line of callers.
template <typename... Args>
[[noreturn]] void throw_invalid(fmt::format_string<Args...> f, Args&&... args) {
  throw InvalidArgument(fmt::format(f, std::forward<Args>(args)...));
}

}  // namespace scpkit
