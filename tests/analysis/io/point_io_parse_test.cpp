// The in-memory parsers on hand-written inputs: every PLY type and alias, skipped properties and
// elements, faces, colours, scalars; XYZ separators, comments and headers.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstring>

#include "analysis/io/point_io.hpp"

namespace springscan::analysis {
namespace {

// Appends a value in big-endian byte order.
template <typename T>
void put_be(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::little) std::reverse(bytes, bytes + sizeof(T));
  out.append(bytes, sizeof(T));
}

TEST(PlyParse, AsciiWithAliasesSkippedPropertiesFacesAndExtraElements) {
  const std::string text =
      "ply\r\n"
      "format ascii 1.0\r\n"
      "comment made by hand\r\n"
      "obj_info scanner 7\r\n"
      "element camera 1\r\n"
      "property float32 view_px\r\n"
      "property list uint8 int32 ids\r\n"
      "element vertex 4\r\n"
      "property int8 flags\r\n"
      "property float64 x\r\n"
      "property float32 y\r\n"
      "property int16 z\r\n"
      "property list uchar float garbage\r\n"
      "property float32 red\r\n"
      "property float32 green\r\n"
      "property float32 blue\r\n"
      "property uint16 quality\r\n"
      "property float nx\r\n"  // nx alone: no normals
      "element face 2\r\n"
      "property uchar flags\r\n"
      "property list uchar uint vertex_indices\r\n"
      "element material 2\r\n"
      "property double shine\r\n"
      "end_header\r\n"
      "1.5 3 7 8 9\r\n"
      "-1 0.5 -2.25 3 2 1 2 1 0 0.5 65535 0.1\r\n"
      "0 1 2 3 0 0 1 0 1 0.1\r\n"
      "0 4 5 6 1 4 0 0 0 2 0.3\r\n"
      "0 -7 -8 -9 0 0.5 0.5 0.5 3 0.4\r\n"
      "9 4 0 1 2 3\r\n"
      "9 3 3 2 1\r\n"
      "1\n2\n";
  auto s = parse_ply(text, "hand.ply");
  ASSERT_TRUE(s) << s.message();
  ASSERT_EQ(s->cloud.size(), 4u);
  EXPECT_EQ(s->cloud.points[0], Vec3(0.5, -2.25, 3));
  EXPECT_EQ(s->cloud.points[3], Vec3(-7, -8, -9));
  EXPECT_FALSE(s->cloud.has_normals());
  ASSERT_TRUE(s->cloud.has_colors());
  EXPECT_EQ(s->cloud.colors[0], (Rgb{255, 0, 128}));  // float 0..1 scaled, 0.5 -> 127.5 -> 128
  EXPECT_EQ(s->cloud.colors[3], (Rgb{128, 128, 128}));
  EXPECT_EQ(s->cloud.scalars, (std::vector<double>{65535, 1, 2, 3}));  // "quality"
  // The quad 0 1 2 3 becomes two fan triangles; the triangle stays.
  using Tri = std::array<std::uint32_t, 3>;
  EXPECT_EQ(s->triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}, {3, 2, 1}}));

  PointReadOptions no_faces;
  no_faces.read_faces = false;
  no_faces.scalar_property = "flags";
  auto points = parse_ply(text, "hand.ply", no_faces);
  ASSERT_TRUE(points) << points.message();
  EXPECT_TRUE(points->triangles.empty());
  EXPECT_EQ(points->cloud.scalars, (std::vector<double>{-1, 0, 0, 0}));

  PointReadOptions missing;
  missing.scalar_property = "deviation";
  auto error = parse_ply(text, "hand.ply", missing);
  ASSERT_FALSE(error);
  EXPECT_NE(error.message().find("no property 'deviation'"), std::string::npos);
}

TEST(PlyParse, BigEndianEveryScalarType) {
  std::string bytes =
      "ply\nformat binary_big_endian 1.0\nelement vertex 2\n"
      "property char a\nproperty uchar b\nproperty short c\nproperty ushort d\n"
      "property int e\nproperty uint f\nproperty float x\nproperty double y\n"
      "property int z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
      "property float nx\nproperty float ny\nproperty float nz\nproperty double scalar_dev\n"
      "end_header\n";
  for (int i = 0; i < 2; ++i) {
    put_be<std::int8_t>(bytes, -5);
    put_be<std::uint8_t>(bytes, 250);
    put_be<std::int16_t>(bytes, -30000);
    put_be<std::uint16_t>(bytes, 60000);
    put_be<std::int32_t>(bytes, -2000000000);
    put_be<std::uint32_t>(bytes, 4000000000u);
    put_be<float>(bytes, 1.25f + static_cast<float>(i));
    put_be<double>(bytes, -1e-3);
    put_be<std::int32_t>(bytes, 123456789);
    put_be<std::uint8_t>(bytes, 10);
    put_be<std::uint8_t>(bytes, 20);
    put_be<std::uint8_t>(bytes, 30);
    put_be<float>(bytes, 0.0f);
    put_be<float>(bytes, 0.6f);
    put_be<float>(bytes, 0.8f);
    put_be<double>(bytes, 0.125 * i);
  }
  auto s = parse_ply(bytes, "be.ply");
  ASSERT_TRUE(s) << s.message();
  ASSERT_EQ(s->cloud.size(), 2u);
  EXPECT_EQ(s->cloud.points[1], Vec3(2.25, -1e-3, 123456789));
  EXPECT_NEAR((s->cloud.normals[0] - Vec3(0, 0.6, 0.8)).norm(), 0.0, 1e-7);
  EXPECT_EQ(s->cloud.colors[1], (Rgb{10, 20, 30}));
  EXPECT_EQ(s->cloud.scalars, (std::vector<double>{0.0, 0.125}));
}

TEST(PlyParse, BinaryVertexWithListAndFaceIdsUsesTheGeneralPath) {
  std::string bytes =
      "ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty float x\n"
      "property list uchar short junk\nproperty float y\nproperty float z\nproperty int face_id\n"
      "end_header\n";
  for (int i = 0; i < 2; ++i) {
    put_be<float>(bytes, 1.0f * static_cast<float>(i));
    put_be<std::uint8_t>(bytes, static_cast<std::uint8_t>(i + 1));
    for (int k = 0; k <= i; ++k) put_be<std::int16_t>(bytes, 77);
    put_be<float>(bytes, 2.0f);
    put_be<float>(bytes, 3.0f);
    put_be<std::int32_t>(bytes, 40 + i);
  }
  auto s = parse_ply(bytes, "list.ply");
  ASSERT_TRUE(s) << s.message();
  EXPECT_EQ(s->cloud.points[1], Vec3(1, 2, 3));
  EXPECT_EQ(s->cloud.face_ids, (std::vector<std::int32_t>{40, 41}));
}

TEST(XyzParse, SeparatorsCommentsHeadersAndCountLines) {
  const std::string csv =
      "# exported by a CMM\n"
      "// second comment\n"
      "X,Y,Z\n"
      "\n"
      "1,2,3\n"
      "  4.5 ,\t-6e1 , +7\r\n"
      "\n"
      "8;9;10\n";
  auto s = parse_xyz(csv, "scan.csv");
  ASSERT_TRUE(s) << s.message();
  EXPECT_EQ(s->cloud.points, (std::vector<Vec3>{Vec3(1, 2, 3), Vec3(4.5, -60, 7), Vec3(8, 9, 10)}));
  EXPECT_FALSE(s->cloud.has_normals());

  auto pts = parse_xyz("2\n0 0 1 0 0 1\n1 1 1 0 1 0", "scan.pts");
  ASSERT_TRUE(pts) << pts.message();
  ASSERT_EQ(pts->cloud.normals.size(), 2u);
  EXPECT_EQ(pts->cloud.normals[1], Vec3(0, 1, 0));

  auto mixed = parse_xyz("1 2 3\n4 5 6 7\n", "mixed.xyz");
  ASSERT_FALSE(mixed);
  EXPECT_NE(mixed.message().find("mixed.xyz: line 2"), std::string::npos) << mixed.message();
  EXPECT_TRUE(mixed.error().is_corruption()) << mixed.error().to_string();
  auto word = parse_xyz("1 2 3\n4 five 6\n", "word.xyz");
  ASSERT_FALSE(word);
  EXPECT_NE(word.message().find("line 2: column 2"), std::string::npos) << word.message();
  auto five = parse_xyz("1 2 3 4 5\n", "five.xyz");
  ASSERT_FALSE(five);
  EXPECT_NE(five.message().find("5 columns"), std::string::npos) << five.message();
}

TEST(StlParse, AsciiErrorsNameTheLine) {
  const std::string text =
      "solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
      "   vertex 0 1\n  endloop\n endfacet\nendsolid t\n";
  auto s = parse_stl(text, "bad.stl");
  ASSERT_FALSE(s);
  EXPECT_NE(s.message().find("bad.stl: line 7"), std::string::npos) << s.message();
  EXPECT_TRUE(s.error().is_corruption()) << s.error().to_string();
}

}  // namespace
}  // namespace springscan::analysis
