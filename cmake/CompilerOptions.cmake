# Warnings and sanitizers are set per target, never globally (STYLE.md section 1).
function(springscan_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow
                                           -Wnon-virtual-dtor -Wcast-align)
  if(SPRINGSCAN_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# The sanitizer build instruments every target, including generated protobuf code, so it is
# applied to the whole build through these two variables rather than per target.
if(SPRINGSCAN_SANITIZE)
  set(SPRINGSCAN_SANITIZER_FLAGS -fsanitize=address,undefined -fno-omit-frame-pointer
                                 -fno-sanitize-recover=undefined)
  add_compile_options(${SPRINGSCAN_SANITIZER_FLAGS})
  add_link_options(${SPRINGSCAN_SANITIZER_FLAGS})
endif()

# springscan_inline_eigen(TARGET): under ASan + UBSan, Eigen's small functions (coefficient
# access, expression evaluators) inlined by force in TARGET. clang inserts UBSan's checks before
# it inlines, and with them each of those functions exceeds the inliner's threshold and stays a
# call: the analysis then runs several times slower than it needs to (docs/performance.md,
# "CI's own time"). always_inline keeps every check, inlined. Set on the computing libraries
# only, where the sanitizer suite spends its time: it costs compile time, which the test
# programs' glue would not pay back. No-op in the other builds.
function(springscan_inline_eigen target)
  if(SPRINGSCAN_SANITIZE)
    target_compile_definitions(${target} PRIVATE
                               "EIGEN_STRONG_INLINE=__attribute__((always_inline)) inline")
  endif()
endfunction()

# The libFuzzer targets of tests/fuzz (clang) live in the ASan + UBSan build beside the tests
# (scripts/build.sh sanitize), so CI compiles the project under ASan once, not twice. Coverage
# instrumentation (fuzzer-no-link) goes only on the code that parses untrusted bytes, through
# springscan_fuzz_coverage(): it is what guides the fuzzer, and instrumenting the whole analysis
# would slow every sanitizer test for nothing.
if(SPRINGSCAN_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "SPRINGSCAN_FUZZ needs clang (libFuzzer): CXX=clang++")
  endif()
  if(NOT SPRINGSCAN_SANITIZE)
    message(FATAL_ERROR "SPRINGSCAN_FUZZ needs SPRINGSCAN_SANITIZE (the fuzzers run under ASan)")
  endif()
endif()

# springscan_fuzz_coverage(TARGET [SOURCES file...]): coverage instrumentation for libFuzzer on
# all of TARGET's sources, or only on the SOURCES given (in the calling directory). No-op
# unless SPRINGSCAN_FUZZ.
function(springscan_fuzz_coverage target)
  if(NOT SPRINGSCAN_FUZZ)
    return()
  endif()
  cmake_parse_arguments(PARSE_ARGV 1 arg "" "" "SOURCES")
  if(arg_SOURCES)
    set_property(SOURCE ${arg_SOURCES} APPEND PROPERTY COMPILE_OPTIONS -fsanitize=fuzzer-no-link)
  else()
    target_compile_options(${target} PRIVATE -fsanitize=fuzzer-no-link)
  endif()
endfunction()

# ThreadSanitizer, likewise for the whole build. It cannot share a process with
# AddressSanitizer, hence a build of its own (scripts/build.sh tsan, build-tsan/).
if(SPRINGSCAN_TSAN)
  if(SPRINGSCAN_SANITIZE OR SPRINGSCAN_FUZZ)
    message(FATAL_ERROR "SPRINGSCAN_TSAN excludes SPRINGSCAN_SANITIZE and SPRINGSCAN_FUZZ "
                        "(-fsanitize=thread cannot be combined with -fsanitize=address)")
  endif()
  set(SPRINGSCAN_SANITIZER_FLAGS -fsanitize=thread -fno-omit-frame-pointer)
  add_compile_options(${SPRINGSCAN_SANITIZER_FLAGS})
  add_link_options(${SPRINGSCAN_SANITIZER_FLAGS})
  # protobuf 3.21's map_field.h gives MapFieldBase two more members when __SANITIZE_THREAD__ is
  # defined. Debian's libprotobuf is built without TSan, so our instrumented code and the library
  # would disagree on the layout of every map field (google.protobuf.Struct in the MQTT tests: a
  # SEGV in Map::find). Hence the macro is undefined; libstdc++'s one use of it, _GLIBCXX_TSAN
  # (a shared_ptr release path TSan can follow), is defined directly, and our code tests
  # SPRINGSCAN_TSAN.
  add_compile_options(-U__SANITIZE_THREAD__)
  add_compile_definitions(_GLIBCXX_TSAN=1 SPRINGSCAN_TSAN=1)
endif()
