#pragma once
// Where the tests and the figures programs find the checkout, the shared CAD data and the
// programs they start. The values live in one small file CMake generates per target
// (cmake/TestPaths.cmake), not in compile definitions: every other object file is then the same
// whatever folder the checkout is in, and ccache hits across clones (scripts/ccache-launcher.sh).
#include <string>

namespace springscan::test_paths {

extern const char* const kSourceDir;    // the checkout's root
extern const char* const kSharedDir;    // ../shared beside it: data/cad/ and the references
extern const char* const kPython3;      // Debian's python3, which sees python3-paho-mqtt/pymodbus
extern const char* const kSpringscand;  // the built programs; "" where a target is not built
extern const char* const kSpringscan;
extern const char* const kScannerSim;

// A file of the checkout: source("tests/daemon/pymodbus_plc.py").
inline std::string source(const std::string& relative) {
  return std::string(kSourceDir) + "/" + relative;
}

// A CAD file of ../shared/data/cad/.
inline std::string shared_cad(const std::string& name) {
  return std::string(kSharedDir) + "/data/cad/" + name;
}

}  // namespace springscan::test_paths
