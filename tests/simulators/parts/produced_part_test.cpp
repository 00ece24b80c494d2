#include "simulators/parts/produced_part.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "analysis/cad/sampling.hpp"
#include "analysis/cad/segmentation.hpp"
#include "analysis/core/kdtree.hpp"
#include "simulators/parts/cad_profile.hpp"
#include "simulators/parts/sheet_part.hpp"
#include "tests/simulators/parts/production_parts.hpp"

namespace springscan::parts {
namespace {

using testing::loaded_part;
using testing::production_parts;

constexpr double kDeg = std::numbers::pi / 180.0;

std::vector<double> random_springback(const PartModel& model, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> sb(0.2, 3.0);
  std::vector<double> out;
  for (std::size_t i = 0; i < model.segmentation.bends.size(); ++i) out.push_back(sb(rng));
  return out;
}

struct Plane {
  Vec3 centroid = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
  std::size_t points = 0;
};

// Least-squares plane of the produced samples of one side of a flange: the flange's faces whose
// CAD normal agrees with that of its largest face (the two sides together would tilt the fit).
Plane fit_side(const ProducedPart& part, const Flange& flange,
               const std::vector<CadFaceInfo>& faces) {
  int largest = flange.face_ids.front();
  for (int f : flange.face_ids) {
    if (faces[static_cast<std::size_t>(f)].area_mm2 >
        faces[static_cast<std::size_t>(largest)].area_mm2) {
      largest = f;
    }
  }
  const Vec3 side = faces[static_cast<std::size_t>(largest)].direction;
  std::vector<Vec3> pts;
  for (std::size_t i = 0; i < part.samples.size(); ++i) {
    const int f = part.samples.face_ids[i];
    if (std::find(flange.face_ids.begin(), flange.face_ids.end(), f) == flange.face_ids.end()) {
      continue;
    }
    if (faces[static_cast<std::size_t>(f)].direction.dot(side) > 0.0)
      pts.push_back(part.samples.points[i]);
  }
  Plane plane;
  plane.points = pts.size();
  if (pts.size() < 3) return plane;
  for (const auto& p : pts) plane.centroid += p;
  plane.centroid /= static_cast<double>(pts.size());
  Mat3 cov = Mat3::Zero();
  for (const auto& p : pts) cov += (p - plane.centroid) * (p - plane.centroid).transpose();
  Eigen::SelfAdjointEigenSolver<Mat3> eig(cov);
  plane.normal = eig.eigenvectors().col(0);
  return plane;
}

// The angle the sheet turns between two fitted flange planes: 180 degrees minus the angle
// between the two flanges' directions away from the planes' intersection line. Needs neither
// the normals' orientation nor the segmentation's axes.
double turn_angle_deg(const Plane& a, const Plane& b) {
  const Vec3 d = a.normal.cross(b.normal).normalized();
  Mat3 m;
  m.row(0) = a.normal.transpose();
  m.row(1) = b.normal.transpose();
  m.row(2) = d.transpose();
  const Vec3 rhs(a.normal.dot(a.centroid), b.normal.dot(b.centroid), d.dot(a.centroid));
  const Vec3 on_line = m.fullPivLu().solve(rhs);
  Vec3 ua = d.cross(a.normal), ub = d.cross(b.normal);
  if (ua.dot(a.centroid - on_line) < 0.0) ua = -ua;
  if (ub.dot(b.centroid - on_line) < 0.0) ub = -ub;
  return 180.0 - std::acos(std::clamp(ua.dot(ub), -1.0, 1.0)) / kDeg;
}

class ProducedPartOf : public ::testing::TestWithParam<std::string> {};

TEST_P(ProducedPartOf, FittedFlangePlanesMeetAtNominalMinusSpringback) {
  const auto& loaded = loaded_part(GetParam());
  const auto& seg = loaded.model.segmentation;
  ASSERT_FALSE(seg.bends.empty());
  const auto springback = random_springback(loaded.model, 7);
  const auto part = make_produced_part(loaded.model, loaded.shape, springback);
  ASSERT_TRUE(part) << part.message();
  EXPECT_TRUE(part->report.closing_bends.empty());
  const auto faces = describe_faces(loaded.shape);
  double worst = 0.0;
  int checked = 0;
  for (const Bend& bend : seg.bends) {
    const BendTruth& truth = part->bends[static_cast<std::size_t>(bend.id)];
    if (truth.hem) {
      EXPECT_EQ(truth.springback_deg, 0.0);
      continue;
    }
    EXPECT_EQ(truth.springback_deg, springback[static_cast<std::size_t>(bend.id)]);
    const Plane a = fit_side(*part, seg.flanges[static_cast<std::size_t>(bend.flange_a)], faces);
    const Plane b = fit_side(*part, seg.flanges[static_cast<std::size_t>(bend.flange_b)], faces);
    ASSERT_GE(a.points, 3u);
    ASSERT_GE(b.points, 3u);
    const double expected = bend.nominal_angle_deg - truth.springback_deg;
    const double error = turn_angle_deg(a, b) - expected;
    EXPECT_NEAR(error, 0.0, 1e-6) << GetParam() << " bend " << bend.id;
    EXPECT_NEAR(truth.produced_angle_deg, expected, 1e-12);
    worst = std::max(worst, std::abs(error));
    ++checked;
  }
  std::cout << GetParam() << ": " << checked << " bends, worst plane-fit error " << worst
            << " deg\n";
}

// Coincident CAD vertices of neighbouring faces stay together: the part does not tear, whether
// the faces are flanges, bend zones or sheet edges spanning flange and bend.
TEST_P(ProducedPartOf, DoesNotTear) {
  const auto& loaded = loaded_part(GetParam());
  const auto part =
      make_produced_part(loaded.model, loaded.shape, random_springback(loaded.model, 3));
  ASSERT_TRUE(part) << part.message();
  const CadMesh& cad = loaded.shape.mesh();
  std::vector<std::int32_t> vertex_face(cad.vertices.size(), -1);
  for (std::size_t t = 0; t < cad.triangles.size(); ++t) {
    for (auto v : cad.triangles[t]) vertex_face[v] = cad.triangle_faces[t];
  }
  const KdTree tree(cad.vertices);
  std::vector<Neighbor> near;
  double worst = 0.0;
  std::size_t pairs = 0;
  for (std::size_t i = 0; i < cad.vertices.size(); ++i) {
    tree.radius(cad.vertices[i], 1e-4, near);
    for (const auto& n : near) {
      if (vertex_face[n.index] == vertex_face[i]) continue;
      ++pairs;
      worst = std::max(worst, (part->mesh.vertices[n.index] - part->mesh.vertices[i]).norm());
    }
  }
  EXPECT_GT(pairs, 100u);
  EXPECT_LT(worst, 1e-9) << GetParam();
  std::cout << GetParam() << ": " << pairs << " seam vertex pairs, widest gap " << worst << " mm\n";
}

// Bend zones stay cylinders of their radius about the produced axis, spanning nominal - springback.
TEST_P(ProducedPartOf, BendZonesKeepTheirRadius) {
  const auto& loaded = loaded_part(GetParam());
  const auto& seg = loaded.model.segmentation;
  const auto part =
      make_produced_part(loaded.model, loaded.shape, random_springback(loaded.model, 5));
  ASSERT_TRUE(part) << part.message();
  for (std::size_t i = 0; i < part->samples.size(); ++i) {
    const int f = part->samples.face_ids[i];
    for (const Bend& bend : seg.bends) {
      if (std::find(bend.face_ids.begin(), bend.face_ids.end(), f) == bend.face_ids.end()) continue;
      const auto& truth = part->bends[static_cast<std::size_t>(bend.id)];
      const Vec3 v_cad = loaded.model.samples.points[i] - bend.axis_point;
      const Vec3 v = part->samples.points[i] - truth.axis_point;
      const double r_cad = (v_cad - v_cad.dot(bend.axis_direction) * bend.axis_direction).norm();
      const double r = (v - v.dot(truth.axis_direction) * truth.axis_direction).norm();
      ASSERT_NEAR(r, r_cad, 1e-9) << "bend " << bend.id;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(ProductionParts, ProducedPartOf, ::testing::ValuesIn(production_parts()),
                         [](const auto& param_info) {
                           std::string name =
                               param_info.param.substr(0, param_info.param.rfind('.'));
                           if (name.rfind("openamr", 0) == 0)
                             name = name.substr(name.find('_') + 1);
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

// An independent oracle: a profile's CAD (shell or solid, through OpenCASCADE), produced with
// flange 0 as the root, lies on the analytic produced profile (sheet_part.hpp: the same path
// with each bend angle reduced by its springback, built from the same origin): every produced
// sample of the reference side, bend zones included, within 1e-9 mm.
struct ProfileCase {
  const char* name;
  ProfileSpec spec;
  std::vector<double> springback_deg;
};

class ProducedProfile : public ::testing::TestWithParam<ProfileCase> {};

TEST_P(ProducedProfile, LiesOnTheAnalyticProducedProfile) {
  const ProfileCase& c = GetParam();
  const auto shape = make_profile_shape(c.spec);
  ASSERT_TRUE(shape) << shape.message();
  PartModel model;
  auto samples = sample_cad(*shape);
  ASSERT_TRUE(samples) << samples.message();
  model.samples = std::move(*samples);
  model.segmentation = segment_cad(*shape);
  model.face_count = shape->face_count();
  ASSERT_EQ(model.segmentation.bends.size(), c.springback_deg.size());
  // The root: the flange holding the sample nearest the middle of path line 0.
  const Vec3 start(0.5 * c.spec.flange_lengths_mm[0], 0.5 * c.spec.width_mm, 0.0);
  std::size_t nearest = 0;
  for (std::size_t i = 0; i < model.samples.size(); ++i) {
    if ((model.samples.points[i] - start).norm() < (model.samples.points[nearest] - start).norm()) {
      nearest = i;
    }
  }
  ProducedPartSettings settings;
  for (const Flange& f : model.segmentation.flanges) {
    const auto& ids = f.face_ids;
    if (std::find(ids.begin(), ids.end(), model.samples.face_ids[nearest]) != ids.end()) {
      settings.root_flange = f.id;
    }
  }
  ASSERT_GE(settings.root_flange, 0);
  // Springback per CAD bend: the analytic bend whose arc holds the CAD bend's axis.
  const auto path = profile_path(c.spec);
  std::vector<double> springback;
  for (const Bend& bend : model.segmentation.bends) {
    double best = 1e9, sb = 0.0;
    for (const auto& e : path) {
      if (e.kind != ProfileElement::Kind::kArc) continue;
      const double d =
          (Eigen::Vector2d(bend.axis_point.x(), bend.axis_point.z()) - e.center).norm();
      if (d < best) best = d, sb = c.springback_deg[static_cast<std::size_t>(e.bend_index)];
    }
    springback.push_back(sb);
  }
  const auto part = make_produced_part(model, *shape, springback, settings);
  ASSERT_TRUE(part) << part.message();
  const auto produced_spec = produced_profile(c.spec, c.springback_deg);
  ASSERT_TRUE(produced_spec) << produced_spec.message();
  const auto nominal_surface = profile_surface_distance(c.spec);
  const auto produced_surface = profile_surface_distance(*produced_spec);
  std::size_t checked = 0, in_bends = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < model.samples.size(); ++i) {
    const auto on_nominal = nominal_surface->closest(model.samples.points[i]);
    if (std::abs(on_nominal.signed_distance_mm) > 1e-7) continue;  // not the reference side
    const auto on_produced = produced_surface->closest(part->samples.points[i]);
    worst = std::max(worst, std::abs(on_produced.signed_distance_mm));
    ++checked;
    in_bends +=
        path[static_cast<std::size_t>(on_nominal.face_id)].kind == ProfileElement::Kind::kArc;
  }
  EXPECT_GT(checked, 1000u);
  EXPECT_GT(in_bends, 50u);
  EXPECT_LT(worst, 1e-9) << c.name;
  std::cout << c.name << ": " << checked << " reference-side samples (" << in_bends
            << " in bend zones) within " << worst << " mm of the analytic produced profile\n";
}

INSTANTIATE_TEST_SUITE_P(Profiles, ProducedProfile,
                         ::testing::Values(ProfileCase{"hat_shell",
                                                       hat_profile(25, 30, 40, 60, 4),
                                                       {1.5, 0.8, 1.1, 0.4}},
                                           ProfileCase{"hat_solid",
                                                       [] {
                                                         ProfileSpec s =
                                                             hat_profile(25, 30, 40, 90, 3);
                                                         s.thickness_mm = 2.0;
                                                         return s;
                                                       }(),
                                                       {2.0, 0.5, 3.0, 1.0}},
                                           ProfileCase{"z_solid",
                                                       [] {
                                                         ProfileSpec s = z_profile(30, 40, 60, 5);
                                                         s.thickness_mm = 1.5;
                                                         return s;
                                                       }(),
                                                       {-1.0, 2.5}}),
                         [](const auto& param_info) { return std::string(param_info.param.name); });

TEST(ProducedPart, ZeroSpringbackIsTheCadPart) {
  const auto& loaded = loaded_part("openamr-MMP.00.00.00.003_Side_panel.step");
  const std::vector<double> zero(loaded.model.segmentation.bends.size(), 0.0);
  const auto part = make_produced_part(loaded.model, loaded.shape, zero);
  ASSERT_TRUE(part) << part.message();
  for (std::size_t i = 0; i < part->mesh.vertices.size(); ++i) {
    ASSERT_LT((part->mesh.vertices[i] - loaded.shape.mesh().vertices[i]).norm(), 1e-12);
  }
  EXPECT_EQ(part->report.root_flange, 6);  // the largest flange, the panel's face
}

TEST(ProducedPart, ClosedHemsStayClosed) {
  const auto& loaded = loaded_part("openamr-MMP.01.00.00.002_Cover_flange.step");
  const std::vector<double> sb(loaded.model.segmentation.bends.size(), 2.0);
  const auto part = make_produced_part(loaded.model, loaded.shape, sb);
  ASSERT_TRUE(part) << part.message();
  EXPECT_EQ(part->report.hems.size(), 3u);
  for (int b : part->report.hems) {
    const auto& truth = part->bends[static_cast<std::size_t>(b)];
    EXPECT_EQ(truth.springback_deg, 0.0);
    EXPECT_EQ(truth.requested_springback_deg, 2.0);
    // The hem's flange moves exactly with the one it is folded onto.
    const auto& Tp = part->flange_transforms[static_cast<std::size_t>(truth.parent_flange)];
    const auto& Tc = part->flange_transforms[static_cast<std::size_t>(truth.child_flange)];
    EXPECT_LT((Tp.matrix() - Tc.matrix()).norm(), 1e-12);
  }
}

TEST(ProducedPart, PositiveSpringbackOpensTheBend) {
  // The nema bracket: one 90 degree bend with a sharp inner corner. Opening it moves the far
  // flange away from the root flange's plane side it was bent towards.
  const auto& loaded = loaded_part("nema-17-bracket.step");
  const auto& seg = loaded.model.segmentation;
  ASSERT_EQ(seg.bends.size(), 1u);
  const auto part = make_produced_part(loaded.model, loaded.shape, {5.0});
  ASSERT_TRUE(part) << part.message();
  const auto& truth = part->bends[0];
  const auto faces = describe_faces(loaded.shape);
  const Plane a =
      fit_side(*part, seg.flanges[static_cast<std::size_t>(truth.parent_flange)], faces);
  const Plane b = fit_side(*part, seg.flanges[static_cast<std::size_t>(truth.child_flange)], faces);
  EXPECT_NEAR(turn_angle_deg(a, b), 85.0, 1e-9);
}

TEST(ProducedPart, LoadCadPartSegmentsAsLoadPartModel) {
  const auto path = analysis::testing::shared_cad("nema-17-bracket.step");
  const auto part = load_cad_part(path);
  const auto model = load_part_model(path);
  ASSERT_TRUE(part && model);
  EXPECT_EQ(part->model.face_count, model->face_count);
  EXPECT_EQ(part->model.samples.size(), model->samples.size());
  ASSERT_EQ(part->model.segmentation.bends.size(), model->segmentation.bends.size());
  EXPECT_EQ(part->model.segmentation.bends[0].nominal_angle_deg,
            model->segmentation.bends[0].nominal_angle_deg);
  EXPECT_FALSE(load_cad_part(path + ".missing"));
}

// A cycle of the flange graph: bend 0 of the motor bracket listed twice. The copy is reached
// second, finds both flanges placed, gets no springback of its own and says how far off it is.
TEST(ProducedPart, ClosingBendOfACycleIsReported) {
  const auto& loaded = loaded_part("openamr-MMP.03.00.00.003_Motor_bracket.step");
  PartModel model = loaded.model;
  Bend copy = model.segmentation.bends[0];
  copy.id = static_cast<int>(model.segmentation.bends.size());
  copy.face_ids.clear();
  model.segmentation.bends.push_back(copy);
  std::vector<double> sb(model.segmentation.bends.size(), 1.0);
  sb[0] = 2.0;
  sb.back() = 0.5;
  const auto part = make_produced_part(model, loaded.shape, sb);
  ASSERT_TRUE(part) << part.message();
  ASSERT_EQ(part->report.closing_bends, std::vector<int>{copy.id});
  const BendTruth& closing = part->bends.back();
  EXPECT_TRUE(closing.closes_cycle);
  EXPECT_EQ(closing.springback_deg, 0.0);
  EXPECT_NEAR(closing.produced_angle_deg, 88.0, 1e-9);  // as bend 0 made it
  EXPECT_NEAR(closing.cycle_error_deg, 88.0 - 89.5, 1e-9);
  EXPECT_FALSE(part->bends[0].closes_cycle);
}

TEST(ProducedPart, RejectsBadInput) {
  const auto& loaded = loaded_part("nema-17-bracket.step");
  EXPECT_FALSE(make_produced_part(loaded.model, loaded.shape, {}));
  EXPECT_FALSE(make_produced_part(loaded.model, CadShape{}, {1.0}));
  ProducedPartSettings bad_root;
  bad_root.root_flange = 9;
  EXPECT_FALSE(make_produced_part(loaded.model, loaded.shape, {1.0}, bad_root));
}

}  // namespace
}  // namespace springscan::parts
