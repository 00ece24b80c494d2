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
# The fuzz build (clang): coverage instrumentation and ASan + UBSan everywhere, libFuzzer's
# main only in the fuzz targets (tests/fuzz/CMakeLists.txt).
if(SPRINGSCAN_FUZZ)
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer
                      -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()

if(SPRINGSCAN_SANITIZE)
  set(SPRINGSCAN_SANITIZER_FLAGS -fsanitize=address,undefined -fno-omit-frame-pointer
                                 -fno-sanitize-recover=undefined)
  add_compile_options(${SPRINGSCAN_SANITIZER_FLAGS})
  add_link_options(${SPRINGSCAN_SANITIZER_FLAGS})
endif()

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
