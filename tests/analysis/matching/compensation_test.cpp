// Compensation vectors: c = -alpha * d with d interpolated from the field, clipped, written out.
#include "analysis/matching/compensation.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace springscan::analysis {
namespace {

// A field on a 2 mm grid in the z = 0 plane (x, y in [0, 40]) with displacement d(p).
template <class F>
DeformationField grid_field(F d) {
  DeformationField field;
  std::uint32_t k = 0;
  for (int x = 0; x <= 20; ++x) {
    for (int y = 0; y <= 20; ++y) {
      DeformationVector v;
      v.model_index = v.scan_index = k++;
      v.model = Vec3(2.0 * x, 2.0 * y, 0.0);
      v.scan = v.model + d(v.model);
      v.squared_distance_mm2 = (v.scan - v.model).squaredNorm();
      field.vectors.push_back(v);
    }
  }
  field.model_points = field.scan_points = k;
  return field;
}

TEST(Compensation, ConstantFieldIsMirroredAndScaled) {
  const Vec3 d(0.3, 0.0, -0.2);
  const auto field = grid_field([&](const Vec3&) { return d; });
  const std::vector<Vec3> control{Vec3(10, 10, 0), Vec3(3.3, 7.1, 0.5), Vec3(0, 0, 0)};
  for (const double alpha : {1.0, 0.5}) {
    const auto c = compensation(field, control, {.scale = alpha});
    ASSERT_TRUE(c.ok()) << c.message();
    EXPECT_NEAR(c->smoothing_radius_mm, 2.0, 1e-12);  // the grid spacing
    for (const auto& v : c->vectors) {
      EXPECT_TRUE(v.supported);
      EXPECT_NEAR((v.vector + alpha * d).norm(), 0.0, 1e-12);
    }
  }
}

TEST(Compensation, LinearFieldIsReproducedInTheInterior) {
  // A symmetric Gaussian window on a regular grid reproduces a linear field away from borders.
  const auto field =
      grid_field([](const Vec3& p) { return Vec3(0.01 * p.y(), 0.0, 0.02 * p.x()); });
  const auto c = compensation(field, {Vec3(20, 20, 0), Vec3(14, 26, 0)}, {.scale = 1.0});
  ASSERT_TRUE(c.ok());
  for (const auto& v : c->vectors) {
    const Vec3 expected = -Vec3(0.01 * v.point.y(), 0.0, 0.02 * v.point.x());
    EXPECT_NEAR((v.vector - expected).norm(), 0.0, 1e-9);
  }
}

TEST(Compensation, MagnitudeLimitKeepsDirection) {
  const Vec3 d(6.0, 8.0, 0.0);  // 10 mm
  const auto field = grid_field([&](const Vec3&) { return d; });
  const auto c = compensation(field, {Vec3(10, 10, 0)}, {.scale = 1.0, .max_magnitude_mm = 5.0});
  ASSERT_TRUE(c.ok());
  ASSERT_EQ(c->vectors.size(), 1u);
  EXPECT_TRUE(c->vectors[0].clipped);
  EXPECT_EQ(c->clipped, 1u);
  EXPECT_NEAR(c->vectors[0].vector.norm(), 5.0, 1e-12);
  EXPECT_NEAR((c->vectors[0].vector - Vec3(-3.0, -4.0, 0.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(c->max_magnitude_mm, 5.0, 1e-12);
}

TEST(Compensation, FarControlPointsAreUnsupported) {
  const auto field = grid_field([](const Vec3&) { return Vec3(0.1, 0, 0); });
  const auto c = compensation(field, {Vec3(10, 10, 0), Vec3(100, 100, 0)});
  ASSERT_TRUE(c.ok());
  EXPECT_TRUE(c->vectors[0].supported);
  EXPECT_FALSE(c->vectors[1].supported);
  EXPECT_EQ(c->vectors[1].vector, Vec3::Zero());
  EXPECT_EQ(c->unsupported, 1u);
}

TEST(Compensation, EmptyFieldAndBadSettings) {
  const auto c = compensation(DeformationField{}, {Vec3::Zero()});
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->unsupported, 1u);
  EXPECT_FALSE(compensation(DeformationField{}, {}, {.max_magnitude_mm = 0.0}).ok());
  const auto bad = compensation(DeformationField{}, {}, {.smoothing_radius_mm = -1.0});
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("smoothing_radius_mm"), std::string::npos);
}

TEST(Compensation, WritesCsvAndPly) {
  const auto field = grid_field([](const Vec3&) { return Vec3(0.0, 0.0, 0.5); });
  const auto c = compensation(field, {Vec3(10, 10, 0), Vec3(12, 10, 0), Vec3(99, 99, 0)});
  ASSERT_TRUE(c.ok());
  const auto dir = std::filesystem::temp_directory_path() /
                   ("springscan_compensation_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string csv = (dir / "comp.csv").string(), ply = (dir / "comp.ply").string();
  ASSERT_TRUE(write_compensation_csv(csv, *c).ok());
  ASSERT_TRUE(write_compensation_ply(ply, *c).ok());

  std::ifstream in_csv(csv);
  std::string line;
  std::getline(in_csv, line);
  EXPECT_EQ(line, "x_mm,y_mm,z_mm,cx_mm,cy_mm,cz_mm,magnitude_mm,supported,clipped");
  std::getline(in_csv, line);
  EXPECT_EQ(line, "10.000000,10.000000,0.000000,0.000000,0.000000,-0.500000,0.500000,1,0");
  int rows = 1;
  while (std::getline(in_csv, line)) ++rows;
  EXPECT_EQ(rows, 3);

  std::ifstream in_ply(ply);
  std::string text((std::istreambuf_iterator<char>(in_ply)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("element vertex 3\n"), std::string::npos);
  EXPECT_NE(text.find("end_header\n10.000000 10.000000 0.000000 0.000000 0.000000 -1.000000"),
            std::string::npos);
  EXPECT_FALSE(write_compensation_csv((dir / "missing" / "x.csv").string(), *c).ok());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace springscan::analysis
