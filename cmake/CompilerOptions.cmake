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
  if(SPRINGSCAN_SANITIZE)
    message(FATAL_ERROR "SPRINGSCAN_TSAN and SPRINGSCAN_SANITIZE exclude each other "
                        "(-fsanitize=thread cannot be combined with -fsanitize=address)")
  endif()
  set(SPRINGSCAN_SANITIZER_FLAGS -fsanitize=thread -fno-omit-frame-pointer)
  add_compile_options(${SPRINGSCAN_SANITIZER_FLAGS})
  add_link_options(${SPRINGSCAN_SANITIZER_FLAGS})
endif()
