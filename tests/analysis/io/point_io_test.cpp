// Round trips through every format and encoding, and files written by Open3D (tests/data).
#include "analysis/io/point_io.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "tests/support/test_paths.hpp"

namespace springscan::analysis {
namespace {

const std::string kData = springscan::test_paths::source("tests/data");

// A cloud with every attribute, and a few triangles over its points; fixed seed.
Surface random_surface(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-500.0, 500.0);
  std::uniform_int_distribution<int> byte(0, 255);
  Surface s;
  for (std::size_t i = 0; i < n; ++i) {
    s.cloud.points.emplace_back(u(rng), u(rng), u(rng));
    s.cloud.normals.push_back(Vec3(u(rng), u(rng), u(rng)).normalized());
    s.cloud.colors.push_back(Rgb{static_cast<std::uint8_t>(byte(rng)),
                                 static_cast<std::uint8_t>(byte(rng)),
                                 static_cast<std::uint8_t>(byte(rng))});
    s.cloud.scalars.push_back(u(rng) / 100.0);
    s.cloud.face_ids.push_back(static_cast<std::int32_t>(i % 7) - 1);
  }
  for (std::uint32_t i = 0; i + 2 < n; i += 3) s.triangles.push_back({i, i + 2, i + 1});
  return s;
}

void expect_same(const Surface& a, const Surface& b, double tolerance) {
  ASSERT_EQ(a.cloud.size(), b.cloud.size());
  for (std::size_t i = 0; i < a.cloud.size(); ++i) {
    EXPECT_NEAR((a.cloud.points[i] - b.cloud.points[i]).norm(), 0.0, tolerance * 500) << i;
  }
  ASSERT_EQ(a.cloud.normals.size(), b.cloud.normals.size());
  for (std::size_t i = 0; i < a.cloud.normals.size(); ++i) {
    EXPECT_NEAR((a.cloud.normals[i] - b.cloud.normals[i]).norm(), 0.0, tolerance) << i;
  }
  ASSERT_EQ(a.cloud.scalars.size(), b.cloud.scalars.size());
  for (std::size_t i = 0; i < a.cloud.scalars.size(); ++i) {
    EXPECT_NEAR(a.cloud.scalars[i], b.cloud.scalars[i], tolerance * 5) << i;
  }
  EXPECT_EQ(a.cloud.colors, b.cloud.colors);
  EXPECT_EQ(a.cloud.face_ids, b.cloud.face_ids);
  EXPECT_EQ(a.triangles, b.triangles);
}

struct PlyCase {
  PlyEncoding encoding;
  bool single_precision;
};

std::string ply_case_name(const ::testing::TestParamInfo<PlyCase>& param_info) {
  static const char* const kNames[] = {"BinaryLittleEndian", "Ascii", "BinaryBigEndian"};
  return std::string(kNames[static_cast<int>(param_info.param.encoding)]) +
         (param_info.param.single_precision ? "Float" : "Double");
}

class PlyRoundTrip : public ::testing::TestWithParam<PlyCase> {};

TEST_P(PlyRoundTrip, KeepsEveryAttribute) {
  const Surface original = random_surface(300, 7);
  PointWriteOptions options;
  options.ply_encoding = GetParam().encoding;
  options.single_precision = GetParam().single_precision;
  auto bytes = format_ply(original, options);
  ASSERT_TRUE(bytes) << bytes.message();
  auto back = parse_ply(*bytes, "mem.ply");
  ASSERT_TRUE(back) << back.message();
  // Doubles come back bit-exact (ascii prints the shortest exact form); floats to 2^-24.
  expect_same(original, *back, GetParam().single_precision ? 1e-6 : 0.0);
}

INSTANTIATE_TEST_SUITE_P(Encodings, PlyRoundTrip,
                         ::testing::Values(PlyCase{PlyEncoding::kBinaryLittleEndian, false},
                                           PlyCase{PlyEncoding::kBinaryBigEndian, false},
                                           PlyCase{PlyEncoding::kAscii, false},
                                           PlyCase{PlyEncoding::kBinaryLittleEndian, true},
                                           PlyCase{PlyEncoding::kBinaryBigEndian, true},
                                           PlyCase{PlyEncoding::kAscii, true}),
                         ply_case_name);

TEST(PlyRoundTrip, EmptyCloudAndCustomScalarName) {
  auto empty = format_ply(Surface{});
  ASSERT_TRUE(empty);
  auto back = parse_ply(*empty, "empty.ply");
  ASSERT_TRUE(back) << back.message();
  EXPECT_TRUE(back->cloud.empty());

  Surface s = random_surface(4, 3);
  PointWriteOptions options;
  options.scalar_name = "signed_deviation_mm";
  auto bytes = format_ply(s, options);
  ASSERT_TRUE(bytes);
  EXPECT_NE(bytes->find("property double signed_deviation_mm\n"), std::string::npos);
  auto read = parse_ply(*bytes, "mem.ply");
  ASSERT_TRUE(read) << read.message();
  EXPECT_EQ(read->cloud.scalars, s.cloud.scalars);
}

TEST(XyzRoundTrip, AllColumnLayoutsAreExact) {
  const Surface full = random_surface(50, 11);
  for (int layout = 0; layout < 4; ++layout) {
    Surface s;
    s.cloud.points = full.cloud.points;
    if (layout & 1) s.cloud.normals = full.cloud.normals;
    if (layout & 2) s.cloud.scalars = full.cloud.scalars;
    auto text = format_xyz(s);
    ASSERT_TRUE(text);
    auto back = parse_xyz(*text, "mem.xyz");
    ASSERT_TRUE(back) << back.message();
    expect_same(s, *back, 0.0);
  }
}

TEST(StlRoundTrip, BinaryKeepsTrianglesAndWeldsCorners) {
  // Vertices on a float grid so that the float32 STL coordinates are exact.
  Surface s;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) s.cloud.points.emplace_back(i * 2.5, j * 0.25, i * j * 0.125);
  }
  for (std::uint32_t i = 0; i < 4; ++i) {
    for (std::uint32_t j = 0; j < 4; ++j) {
      const std::uint32_t a = i * 5 + j;
      s.triangles.push_back({a, a + 5, a + 1});
      s.triangles.push_back({a + 1, a + 5, a + 6});
    }
  }
  auto bytes = format_stl(s);
  ASSERT_TRUE(bytes);
  EXPECT_EQ(bytes->size(), 84u + 50u * s.triangles.size());
  auto back = parse_stl(*bytes, "mem.stl");
  ASSERT_TRUE(back) << back.message();
  // Order of first appearance in the triangles renumbers the vertices; compare by position.
  ASSERT_EQ(back->cloud.size(), s.cloud.size());
  ASSERT_EQ(back->triangles.size(), s.triangles.size());
  for (std::size_t t = 0; t < s.triangles.size(); ++t) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(back->cloud.points[back->triangles[t][c]], s.cloud.points[s.triangles[t][c]]);
    }
  }
}

TEST(StlRoundTrip, HeaderStartingWithSolidIsStillBinary) {
  Surface s;
  s.cloud.points = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  s.triangles = {{0, 1, 2}};
  auto bytes = format_stl(s);
  ASSERT_TRUE(bytes);
  std::string data = *bytes;
  data.replace(0, 5, "solid");  // as SolidWorks and others write binary headers
  auto back = parse_stl(data, "solid_header.stl");
  ASSERT_TRUE(back) << back.message();
  EXPECT_EQ(back->triangles.size(), 1u);
  EXPECT_EQ(back->cloud.points[1], Vec3(1, 0, 0));
}

TEST(Open3dFiles, BinaryAndAsciiCloudsMatchTheGeneratingFormula) {
  for (const char* file : {"open3d_cloud_binary.ply", "open3d_cloud_ascii.ply"}) {
    SCOPED_TRACE(file);
    auto cloud = read_point_cloud(kData + "/" + file);
    ASSERT_TRUE(cloud) << cloud.message();
    ASSERT_EQ(cloud->size(), 10u);
    ASSERT_TRUE(cloud->has_normals());
    ASSERT_TRUE(cloud->has_colors());
    for (std::size_t i = 0; i < 10; ++i) {
      const double d = static_cast<double>(i);
      EXPECT_NEAR((cloud->points[i] - Vec3(d, 2 * d, -0.5 * d)).norm(), 0.0, 1e-12);
      EXPECT_NEAR((cloud->normals[i] - Vec3(1, d, 0).normalized()).norm(), 0.0, 1e-6);
      EXPECT_NEAR(cloud->colors[i][0], d / 9 * 255, 1.0);
      EXPECT_NEAR(cloud->colors[i][1], 127.5, 1.0);
      EXPECT_NEAR(cloud->colors[i][2], (1 - d / 9) * 255, 1.0);
    }
  }
}

TEST(Open3dFiles, CubeIsTheSameInPlyBinaryStlAndAsciiStl) {
  auto ply = read_mesh(kData + "/open3d_cube.ply");
  auto binary = read_mesh(kData + "/open3d_cube_binary.stl");
  auto ascii = read_mesh(kData + "/cube_ascii.stl");
  ASSERT_TRUE(ply) << ply.message();
  ASSERT_TRUE(binary) << binary.message();
  ASSERT_TRUE(ascii) << ascii.message();
  for (const TriangleMesh* mesh : {&*ply, &*binary, &*ascii}) {
    ASSERT_EQ(mesh->vertices.size(), 8u);
    ASSERT_EQ(mesh->triangles.size(), 12u);
    double area = 0.0;
    for (const auto& t : mesh->triangles) {
      const Vec3& a = mesh->vertices[t[0]];
      area += 0.5 * (mesh->vertices[t[1]] - a).cross(mesh->vertices[t[2]] - a).norm();
      for (auto i : t) EXPECT_TRUE(mesh->vertices[i].cwiseAbs().maxCoeff() <= 10.0);
    }
    EXPECT_NEAR(area, 600.0, 1e-9);  // a 10 mm cube
  }
  // The same triangles, corner by corner, in all three files.
  for (std::size_t t = 0; t < 12; ++t) {
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(binary->vertices[binary->triangles[t][c]], ply->vertices[ply->triangles[t][c]]);
      EXPECT_EQ(ascii->vertices[ascii->triangles[t][c]], ply->vertices[ply->triangles[t][c]]);
    }
  }
  auto points = read_point_cloud(kData + "/open3d_cube_binary.stl");
  ASSERT_TRUE(points);
  EXPECT_EQ(points->size(), 8u);
}

TEST(PointFiles, WriteThenReadEveryExtension) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / "springscan_point_files";
  std::filesystem::create_directories(dir);
  const Surface s = random_surface(30, 5);
  for (const char* name : {"a.ply", "B.PLY", "c.xyz", "d.csv", "e.txt", "f.pts"}) {
    SCOPED_TRACE(name);
    const std::string path = (dir / name).string();
    auto written = write_point_cloud(path, s.cloud);
    ASSERT_TRUE(written) << written.message();
    auto back = read_point_cloud(path);
    ASSERT_TRUE(back) << back.message();
    EXPECT_EQ(back->points, s.cloud.points);
    EXPECT_EQ(back->normals, s.cloud.normals);
    EXPECT_EQ(back->scalars, s.cloud.scalars);
  }
  const std::string stl = (dir / "g.stl").string();
  EXPECT_FALSE(write_point_cloud(stl, s.cloud));  // STL needs triangles
  ASSERT_TRUE(write_surface(stl, s));
  auto mesh = read_mesh(stl);
  ASSERT_TRUE(mesh) << mesh.message();
  EXPECT_EQ(mesh->triangles.size(), s.triangles.size());
  EXPECT_FALSE(read_point_cloud((dir / "h.obj").string()));
  auto missing = read_point_cloud((dir / "missing.ply").string());
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.message().find("missing.ply"), std::string::npos);
  EXPECT_TRUE(missing.error().is_not_found()) << missing.error().to_string();
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace springscan::analysis
