// Hostile input: every reader must answer with an error naming the file and the line or byte
// offset, never crash, and never allocate by a count the file cannot hold. The sanitizer build
// runs these too (scripts/test.sh sanitize).
#include <gtest/gtest.h>

#include <random>

#include "analysis/io/point_io.hpp"

namespace springscan::analysis {
namespace {

// Asserts an error that contains each of `parts`.
template <typename T>
void expect_error(const Expected<T>& result, std::initializer_list<std::string> parts) {
  ASSERT_FALSE(result.ok()) << "expected an error containing " << *parts.begin();
  for (const std::string& part : parts) {
    EXPECT_NE(result.message().find(part), std::string::npos)
        << "'" << part << "' not in: " << result.message();
  }
}

std::string binary_ply_header(const std::string& count) {
  return "ply\nformat binary_little_endian 1.0\nelement vertex " + count +
         "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
}

std::string valid_binary_ply() {
  Surface s;
  for (int i = 0; i < 6; ++i) s.cloud.points.emplace_back(i, 2 * i, 3 * i);
  s.cloud.normals.assign(6, Vec3(0, 0, 1));
  s.triangles = {{0, 1, 2}, {3, 4, 5}};
  PointWriteOptions options;
  options.single_precision = true;
  return format_ply(s, options).value();
}

TEST(Hostile, HugeVertexCountOnASmallFileIsRejectedBeforeAllocating) {
  std::string bytes = binary_ply_header("1000000000000") + std::string(1000, '\0');
  expect_error(parse_ply(bytes, "huge.ply"),
               {"huge.ply", "declares 1000000000000 records", "bytes remain after byte offset"});
  const std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 1000000000000\n"
      "property float x\nproperty float y\nproperty float z\nend_header\n"
      "1 2 3\n";
  expect_error(parse_ply(ascii, "huge_ascii.ply"), {"huge_ascii.ply", "1000000000000", "line 8"});
  // A count past 2^64 is not a number at all.
  expect_error(parse_ply(binary_ply_header("99999999999999999999999"), "overflow.ply"),
               {"overflow.ply", "header line 3", "not a number"});
  // Huge counts in a binary STL header and in a skipped element without properties.
  std::string stl(84, '\0');
  stl[80] = stl[81] = stl[82] = stl[83] = '\xff';
  expect_error(parse_stl(stl, "huge.stl"), {"huge.stl", "4294967295 triangles"});
  const std::string empty_element =
      "ply\nformat binary_little_endian 1.0\nelement nothing 1000000000000\n"
      "element vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  expect_error(parse_ply(empty_element, "noprops.ply"), {"noprops.ply", "no properties"});
}

TEST(Hostile, TruncatedBodiesNameTheOffsetOrLine) {
  const std::string valid = valid_binary_ply();
  expect_error(parse_ply(valid.substr(0, valid.size() - 5), "cut.ply"),
               {"cut.ply", "element 'face'", "byte offset"});
  const std::string header = binary_ply_header("3");
  expect_error(
      parse_ply(header + std::string(35, '\0'), "cut_vertex.ply"),
      {"cut_vertex.ply", "element 'vertex'", "byte offset " + std::to_string(header.size())});
  const std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n1 2 3\n4 5        ";
  expect_error(parse_ply(ascii, "cut_ascii.ply"), {"cut_ascii.ply", "line 9", "ends mid-record"});
  Surface tri;
  tri.cloud.points = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  tri.triangles = {{0, 1, 2}, {2, 1, 0}};
  const std::string stl = format_stl(tri).value();
  expect_error(parse_stl(stl.substr(0, stl.size() - 1), "cut.stl"),
               {"cut.stl", "2 triangles", "needs 184 bytes", "has 183 bytes"});
  expect_error(parse_stl("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", "cut_a.stl"),
               {"cut_a.stl", "line 4", "expected 'vertex', got the end of the file"});
  expect_error(parse_stl("solid x\n", "noend.stl"), {"noend.stl", "before 'endsolid'"});
}

TEST(Hostile, NonFiniteCoordinatesAreRejectedWithTheVertexIndex) {
  const std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\n"
      "property double y\nproperty double z\nend_header\n"
      "1 2 3\n4 5 6\n7 nan 9\n";
  expect_error(parse_ply(ascii, "nan.ply"), {"nan.ply", "vertex 2", "non-finite coordinate"});
  Surface s;
  s.cloud.points = {Vec3(0, 0, 0), Vec3(std::numeric_limits<double>::infinity(), 0, 0)};
  expect_error(parse_ply(format_ply(s).value(), "inf.ply"), {"inf.ply", "vertex 1"});
  s.cloud.points[1] = Vec3::Zero();
  s.cloud.normals = {Vec3(0, 0, 1), Vec3(0, std::nan(""), 1)};
  expect_error(parse_ply(format_ply(s).value(), "nann.ply"), {"vertex 1", "non-finite normal"});
  expect_error(parse_xyz("1 2 3\n4 inf 6\n", "inf.xyz"),
               {"inf.xyz", "line 2", "point 1", "non-finite"});
  expect_error(parse_stl("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
                         "vertex NaN 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n",
                         "nan.stl"),
               {"nan.stl", "triangle 0", "non-finite"});
}

TEST(Hostile, BadHeadersNameTheHeaderLine) {
  const std::string prefix = "ply\nformat binary_little_endian 1.0\nelement vertex 1\n";
  expect_error(parse_ply(prefix + "property float x\nproperty quad y\nend_header\n", "t.ply"),
               {"t.ply", "header line 5", "unknown property type 'quad'"});
  expect_error(parse_ply(prefix + "property list float int v\nend_header\n", "l.ply"),
               {"l.ply", "header line 4", "not integer"});
  expect_error(parse_ply(prefix + "property float x\n", "noend.ply"),
               {"noend.ply", "no end_header"});
  expect_error(parse_ply("ply\nformat binary_middle_endian 1.0\nend_header\n", "f.ply"),
               {"f.ply", "header line 2", "unknown format"});
  expect_error(parse_ply("ply\nelement vertex 1\nend_header\n", "nf.ply"),
               {"nf.ply", "header line 2", "expected the format line"});
  expect_error(
      parse_ply(prefix + "property float x\nproperty float y\nend_header\n0000", "noz.ply"),
      {"noz.ply", "lacks property x, y or z"});
  expect_error(parse_ply("ply\nformat ascii 1.0\nend_header\n", "novertex.ply"),
               {"novertex.ply", "no 'vertex' element"});
}

TEST(Hostile, ListCountsThatOverrunAndBadFaces) {
  std::string valid = valid_binary_ply();
  // The first face record starts right after the 6 vertices; its count byte says 3.
  const std::size_t face = valid.find("end_header\n") + 11 + 6 * 24;
  ASSERT_EQ(valid[face], 3);
  std::string overrun = valid;
  overrun[face] = static_cast<char>(200);
  expect_error(parse_ply(overrun, "overrun.ply"),
               {"overrun.ply", "element 'face' record 0", "list of 200 items overruns"});
  std::string bad_index = valid;
  bad_index[face + 1] = 99;
  expect_error(parse_ply(bad_index, "index.ply"),
               {"index.ply", "triangle 0 refers to vertex 99", "6 vertices"});
  const std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n";
  expect_error(parse_ply(ascii + "2 0 1\n", "two.ply"), {"two.ply", "face has 2 vertices"});
  expect_error(parse_ply(ascii + "99999 0 1 2\n", "many.ply"),
               {"many.ply", "line 13", "list of 99999 items overruns"});
  expect_error(parse_ply(ascii + "3 0 -1 2\n", "neg.ply"), {"neg.ply", "vertex index -1"});
  expect_error(parse_ply(ascii + "-3 0 1 2\n", "negc.ply"), {"negc.ply", "list count"});
}

TEST(Hostile, EmptyFilesAndBinaryGarbage) {
  for (auto format : {PointFormat::kPly, PointFormat::kXyz, PointFormat::kStl}) {
    expect_error(parse_surface("", format, "empty.file"), {"empty.file", "empty file"});
  }
  expect_error(parse_xyz("# nothing\n\n", "comments.xyz"), {"comments.xyz", "no points"});
  std::mt19937 rng(42);
  std::string garbage(4096, '\0');
  for (auto& c : garbage) c = static_cast<char>(rng());
  expect_error(parse_ply(garbage, "garbage.ply"), {"garbage.ply", "not a PLY file"});
  expect_error(parse_xyz(garbage, "garbage.xyz"), {"garbage.xyz"});
  expect_error(parse_stl(garbage, "garbage.stl"), {"garbage.stl", "triangles"});
  expect_error(parse_stl("hello", "short.stl"), {"short.stl", "not an STL file"});
  expect_error(parse_ply("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                         "property float y\nproperty float z\nend_header\n1 \x01\x02 3\n",
                         "bin_in_ascii.ply"),
               {"bin_in_ascii.ply", "line 8", "expected a number"});
}

// Every prefix and thousands of random byte flips of valid files: errors or values, never a
// crash (the sanitizer build turns any out-of-bounds read into a failure).
TEST(Hostile, TruncationsAndMutationsNeverCrash) {
  Surface s;
  for (int i = 0; i < 4; ++i) s.cloud.points.emplace_back(i, -i, 0.5 * i);
  s.triangles = {{0, 1, 2}, {1, 2, 3}};
  PointWriteOptions ascii;
  ascii.ply_encoding = PlyEncoding::kAscii;
  const std::vector<std::pair<std::string, PointFormat>> files = {
      {valid_binary_ply(), PointFormat::kPly},
      {format_ply(s, ascii).value(), PointFormat::kPly},
      {format_stl(s).value(), PointFormat::kStl},
      {format_xyz(s).value(), PointFormat::kXyz},
      {"solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
       "endloop\nendfacet\nendsolid a\n",
       PointFormat::kStl}};
  std::mt19937 rng(7);
  std::size_t parsed = 0;
  for (const auto& [bytes, format] : files) {
    ASSERT_TRUE(parse_surface(bytes, format, "valid"));
    for (std::size_t n = 0; n < bytes.size(); ++n) {
      parsed += parse_surface(bytes.substr(0, n), format, "prefix").ok();
    }
    for (int trial = 0; trial < 2000; ++trial) {
      std::string mutated = bytes;
      for (int k = 0; k < 3; ++k) mutated[rng() % mutated.size()] = static_cast<char>(rng());
      parsed += parse_surface(mutated, format, "mutated").ok();
    }
  }
  EXPECT_GT(parsed, 0u);  // some mutations (a changed digit) still parse, as they should
}

}  // namespace
}  // namespace springscan::analysis
