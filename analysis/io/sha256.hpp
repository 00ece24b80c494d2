#pragma once
// SHA-256 (FIPS 180-4), small and dependency-free: the content key of the CAD model cache.

#include <string>
#include <string_view>

#include "analysis/core/expected.hpp"

namespace springscan::analysis {

/// The SHA-256 of `data` as 64 lowercase hex digits. Pure and thread-safe.
std::string sha256_hex(std::string_view data);

/// The SHA-256 of a file's bytes, read in 64 KiB blocks. Errors name the file.
Expected<std::string> sha256_file(const std::string& path);

}  // namespace springscan::analysis
