// The calibration artefact (simulators/parts/artefact.hpp): a closed solid of planes only, with
// the inclined faces docs/calibration.md lists, the same through its STEP file.
#include "simulators/parts/artefact.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "analysis/cad/segmentation.hpp"

namespace springscan::parts {
namespace {

bool has_normal(const std::vector<analysis::CadFaceInfo>& faces, const analysis::Vec3& n) {
  for (const auto& f : faces)
    if (f.direction.dot(n.normalized()) > 1.0 - 1e-9) return true;
  return false;
}

TEST(Artefact, ClosedSolidOfPlanesWithTheInclinedFaces) {
  auto shape = make_artefact_shape();
  ASSERT_TRUE(shape.ok()) << shape.message();
  const auto& report = shape->report();
  EXPECT_EQ(report.solids, 1);
  EXPECT_EQ(report.free_edges, 0);
  EXPECT_NEAR(report.bbox_min.norm(), 0.0, 1e-6);
  EXPECT_TRUE(report.bbox_max.isApprox(analysis::Vec3(160, 100, 55), 1e-6));
  const auto faces = analysis::describe_faces(*shape);
  for (const auto& f : faces) EXPECT_EQ(f.type, "plane") << "face " << f.id;
  for (const analysis::Vec3& n :
       {analysis::Vec3(1, 0, 1), analysis::Vec3(0, -1, 1), analysis::Vec3(-1, 1, 1.2),
        analysis::Vec3(-1, 0, 2), analysis::Vec3(0, 0, 1), analysis::Vec3(0, 0, -1)})
    EXPECT_TRUE(has_normal(faces, n)) << n.transpose();
}

TEST(Artefact, StepFileHasTheSameFaces) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("springscan_artefact_test_" + std::to_string(::getpid()) + ".step");
  ASSERT_TRUE(write_artefact_step(path.string()).ok());
  auto loaded = analysis::load_cad(path.string());
  std::filesystem::remove(path);
  ASSERT_TRUE(loaded.ok()) << loaded.message();
  EXPECT_EQ(loaded->face_count(), make_artefact_shape()->face_count());
  EXPECT_EQ(loaded->report().free_edges, 0);
}

TEST(Artefact, RefusesInconsistentSizes) {
  ArtefactSpec spec;
  spec.chamfer_mm = 40.0;  // deeper than the 30 mm base
  EXPECT_FALSE(make_artefact_shape(spec).ok());
  spec = ArtefactSpec{};
  spec.length_mm = 0.0;
  EXPECT_FALSE(make_artefact_shape(spec).ok());
}

}  // namespace
}  // namespace springscan::parts
