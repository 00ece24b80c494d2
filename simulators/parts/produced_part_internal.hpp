#pragma once
// The lookup data behind ProducedPart (produced_part.cpp) and the walk that fills it
// (produced_walk.cpp). Not part of the simulators' interface.

#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "analysis/core/kdtree.hpp"
#include "simulators/parts/produced_part.hpp"

namespace springscan::parts {

// One bend as the walk placed it, in the CAD frame of its parent flange.
struct BendFrame {
  Vec3 c = Vec3::Zero();        // on the CAD axis
  Vec3 d = Vec3::UnitX();       // axis, oriented so that e0 turns into e1 by +span
  Vec3 e0 = Vec3::UnitY();      // from the axis towards the parent flange's sheet (phi = 0)
  Vec3 e0_perp = Vec3::Zero();  // d x e0 (phi = 90 degrees)
  double span_rad = 0.0;        // Phi: the angle the sheet turns in the CAD part
  double springback_rad = 0.0;  // applied (0 for hems and closing bends)
  double r_in = 0.0, r_out = 0.0, axial_min = 0.0, axial_max = 0.0;
  Transform T_parent = Transform::Identity();
};

enum class FaceKind { kFlange, kBend, kOther };

struct ProducedPartData {
  std::vector<FaceKind> face_kind;
  std::vector<int> face_index;  // Flange::id or Bend::id of the face, -1 for other faces
  std::vector<BendFrame> frames;
  std::vector<Transform> flange_T;
  std::vector<std::vector<int>> flange_bends;              // bends touching each flange
  std::vector<std::vector<int>> face_candidates;           // other faces: regions they touch
  std::vector<int> sample_region;                          // per KD-tree point: region code
  std::vector<std::vector<std::uint32_t>> region_samples;  // KD-tree points of each region
  std::unique_ptr<KdTree> tree;                            // flange and bend samples
  int flange_count = 0;
  double wedge_tolerance_mm = 0.05;
};

namespace detail {

inline Transform rotation_about(const Vec3& c, const Vec3& d, double angle_rad) {
  Transform T = Transform::Identity();
  T.linear() = Eigen::AngleAxisd(angle_rad, d).toRotationMatrix();
  T.translation() = c - T.linear() * c;
  return T;
}

// From the axis towards the sheet of `flange` (its mid-plane), perpendicular to the axis: the
// material as seen from the axis, which decides the sense of the bend whatever the normals say.
inline Vec3 towards_sheet(const Flange& flange, const Vec3& c, const Vec3& d) {
  const Vec3 mid = flange.point - 0.5 * flange.thickness_mm * flange.normal;
  Vec3 e = flange.normal * ((mid - c).dot(flange.normal) >= 0.0 ? 1.0 : -1.0);
  e -= e.dot(d) * d;
  return e.normalized();
}

/// Fills data.face_kind, face_index, flange_count and flange_bends from the segmentation.
void classify_faces(const PartModel& model, const CadShape& shape, ProducedPartData& data);

/// The breadth-first walk from part.report.root_flange: data.flange_T and data.frames, and
/// part.bends and the report's hems, closing bends, rigid flanges and warnings.
void walk(const PartModel& model, const CadShape& shape, const std::vector<CadFaceInfo>& faces,
          const std::vector<double>& springback_deg, const ProducedPartSettings& settings,
          ProducedPartData& data, ProducedPart& part);

}  // namespace detail
}  // namespace springscan::parts
