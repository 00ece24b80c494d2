#include "analysis/cad/compensated_solid.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "analysis/cad/distance.hpp"
#include "analysis/cad/model.hpp"
#include "analysis/cad/segmentation.hpp"
#include "analysis/core/kdtree.hpp"
#include "simulators/parts/cad_profile.hpp"
#include "simulators/parts/produced_part.hpp"
#include "tests/analysis/cad_test_util.hpp"

namespace springscan::analysis {
using namespace springscan::parts;  // test parts (simulators/parts)
namespace {

using testing::TempDir;

ProfileSpec thick(ProfileSpec spec, double thickness_mm = 1.5) {
  spec.thickness_mm = thickness_mm;
  spec.width_mm = 40.0;
  return spec;
}

OffsetField rigid_field(const Transform& T) {
  return [T](const std::vector<Vec3>& points) {
    PointOffsets out;
    for (const Vec3& p : points) out.offset.push_back(T * p - p);
    out.covered.assign(points.size(), true);
    return out;
  };
}

Transform small_motion() {
  Transform T = Transform::Identity();
  T.linear() = Eigen::AngleAxisd(0.02, Vec3(0.3, 1.0, 0.2).normalized()).toRotationMatrix();
  T.translation() = Vec3(0.4, -0.25, 0.7);
  return T;
}

// The largest distance of the moved shape's tessellation vertices, moved back by T^-1, from the
// exact CAD surface.
double worst_vertex_error(const CadShape& cad, const CadShape& moved, const Transform& T) {
  const auto distance = make_cad_distance(cad);
  double worst = 0.0;
  for (const Vec3& v : moved.mesh().vertices)
    worst = std::max(worst, (distance->closest(T.inverse() * v).foot - T.inverse() * v).norm());
  return worst;
}

TEST(CompensatedShape, RigidMotionKeepsPlanesCylindersAndSegmentation) {
  const auto cad = make_profile_shape(thick(hat_profile(20, 30, 40, 80, 3)));
  ASSERT_TRUE(cad) << cad.message();
  const Transform T = small_motion();
  const auto out = compensated_shape(*cad, rigid_field(T));
  ASSERT_TRUE(out) << out.message();
  EXPECT_TRUE(out->valid);
  ASSERT_EQ(out->shape.face_count(), cad->face_count());
  for (const auto& f : out->faces) EXPECT_NE(f.surface, "bspline") << "face " << f.id;
  EXPECT_LT(out->max_deviation_mm, 1e-4);
  EXPECT_LT(worst_vertex_error(*cad, out->shape, T), 1e-4);
  EXPECT_EQ(out->shape.report().solids, 1);
  const auto before = segment_cad(*cad), after = segment_cad(out->shape);
  ASSERT_EQ(after.flanges.size(), before.flanges.size());
  ASSERT_EQ(after.bends.size(), before.bends.size());
  for (std::size_t b = 0; b < before.bends.size(); ++b) {
    EXPECT_NEAR(after.bends[b].nominal_angle_deg, before.bends[b].nominal_angle_deg, 1e-6);
    EXPECT_NEAR(after.bends[b].radius_mm, before.bends[b].radius_mm, 1e-6);
  }
}

// A smooth non-rigid field: a bulge along the sheet normal and a stretch. Faces become B-splines
// whose refit deviation is small; the shape stays a valid solid.
TEST(CompensatedShape, SmoothFieldGivesValidBSplineSolid) {
  const auto cad = make_profile_shape(thick(l_profile(50, 40, 90, 4)));
  ASSERT_TRUE(cad) << cad.message();
  const OffsetField bulge = [](const std::vector<Vec3>& points) {
    PointOffsets out;
    for (const Vec3& p : points)
      out.offset.push_back(
          Vec3(0.002 * p.x(), 0.0, 0.3 * std::sin(p.x() / 25.0) * std::cos(p.y() / 30.0)));
    out.covered.assign(points.size(), true);
    return out;
  };
  CompensatedShapeSettings settings;
  settings.canonical_tolerance_mm = 1e-3;  // the bulge is 0.3 mm: no face may stay a plane
  const auto out = compensated_shape(*cad, bulge, settings);
  ASSERT_TRUE(out) << out.message();
  EXPECT_TRUE(out->valid);
  EXPECT_EQ(out->shape.face_count(), cad->face_count());
  int bsplines = 0;
  for (const auto& f : out->faces) bsplines += f.surface == "bspline" ? 1 : 0;
  EXPECT_GT(bsplines, 0);
  EXPECT_LT(out->max_deviation_mm, 0.005);
  EXPECT_LE(out->p95_deviation_mm, out->max_deviation_mm);
  EXPECT_NEAR(out->max_offset_mm, 0.3, 0.12);
}

// A flange moved rigidly, measured with an error (a 0.15 mm waviness, more than
// canonical_tolerance_mm) the field knows about (its uncertainty): its faces stay planes, one
// normal per flange, and the die re-segments with every flange and bend. The same noise unannounced
// makes B-splines; a curl the field measures well (0.4 mm) is kept as a B-spline.
TEST(CompensatedShape, NoisyRigidFlangesStayPlanesARealCurlDoesNot) {
  const auto cad = make_profile_shape(thick(hat_profile(20, 30, 40, 80, 3)));
  ASSERT_TRUE(cad) << cad.message();
  const Transform T = small_motion();
  auto noisy = [T](double uncertainty_mm) {
    return [T, uncertainty_mm](const std::vector<Vec3>& points) {
      PointOffsets out;
      // Smooth, as the field's errors are (it is fitted over sigma, about 10 mm): a waviness.
      for (const Vec3& p : points) {
        const double noise = 0.15 * std::sin(p.x() / 7.0) * std::cos(p.y() / 9.0);
        out.offset.push_back(T * p - p + Vec3(0.0, 0.0, noise));
      }
      out.covered.assign(points.size(), true);
      out.uncertainty_mm.assign(points.size(), uncertainty_mm);
      return out;
    };
  };
  CompensatedShapeSettings coarse;  // three shapes: a coarser sampling keeps it fast (ASan)
  coarse.face_samples = 11;
  coarse.edge_samples = 21;
  coarse.bspline_tolerance_mm = 0.05;  // the undeclared waviness's B-splines stop at 8-16 spans
  const auto kept = compensated_shape(*cad, noisy(0.05), coarse);
  ASSERT_TRUE(kept) << kept.message();
  const PartSegmentation before = segment_cad(*cad), after = segment_cad(kept->shape);
  for (const Flange& flange : before.flanges)
    for (const int id : flange.face_ids) {
      EXPECT_EQ(kept->faces[static_cast<std::size_t>(id)].surface, "plane") << "face " << id;
      EXPECT_EQ(kept->faces[static_cast<std::size_t>(id)].flange, flange.id) << "face " << id;
    }
  EXPECT_EQ(after.flanges.size(), before.flanges.size());
  EXPECT_EQ(after.bends.size(), before.bends.size());
  const auto unannounced = compensated_shape(*cad, noisy(0.0), coarse);
  ASSERT_TRUE(unannounced) << unannounced.message();
  int bsplines = 0;
  for (const auto& f : unannounced->faces) bsplines += f.surface == "bspline" ? 1 : 0;
  EXPECT_GT(bsplines, 0);
  // A curl along x, known to 0.02 mm: a flat flange h mm either side of its middle lies up to
  // 2/3 x 0.01 h^2 from its best plane (h >= 10 mm here: 0.67 mm), far beyond its allowance.
  const OffsetField curl = [](const std::vector<Vec3>& points) {
    PointOffsets out;
    for (const Vec3& p : points) out.offset.push_back(Vec3(0.0, 0.0, 0.01 * p.x() * p.x()));
    out.covered.assign(points.size(), true);
    out.uncertainty_mm.assign(points.size(), 0.02);
    return out;
  };
  const auto curled = compensated_shape(*cad, curl, coarse);
  ASSERT_TRUE(curled) << curled.message();
  int flat = 0;
  for (const Flange& flange : before.flanges) {
    if (std::abs(flange.normal.z()) < 0.9) continue;  // the walls: mostly moved in their plane
    ++flat;
    for (const int id : flange.face_ids)
      EXPECT_EQ(curled->faces[static_cast<std::size_t>(id)].surface, "bspline") << "face " << id;
  }
  EXPECT_EQ(flat, 3);
}

TEST(CompensatedShape, FaceTheFieldDoesNotCoverIsNamed) {
  const auto cad = make_profile_shape(thick(l_profile(50, 40, 90, 4)));
  ASSERT_TRUE(cad) << cad.message();
  // Covers only the first leg (x < 30): the other leg's faces have no vector nearby.
  const OffsetField partial = [](const std::vector<Vec3>& points) {
    PointOffsets out;
    for (const Vec3& p : points) {
      out.offset.push_back(Vec3(0, 0, 0.1));
      out.covered.push_back(p.x() < 30.0);
    }
    return out;
  };
  const auto out = compensated_shape(*cad, partial);
  ASSERT_FALSE(out);
  EXPECT_TRUE(out.error().is_invalid_input());
  EXPECT_NE(out.message().find("does not cover face"), std::string::npos) << out.message();
}

TEST(CompensatedShape, EmptyInputsAreRefused) {
  EXPECT_FALSE(compensated_shape(CadShape{}, rigid_field(Transform::Identity())));
  const auto cad = make_profile_shape(l_profile(30, 30, 90, 3));
  ASSERT_TRUE(cad);
  EXPECT_FALSE(compensated_shape(*cad, OffsetField{}));
  const OffsetField none = [](const std::vector<Vec3>& points) {
    return PointOffsets{std::vector<Vec3>(points.size(), Vec3::Zero()),
                        std::vector<bool>(points.size(), false),
                        {}};
  };
  EXPECT_FALSE(compensated_shape(*cad, none));
}

// The over-bend a springback compensation asks for: minus the produced part's motion (the
// simulator's springback per bend). The compensated CAD re-imports from STEP with the same
// faces, flanges and bends, each bend closed by about its springback.
TEST(CompensatedShape, OverBendReimportsFromStepWithSameFlangesAndBends) {
  const TempDir dir;
  const ProfileSpec spec = thick(hat_profile(20, 30, 40, 80, 3));
  ASSERT_TRUE(write_profile_cad(spec, dir.file("hat.step")));
  const auto part = load_cad_part(dir.file("hat.step"));
  ASSERT_TRUE(part) << part.message();
  const std::size_t bends = part->model.segmentation.bends.size();
  ASSERT_EQ(bends, 4u);
  const std::vector<double> springback{2.0, -1.5, 1.0, 2.5};
  const auto produced = make_produced_part(part->model, part->shape, springback);
  ASSERT_TRUE(produced) << produced.message();
  const KdTree samples(part->model.samples.points);
  const OffsetField over_bend = [&](const std::vector<Vec3>& points) {
    PointOffsets out;
    for (const Vec3& p : points) {
      const int face = part->model.samples.face_ids[samples.nearest(p)->index];
      out.offset.push_back(-(produced->produced(p, face) - p));
    }
    out.covered.assign(points.size(), true);
    return out;
  };
  const auto out = compensated_shape(part->shape, over_bend);
  ASSERT_TRUE(out) << out.message();
  EXPECT_TRUE(out->valid);
  EXPECT_LT(out->max_deviation_mm, 0.01);
  ASSERT_TRUE(write_step_atomically(out->shape, dir.file("die.step")));
  const auto die = load_part_model(dir.file("die.step"));
  ASSERT_TRUE(die) << die.message();
  EXPECT_EQ(die->face_count, part->model.face_count);
  ASSERT_EQ(die->segmentation.flanges.size(), part->model.segmentation.flanges.size());
  ASSERT_EQ(die->segmentation.bends.size(), bends);
  for (std::size_t b = 0; b < bends; ++b) {
    const double nominal = part->model.segmentation.bends[b].nominal_angle_deg;
    const double truth = produced->bends[b].springback_deg;
    EXPECT_NEAR(die->segmentation.bends[b].nominal_angle_deg, nominal + truth, 0.02)
        << "bend " << b;
  }
}

TEST(CompensatedShape, StepWriteIsAtomic) {
  const TempDir dir;
  const auto cad = make_profile_shape(l_profile(30, 30, 90, 3));
  ASSERT_TRUE(cad);
  const std::string path = dir.file("out.step");
  { std::ofstream(path) << "old"; }
  // A folder that does not exist: nothing written, nothing left behind.
  EXPECT_FALSE(write_step_atomically(*cad, dir.file("missing/out.step")));
  ASSERT_TRUE(write_step_atomically(*cad, path));
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.file(""))) files += e.exists();
  EXPECT_EQ(files, 1u);  // no scratch file stays
  std::ifstream in(path);
  std::string first;
  std::getline(in, first);
  EXPECT_EQ(first.rfind("ISO-10303-21", 0), 0u);
}

}  // namespace
}  // namespace springscan::analysis
