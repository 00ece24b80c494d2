#pragma once
// Test and benchmark helper: the triangulation a scanner makes of its own sampling grid (rows of
// points, each row a laser line), as two triangles per grid cell.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace springscan::analysis::testing {

/// Triangles of a `rows` x `columns` grid of points stored row by row (point r * columns + c),
/// two per cell, all wound the same way.
inline std::vector<std::array<std::uint32_t, 3>> grid_triangles(std::size_t rows,
                                                                std::size_t columns) {
  std::vector<std::array<std::uint32_t, 3>> triangles;
  if (rows < 2 || columns < 2) return triangles;
  triangles.reserve(2 * (rows - 1) * (columns - 1));
  for (std::size_t r = 0; r + 1 < rows; ++r) {
    for (std::size_t c = 0; c + 1 < columns; ++c) {
      const auto a = static_cast<std::uint32_t>(r * columns + c);
      const auto b = a + 1;
      const auto d = static_cast<std::uint32_t>(a + columns);
      triangles.push_back({a, b, d + 1});
      triangles.push_back({a, d + 1, d});
    }
  }
  return triangles;
}

}  // namespace springscan::analysis::testing
