#pragma once
// PRIVATE to analysis/cad_segmentation*.cpp: the two halves of segment_cad.

#include <vector>

#include "analysis/cad/segmentation.hpp"

namespace springscan::analysis {

struct FlangeTable {
  std::vector<Flange> flanges;
  std::vector<int> flange_of_face;  ///< -1 for faces in no flange
};

FlangeTable find_flanges(const CadShape& shape, const std::vector<CadFaceInfo>& infos, bool solid,
                         const CadSegmentationSettings& settings);

std::vector<Bend> find_bends(const CadShape& shape, const std::vector<CadFaceInfo>& infos,
                             const FlangeTable& flanges, bool solid,
                             const CadSegmentationSettings& settings);

/// The angle the sheet turns at `bend` (degrees).
double bend_angle_deg(const CadShape& shape, const std::vector<CadFaceInfo>& infos,
                      const FlangeTable& flanges, const Bend& bend);

/// True when p, projected on the (planar or cylindrical) surface of face_id, lands in the face.
bool point_projects_into(const CadShape& shape, int face_id, const Vec3& p);

/// The u-span of a cylindrical face in degrees: the angle its arc sweeps.
double cylinder_sweep_deg(const CadShape& shape, int face_id);

}  // namespace springscan::analysis
