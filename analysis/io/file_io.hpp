#pragma once
// Whole-file reads and crash-safe writes, shared by the point and report readers/writers and
// the daemon's report store. POSIX only (Debian 12).

#include <string>
#include <string_view>

#include "analysis/core/expected.hpp"

namespace springscan::analysis {

/// Reads the whole file into memory in one go. Errors name the path and the OS reason.
/// Thread-safe (no shared state).
Expected<std::string> read_file_bytes(const std::string& path);

/// Writes `bytes` to `path` so that a reader (or a crash at any moment) sees either the old file
/// or the complete new one, never a partial file: write DIR/.NAME.tmp, fsync it, rename it over
/// `path`, fsync DIR. On failure the temporary file is removed and the error names the path and
/// the OS reason. Two writers to the same path at once must be serialized by the caller.
Expected<bool> write_file_atomically(const std::string& path, std::string_view bytes);

}  // namespace springscan::analysis
