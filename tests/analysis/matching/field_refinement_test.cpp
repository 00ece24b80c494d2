// Coverage of the refined field on a solid sheet (docs/matching.md "Refined field", step 4): a
// scanner sees one skin, so a control point on the other skin has no vector, whether the scan
// lies one thickness behind it (the frame is right) or on it but seen from inside the material
// (the frame has the scan on the model's other side). A plate, its control points on both
// skins, a noise-free scan of one skin; the prediction is the identity (a raw field of zero
// vectors, no springback), so only the coverage rule decides.
#include "analysis/matching/field_refinement.hpp"

#include <gtest/gtest.h>

namespace springscan::analysis {
namespace {

constexpr double kHalf = 15.0;  // control points in [-15, 15]^2, the scan over [-20, 20]^2

struct Plate {
  std::vector<Vec3> points, normals;
  std::vector<int> faces;  // 0: top skin (normal +z), 1: bottom skin (normal -z)
  PartSegmentation segmentation;
};

// thickness 0: a surface model, the top skin only.
Plate plate(double thickness) {
  Plate p;
  for (double x = -kHalf; x <= kHalf; x += 5.0)
    for (double y = -kHalf; y <= kHalf; y += 5.0) {
      p.points.emplace_back(x, y, 0.5 * thickness);
      p.normals.push_back(Vec3::UnitZ());
      p.faces.push_back(0);
      if (thickness == 0.0) continue;
      p.points.emplace_back(x, y, -0.5 * thickness);
      p.normals.push_back(-Vec3::UnitZ());
      p.faces.push_back(1);
    }
  Flange f;
  f.face_ids = thickness > 0.0 ? std::vector<int>{0, 1} : std::vector<int>{0};
  f.point = Vec3(0.0, 0.0, 0.5 * thickness);
  f.thickness_mm = thickness;
  p.segmentation.flanges.push_back(f);
  return p;
}

// A scan of one side at height z, 0.25 mm apart, every normal `normal` (toward the scanner).
PointCloud scan_at(double z, const Vec3& normal) {
  PointCloud c;
  for (double x = -20.0; x <= 20.0; x += 0.25)
    for (double y = -20.0; y <= 20.0; y += 0.25) {
      c.points.emplace_back(x, y, z);
      c.normals.push_back(normal);
    }
  return c;
}

struct Covered {
  int top = 0, bottom = 0;
  std::size_t far_side = 0;
  double max_offset_mm = 0.0;  // of the vectors
};

Covered refine(const Plate& p, const PointCloud& scan, bool with_normals) {
  DeformationField raw;
  raw.model_points = p.points.size();
  for (std::size_t i = 0; i < p.points.size(); ++i) {
    DeformationVector v;
    v.model_index = static_cast<std::uint32_t>(i);
    v.scan_index = static_cast<std::uint32_t>(i);
    v.model = v.scan = p.points[i];
    raw.vectors.push_back(v);
  }
  const FieldRefinementInput input{
      p.points, p.normals,   p.faces,  p.segmentation,
      nullptr,  scan.points, p.points, with_normals ? &scan.normals : nullptr};
  const DeformationField field = refine_field(raw, input);
  Covered out;
  for (const DeformationVector& v : field.vectors) {
    (p.faces[v.model_index] == 0 ? out.top : out.bottom) += 1;
    out.max_offset_mm = std::max(out.max_offset_mm, v.displacement().norm());
  }
  out.far_side = field.seen_from_far_side;
  EXPECT_EQ(field.uncovered.size(), p.points.size() - field.vectors.size());
  return out;
}

TEST(FieldCoverage, TheFarSkinOfASolidIsNotCovered) {
  const Plate p = plate(2.0);
  const int per_skin = static_cast<int>(p.points.size() / 2);
  for (const bool normals : {true, false}) {
    const Covered c = refine(p, scan_at(1.0, Vec3::UnitZ()), normals);
    EXPECT_EQ(c.top, per_skin) << normals;
    EXPECT_EQ(c.bottom, 0) << normals;
    EXPECT_EQ(c.far_side, 0u) << normals;  // the scan is one thickness away: no candidates
    EXPECT_LT(c.max_offset_mm, 1e-9) << normals;
  }
}

// The top skin's scan carried onto the bottom skin (a result frame one thickness off): by
// position it fits the bottom skin exactly; its normals say it was seen from inside the sheet.
TEST(FieldCoverage, AScanSeenFromInsideTheMaterialCoversNothing) {
  const Plate p = plate(2.0);
  const int per_skin = static_cast<int>(p.points.size() / 2);
  const Covered c = refine(p, scan_at(-1.0, Vec3::UnitZ()), true);
  EXPECT_EQ(c.top, 0);
  EXPECT_EQ(c.bottom, 0);
  EXPECT_EQ(c.far_side, static_cast<std::size_t>(per_skin));
  // Without normals position alone cannot tell which side the scanner was on.
  EXPECT_EQ(refine(p, scan_at(-1.0, Vec3::UnitZ()), false).bottom, per_skin);
}

// A sheet thinner than twice the normal window (0.4 mm < 2 x 0.5 mm): the window shrinks to
// half the thickness, so the far skin stays out of it even without normals.
TEST(FieldCoverage, OnAThinSheetTheWindowStaysWithinHalfTheThickness) {
  const Plate p = plate(0.4);
  const int per_skin = static_cast<int>(p.points.size() / 2);
  const Covered c = refine(p, scan_at(0.2, Vec3::UnitZ()), false);
  EXPECT_EQ(c.top, per_skin);
  EXPECT_EQ(c.bottom, 0);
}

// A surface model has no inside: the scanner may see it from either side.
TEST(FieldCoverage, ASurfaceModelIsCoveredFromEitherSide) {
  const Plate p = plate(0.0);
  EXPECT_EQ(refine(p, scan_at(0.0, -Vec3::UnitZ()), true).top, static_cast<int>(p.points.size()));
}

}  // namespace
}  // namespace springscan::analysis
