// Springback measured on a PartModel built the production way: the profile as an OpenCASCADE
// shape, sampled (sample_cad) and segmented (segment_cad) like an imported IGES/STEP part.
#include <gtest/gtest.h>

#include <filesystem>

#include "analysis/cad/model.hpp"
#include "analysis/cad/sampling.hpp"
#include "analysis/cad/segmentation.hpp"
#include "analysis/springback/springback.hpp"
#include "simulators/parts/cad_profile.hpp"
#include "simulators/parts/shaped_profile.hpp"
#include "simulators/parts/sheet_part.hpp"

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

PartModel cad_model(const ProfileSpec& spec) {
  const auto shape = make_profile_shape(spec);
  EXPECT_TRUE(shape.ok()) << shape.message();
  PartModel model;
  auto samples = sample_cad(*shape, {.sample_count = 20000});
  EXPECT_TRUE(samples.ok()) << samples.message();
  model.samples = std::move(samples).value();
  model.segmentation = segment_cad(*shape);
  model.face_count = shape->face_count();
  return model;
}

void expect_springback_on_cad(ProfileSpec spec, const std::vector<double>& springback_deg) {
  const PartModel model = cad_model(spec);
  ASSERT_EQ(model.segmentation.bends.size(), springback_deg.size());
  ScanSimulationSettings st;
  st.point_count = 40000;
  st.noise_sigma_mm = 0.02;
  const auto scan = simulate_scan(spec, springback_deg, st);  // the reference side
  ASSERT_TRUE(scan.ok());
  const auto result = measure_springback(model, *scan);
  ASSERT_TRUE(result.ok()) << result.message();
  for (const BendMeasurement& bend : result->bends) {
    ASSERT_TRUE(bend.measured) << bend.status;
    // segment_cad numbers bends by their smallest face id, i.e. in path order here.
    const double truth = springback_deg[static_cast<std::size_t>(bend.bend_id)];
    EXPECT_NEAR(bend.springback_deg, truth, 0.05) << "bend " << bend.bend_id;
    EXPECT_NEAR(bend.nominal_angle_deg,
                std::abs(spec.bend_angles_deg[static_cast<std::size_t>(bend.bend_id)]), 1e-6);
  }
}

TEST(SpringbackCad, SurfaceModelOfAZProfile) {
  expect_springback_on_cad(z_profile(40, 35, 75, 4), {1.5, -0.5});
}

TEST(SpringbackCad, SolidSheetWithBothSidesOfAHatProfile) {
  ProfileSpec spec = hat_profile(25, 30, 40, 85, 4);
  spec.thickness_mm = 1.5;
  expect_springback_on_cad(spec, {1.0, 2.0, 0.5, 1.5});
}

// The free edges of a solid hat loaded like a CAD file (exact distance): its end faces are
// other faces, whose 2 mm margin must not cut the flanges' edges short. The last brim 0.3 mm
// longer, the first as drawn; the scan in the CAD frame.
TEST(SpringbackCad, FreeEdgesOfASolidSheet) {
  ProfileSpec spec = hat_profile(25, 30, 40, 85, 4);
  spec.thickness_mm = 1.5;
  spec.width_mm = 80;
  const std::string path =
      (std::filesystem::temp_directory_path() / "springscan_edge_hat.brep").string();
  ASSERT_TRUE(write_profile_cad(spec, path));
  const auto model = load_part_model(path);
  ASSERT_TRUE(model.ok()) << model.message();
  ProfileShape shape;
  shape.length_change_mm = {0, 0, 0, 0, 0.3};
  const auto scan = simulate_shaped_scan(spec, shape, {.point_count = 60000});
  ASSERT_TRUE(scan.ok());
  const auto result = measure_springback(*model, *scan);
  ASSERT_TRUE(result.ok()) << result.message();
  int edges = 0;
  double total = 0.0;
  for (const FlangeFit& f : result->flanges) {
    const EdgeDeviation* e = f.free_edge();
    if (!e) continue;
    ++edges;
    // Flange ids follow segment_cad; the moved brim is the one whose edge came out.
    const double truth = e->in_plane_mean_mm > 0.15 ? 0.3 : 0.0;
    EXPECT_NEAR(e->in_plane_min_mm, truth, 0.05) << "flange " << f.flange_id;
    EXPECT_NEAR(e->in_plane_max_mm, truth, 0.05) << "flange " << f.flange_id;
    EXPECT_NEAR(e->across_mean_mm, 0.0, 0.05) << "flange " << f.flange_id;
    total += e->in_plane_mean_mm;
  }
  EXPECT_EQ(edges, 2);
  EXPECT_NEAR(total, 0.3, 0.05) << "one edge moved by 0.3 mm, the other not";
  // The side edges of every flange, where the sheet ends along the extrusion: as drawn.
  int side_edges = 0;
  for (const FlangeFit& f : result->flanges)
    for (const EdgeDeviation& e : f.trim_edges) {
      if (e.kind != EdgeKind::kSide) continue;
      ++side_edges;
      EXPECT_NEAR(e.in_plane_mean_mm, 0.0, 0.05) << "flange " << f.flange_id;
      EXPECT_NEAR(e.across_mean_mm, 0.0, 0.05) << "flange " << f.flange_id;
    }
  // Two on each of five flanges; on this solid one of them may miss points in a strip next
  // to a bend (9 of 10 measured here) and is then left out, as the rule says.
  EXPECT_GE(side_edges, 8) << "two on each of five flanges";
}

// A few lone readings beyond a free edge on the flange's own surface (outliers along a grazing
// ray that stay within its inlier band): the edge is the sheet's, not carried out to them.
TEST(SpringbackCad, LoneReadingsBeyondAnEdgeAreNotTheEdge) {
  ProfileSpec spec = hat_profile(25, 30, 40, 85, 4);
  spec.thickness_mm = 1.5;
  spec.width_mm = 80;
  const std::string path =
      (std::filesystem::temp_directory_path() / "springscan_edge_outlier_hat.brep").string();
  ASSERT_TRUE(write_profile_cad(spec, path));
  const auto model = load_part_model(path);
  ASSERT_TRUE(model.ok()) << model.message();
  auto scan = simulate_shaped_scan(spec, ProfileShape{}, {.point_count = 60000});
  ASSERT_TRUE(scan.ok());
  const auto clean = measure_springback(*model, *scan);
  ASSERT_TRUE(clean.ok()) << clean.message();
  // Beyond each free edge, 1.5-2.5 mm out in plane (3-5 of this scan's point spacings, about
  // 0.46 mm), one reading per strip.
  int free_edges = 0;
  for (const FlangeFit& f : clean->flanges)
    if (const EdgeDeviation* e = f.free_edge()) {
      ++free_edges;
      for (std::size_t k = 0; k < e->scan_edge.size(); ++k) {
        scan->points.push_back(e->scan_edge[k] + (1.5 + 0.5 * static_cast<double>(k)) * e->outward);
        if (scan->has_normals()) scan->normals.push_back(scan->normals.front());
      }
    }
  ASSERT_EQ(free_edges, 2);
  const auto result = measure_springback(*model, *scan);
  ASSERT_TRUE(result.ok()) << result.message();
  int edges = 0;
  for (const FlangeFit& f : result->flanges)
    if (const EdgeDeviation* e = f.free_edge()) {
      ++edges;
      EXPECT_NEAR(e->in_plane_min_mm, 0.0, 0.05) << "flange " << f.flange_id;
      EXPECT_NEAR(e->in_plane_max_mm, 0.0, 0.05) << "flange " << f.flange_id;
    }
  EXPECT_EQ(edges, 2);
}

}  // namespace
}  // namespace springscan::analysis
