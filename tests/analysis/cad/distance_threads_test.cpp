// The exact distance under threads: `springscan analyze` died at random (one run in four to
// twelve) in signed_deviation's workers inside BRepTopAdaptor_FClass2d::Perform, because all
// threads shared one classifier per face. The classifier only runs near curved trims, so the
// queries here crowd the curved face boundaries (holes, cut-outs, arcs) of real parts, and every
// parallel run must equal the serial one bit for bit (a race shows as a crash or as a different
// foot).
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "analysis/cad/distance.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/core/parallel.hpp"
#include "analysis/deviation/deviation.hpp"
#include "tests/analysis/cad_test_util.hpp"
#include "tests/analysis/under_sanitizer.hpp"

namespace springscan::analysis {
namespace {

using testing::shared_cad;

#if defined(SPRINGSCAN_UNDER_ASAN) || defined(SPRINGSCAN_TSAN)
// The sanitizers run this code 5 to 15 times slower (about 5 s a part under ThreadSanitizer).
// TSan cannot see inside OpenCASCADE (not instrumented); it reports a race of our own code on the
// first overlapping access, so two repetitions suffice there.
constexpr int kRepetitions = 2;
#else
// With one classifier per face shared by all threads (before FaceClassifierPool), 78 of 100 runs
// of a single part crashed or differed (20 of 20 for the front panel, the motor bracket and the
// nema-17 bracket, 16 for the side panel, 2 for the cover flange).
constexpr int kRepetitions = 6;
#endif
constexpr std::size_t kBoundaryQueries = 2000;  // per part, near face boundaries
constexpr std::size_t kBoxQueries = 250;        // per part, anywhere in the bounding box

// The mesh's face-boundary sides that continue a curved boundary (a hole, a cut-out, an arc in
// a contour): at both ends the next boundary side turns by a little (between 0 and 45 degrees;
// straight edges do not turn, corners turn more). Each face has its own mesh nodes, so a
// triangle side used once is a side on its face's boundary.
using Side = std::pair<std::uint32_t, std::uint32_t>;
std::vector<Side> curved_boundary_sides(const CadMesh& mesh) {
  std::map<Side, int> uses;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) ++uses[std::minmax(t[k], t[(k + 1) % 3])];
  std::vector<Side> boundary;
  std::multimap<std::uint32_t, std::size_t> sides_at;  // vertex -> boundary sides ending there
  for (const auto& [side, n] : uses) {
    if (n != 1) continue;
    sides_at.emplace(side.first, boundary.size());
    sides_at.emplace(side.second, boundary.size());
    boundary.push_back(side);
  }
  const auto direction = [&](const Side& s) {
    return (mesh.vertices[s.second] - mesh.vertices[s.first]).normalized();
  };
  const auto turns_slightly = [&](std::size_t i, std::uint32_t end) {
    const auto [first, last] = sides_at.equal_range(end);
    for (auto it = first; it != last; ++it) {
      if (it->second == i) continue;
      const Vec3 a = direction(boundary[i]), b = direction(boundary[it->second]);
      if (a.cross(b).norm() > 1e-9 && std::abs(a.dot(b)) > std::cos(std::numbers::pi / 4))
        return true;
    }
    return false;
  };
  std::vector<Side> curved;
  for (std::size_t i = 0; i < boundary.size(); ++i)
    if (turns_slightly(i, boundary[i].first) && turns_slightly(i, boundary[i].second))
      curved.push_back(boundary[i]);
  return curved;
}

// Points within 0.15 mm of curved face boundaries: inside the classifier's band (2 x the
// 0.05 mm linear deflection) on both sides of the boundary chords.
std::vector<Vec3> boundary_queries(const CadMesh& mesh, std::size_t count, std::mt19937& rng) {
  const std::vector<Side> sides = curved_boundary_sides(mesh);
  std::vector<Vec3> out;
  if (sides.empty()) return out;
  std::uniform_int_distribution<std::size_t> pick(0, sides.size() - 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0), offset(-0.15, 0.15);
  out.reserve(count);
  while (out.size() < count) {
    const auto [a, b] = sides[pick(rng)];
    const double t = unit(rng);
    const Vec3 on_chord = (1.0 - t) * mesh.vertices[a] + t * mesh.vertices[b];
    out.push_back(on_chord + Vec3(offset(rng), offset(rng), offset(rng)));
  }
  return out;
}

std::vector<Vec3> box_queries(const CadLoadReport& report, std::size_t count, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-0.05, 1.05);
  const Vec3 lo = report.bbox_min, size = report.bbox_max - report.bbox_min;
  std::vector<Vec3> out(count);
  for (auto& q : out) q = lo + size.cwiseProduct(Vec3(unit(rng), unit(rng), unit(rng)));
  return out;
}

// Exact equality of everything a hit reports; the first mismatch is described.
::testing::AssertionResult same_hits(const std::vector<SurfaceHit>& serial,
                                     const std::vector<SurfaceHit>& parallel) {
  if (serial.size() != parallel.size())
    return ::testing::AssertionFailure() << parallel.size() << " hits for " << serial.size();
  std::size_t differ = 0, first = 0;
  for (std::size_t i = 0; i < serial.size(); ++i) {
    const SurfaceHit &s = serial[i], &p = parallel[i];
    const bool same = s.signed_distance_mm == p.signed_distance_mm && s.foot == p.foot &&
                      s.normal == p.normal && s.face_id == p.face_id;
    if (!same && differ++ == 0) first = i;
  }
  if (differ == 0) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << differ << " of " << serial.size() << " hits differ; first at " << first << ": serial "
         << serial[first].signed_distance_mm << " mm on face " << serial[first].face_id
         << ", parallel " << parallel[first].signed_distance_mm << " mm on face "
         << parallel[first].face_id;
}

class CadDistanceThreads : public ::testing::TestWithParam<const char*> {};

TEST_P(CadDistanceThreads, ParallelEqualsSerialNearTrims) {
  const auto shape = load_cad(shared_cad(GetParam()));
  ASSERT_TRUE(shape) << shape.message();
  const auto distance = make_cad_distance(*shape);
  ASSERT_NE(distance, nullptr);
  std::mt19937 rng(1300);
  std::vector<Vec3> queries = boundary_queries(shape->mesh(), kBoundaryQueries, rng);
  ASSERT_EQ(queries.size(), kBoundaryQueries) << "no curved face boundary in the mesh";
  const auto box = box_queries(shape->report(), kBoxQueries, rng);
  queries.insert(queries.end(), box.begin(), box.end());

  const auto serial = closest_all(*distance, queries, 1);
  for (int threads : {2, 8})
    for (int rep = 0; rep < kRepetitions; ++rep)
      ASSERT_TRUE(same_hits(serial, closest_all(*distance, queries, threads)))
          << threads << " threads, repetition " << rep;

  // The same through signed_deviation, the stage that crashed: it hands blocks of
  // kParallelBlock points to its workers, so the queries are repeated over two blocks.
  PartModel model;
  model.distance = distance;
  std::vector<Vec3> scan;
  while (scan.size() < 2 * kParallelBlock) scan.insert(scan.end(), queries.begin(), queries.end());
  const KdTree no_samples(std::vector<Vec3>{});
  const auto deviation = signed_deviation(scan, model, no_samples, {.threads = 2});
  ASSERT_TRUE(deviation) << deviation.message();
  std::size_t differ = 0;
  for (std::size_t i = 0; i < scan.size(); ++i)
    differ += deviation->signed_distance_mm[i] != serial[i % queries.size()].signed_distance_mm;
  EXPECT_EQ(differ, 0u) << "of " << scan.size() << " signed deviations on 2 threads";
}

// "nema-17-bracket.step" -> "nema_17_bracket": test names allow only letters, digits and '_'.
std::string part_name(const ::testing::TestParamInfo<const char*>& param) {
  std::string name = param.param;
  name = name.substr(0, name.rfind('.'));
  std::replace_if(
      name.begin(), name.end(), [](char c) { return !std::isalnum(static_cast<unsigned char>(c)); },
      '_');
  return name;
}

INSTANTIATE_TEST_SUITE_P(RealParts, CadDistanceThreads,
                         ::testing::Values("openamr-MMP.00.00.00.001_Front_panel.step",
                                           "openamr-MMP.00.00.00.003_Side_panel.step",
                                           "openamr-MMP.01.00.00.002_Cover_flange.step",
                                           "openamr-MMP.03.00.00.003_Motor_bracket.step",
                                           "nema-17-bracket.step"),
                         part_name);

}  // namespace
}  // namespace springscan::analysis
