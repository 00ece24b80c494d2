#pragma once
// Even, area-weighted samples of the CAD faces (paper section 2: "extract the shape points from
// the given CAD model ... by scanning the individual surfaces evenly"), each with its face id
// and the exact surface normal.

#include <cstdint>

#include "analysis/cad/import.hpp"
#include "analysis/core/point_cloud.hpp"

namespace springscan::analysis {

struct CadSamplingSettings {
  int sample_count = 20000;  ///< total samples over all faces (>= 0)
  std::uint32_t seed = 1;    ///< fixed seed: the same shape gives the same samples
};

/// Samples every tessellated face: face f gets round(sample_count * area_f / area_total) samples
/// (largest-remainder rounding, areas from its triangles), placed uniformly at random on its
/// triangles by area, so trimming and holes are respected. Each point is the surface evaluated at
/// the sample's interpolated (u, v), hence exactly on the surface; its normal is the surface
/// normal there (BRepLProp_SLProps), reversed on REVERSED faces, i.e. pointing out of a solid.
/// Output: points, normals, face_ids (0-based, CadShape order). Errors: empty shape, negative
/// count. Deterministic for a given seed; the shape is only read.
Expected<PointCloud> sample_cad(const CadShape& shape, const CadSamplingSettings& settings = {});

}  // namespace springscan::analysis
