// libFuzzer target: the point and mesh file parsers (PLY ascii/binary, XYZ/CSV/TXT, STL ascii
// and binary) on arbitrary bytes. The first byte picks the format, the rest is the file. Any
// input must give a value or an error, never a crash, a hang or an allocation past what the
// bytes can hold (the parsers check counts against the bytes left).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "analysis/io/point_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace springscan::analysis;
  if (size == 0) return 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  switch (data[0] % 3) {
    case 0:
      (void)parse_ply(bytes, "fuzz.ply");
      break;
    case 1:
      (void)parse_xyz(bytes, "fuzz.xyz");
      break;
    default:
      (void)parse_stl(bytes, "fuzz.stl");
      break;
  }
  return 0;
}
