#pragma once
// Under ASan, UBSan or TSan the analysis runs 5-15x slower: tests shrink their repeated cases
// there (the sanitizer stages look for memory errors and races, the release suite for accuracy).
// The TSan build undefines __SANITIZE_THREAD__ (protobuf's map layout,
// cmake/CompilerOptions.cmake) and defines SPRINGSCAN_TSAN instead.

namespace springscan::analysis::testing {

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__) || defined(SPRINGSCAN_TSAN)
inline constexpr bool kUnderSanitizer = true;
#else
inline constexpr bool kUnderSanitizer = false;
#endif

}  // namespace springscan::analysis::testing
