#pragma once
// Output files are written whole or not at all: the content goes to a temporary file in the
// destination's folder, is flushed, and is renamed over the destination. A failure leaves
// the destination as it was.
#include <filesystem>
#include <string_view>

namespace scpkit {

/// Throws InputError (naming the path) when the file cannot be written.
void write_file_atomically(const std::filesystem::path& path, std::string_view content);

/// Reads a whole text file; InputError naming the path when it cannot.
std::string read_text_file(const std::filesystem::path& path);

}  // namespace scpkit
