// libFuzzer target: the point and mesh file parsers (PLY ascii/binary, XYZ/CSV/TXT, STL ascii
// and binary) on arbitrary bytes, and a mesh that parses on to the mesh decimation (the path of
// `springscan analyze --decimate`). The first byte picks the format, the rest is the file. Any
// input must give a value or an error, never a crash, a hang or an allocation past what the
// bytes can hold (the parsers check counts against the bytes left).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "analysis/io/point_io.hpp"
#include "analysis/preprocess/decimation.hpp"

namespace {

using namespace springscan::analysis;

// Hostile meshes (out-of-range or repeated indices, NaN corners, non-manifold fans) must be
// refused or decimated, never crash VTK. Small ones only: the decimation, not the input size,
// is what is fuzzed here.
void decimate(const Expected<Surface>& surface) {
  constexpr std::size_t kMaxTriangles = 512;
  if (!surface || surface->triangles.empty() || surface->triangles.size() > kMaxTriangles) return;
  TriangleMesh mesh{surface->cloud.points, surface->triangles};
  (void)decimate_mesh(mesh, {.threads = 1});
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  switch (data[0] % 3) {
    case 0:
      decimate(parse_ply(bytes, "fuzz.ply"));
      break;
    case 1:
      (void)parse_xyz(bytes, "fuzz.xyz");
      break;
    default:
      decimate(parse_stl(bytes, "fuzz.stl"));
      break;
  }
  return 0;
}
