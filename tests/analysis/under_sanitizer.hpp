#pragma once
// Under ASan, UBSan or TSan the analysis runs 5-15x slower: tests shrink their repeated cases
// there (the sanitizer stages look for memory errors and races, the release suite for accuracy).
// g++ defines __SANITIZE_ADDRESS__ under -fsanitize=address; clang 14 (the ASan + UBSan build,
// scripts/build.sh sanitize) does not, and says it by __has_feature(address_sanitizer) instead:
// without that test the clang build ran every release-only accuracy case (CI's ASan stage from
// stop 23 on). The TSan build undefines __SANITIZE_THREAD__ (protobuf's map layout,
// cmake/CompilerOptions.cmake) and defines SPRINGSCAN_TSAN instead.

#if defined(__SANITIZE_ADDRESS__)
#define SPRINGSCAN_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SPRINGSCAN_UNDER_ASAN 1
#endif
#endif

namespace springscan::analysis::testing {

#if defined(SPRINGSCAN_UNDER_ASAN) || defined(__SANITIZE_THREAD__) || defined(SPRINGSCAN_TSAN)
inline constexpr bool kUnderSanitizer = true;
#else
inline constexpr bool kUnderSanitizer = false;
#endif

}  // namespace springscan::analysis::testing
