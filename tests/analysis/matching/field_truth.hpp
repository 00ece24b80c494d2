#pragma once
// Ground truth for the deformation field: a CAD part produced with known springback
// (simulators/parts), laser-scanned from a pose, analysed end to end; the truth of every model
// control point is the produced position of its CAD point in the CAD frame, placed by the
// constructed pose and deformation alone (true_result_frame below). Nothing here reads what the
// analysis computed except the report fields under test: an error of the report's result frame
// is part of every field error measured against this truth, not cancelled by it.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "analysis/cad/distance.hpp"
#include "analysis/core/kdtree.hpp"
#include "analysis/inspection/pipeline.hpp"
#include "simulators/parts/cad_profile.hpp"
#include "simulators/parts/laser_scan.hpp"
#include "simulators/parts/produced_part.hpp"
#include "tests/analysis/cad_test_util.hpp"
#include "tests/analysis/under_sanitizer.hpp"

namespace springscan::analysis::testing {

// The same size under the sanitizers (about 10 s a case there instead of 1): the bounds are the
// sub-sample accuracy of a 200k-point scan, which a tenth of the points does not reach.
constexpr std::int64_t kFieldScanPoints = 200'000;

/// A CAD part from a profile (written as BRep, loaded like any CAD file) or the shared folder.
inline const parts::CadPart& field_part(const std::string& name, const parts::ProfileSpec* spec) {
  static std::map<std::string, parts::CadPart> cache;
  if (auto it = cache.find(name); it != cache.end()) return it->second;
  std::string path = shared_cad(name);
  if (spec) {
    path =
        (std::filesystem::temp_directory_path() / ("springscan_field_" + name + ".brep")).string();
    const auto written = parts::write_profile_cad(*spec, path);
    EXPECT_TRUE(written) << written.message();
  }
  auto part = parts::load_cad_part(path);
  EXPECT_TRUE(part) << name << ": " << part.message();
  return cache.emplace(name, part ? std::move(*part) : parts::CadPart{}).first->second;
}

/// `cad`'s model with the exact distance to its CAD surface, as the station loads it
/// (load_part_model); load_cad_part leaves it out. Built once per part.
inline const PartModel& exact_model(const parts::CadPart& cad) {
  static std::map<const parts::CadPart*, PartModel> cache;
  if (auto it = cache.find(&cad); it != cache.end()) return it->second;
  PartModel model = cad.model;
  model.distance = make_cad_distance(cad.shape);
  return cache.emplace(&cad, std::move(model)).first->second;
}

struct FieldScenario {
  std::vector<double> springback_deg;  ///< one per bend (the last value repeats)
  Transform pose = Transform::Identity();
  double noise_mm = 0.02;
  double outliers = 0.0;
  double missing = 0.0;
  std::int64_t points = kFieldScanPoints;
  double tilt_deg = 35.0;  ///< two passes tilted about y (sees vertical walls)
  /// The passes' tilt axis, turned this far from y about z: at 45 deg both passes see walls
  /// facing along x and along y (about y, those facing along y are edge-on).
  double tilt_axis_deg = 0.0;
  bool from_below = false;  ///< the scanner below the part (looking up +z of the part frame)
  std::uint64_t seed = 1;
  /// false: the points alone, as the laser driver delivers them (the pipeline estimates normals
  /// toward its viewpoint, far above +z of the scan frame: the pose must keep the part facing
  /// up there).
  bool scanner_normals = true;
};

/// Errors of one set of vectors against the truth (p95 over the control points it covers).
struct FieldErrors {
  double p95_normal = 0.0, p95_full = 0.0, max_full = 0.0, max_length = 0.0;
  std::size_t vectors = 0;
};

inline double p95(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(std::ceil(0.95 * static_cast<double>(v.size()))) - 1];
}

struct FieldRun {
  v1::InspectionReport report;
  std::vector<Vec3> truth;         ///< per model control point (report index), result frame
  std::vector<Vec3> truth_normal;  ///< the produced surface normal there, result frame
  /// truth scan points (not outliers) within 1.5 mm on the control point's own skin (the CAD
  /// normals within 60 deg): on a solid the other skin, one thickness behind, is not scanned
  /// where this one is
  std::vector<int> scanned_points;
  std::vector<int> control_face;        ///< CAD face id of each control point
  std::vector<Vec3> control;            ///< control points (CAD), by model index
  std::vector<parts::BendTruth> bends;  ///< the produced part's bends (springback applied)
  Transform T_result_part = Transform::Identity();  ///< the report's frame from the part's
  /// The true result frame from the part's (true_result_frame): the truth is placed with it.
  Transform T_truth_part = Transform::Identity();
  /// The largest distance, over the control points, between where the report's frame and the
  /// true one put the produced part: the result frame's own error, mm.
  double frame_error_mm = 0.0;
  std::vector<Vec3> scan_cad_points;  ///< per scan point: the CAD point it is the image of
  std::vector<int> scan_faces;        ///< per scan point: its CAD face, -1 for an outlier
  std::vector<double> deviation;      ///< per scan point: its signed deviation in the report
};

inline Transform from_row_major(const google::protobuf::RepeatedField<double>& m) {
  Transform T = Transform::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) T.matrix()(r, c) = m.Get(4 * r + c);
  return T;
}

/// The result frame the station should report, from the construction alone: identity when
/// nothing sprang back (the produced part is the CAD part, placed by the pose the test chose);
/// otherwise the best fit of the produced surface that the scan sees (`produced`, noise-free, in
/// the part frame) onto the CAD planes of the same material points (`cad`, `cad_normals`), by
/// the objective docs/alignment.md states for the station's frame: point-to-plane, the farthest
/// `trimmed_fraction` of the pairs left out, a Huber weight with corner `huber_mm`. Solved here
/// by Gauss-Newton with Eigen alone, no code of analysis/. A direction the planes leave free
/// (along an extrusion) keeps the part's own value, as the root flange of the produced part
/// keeps its CAD place: the minimum-norm step about the centroid.
inline Transform true_result_frame(const std::vector<Vec3>& produced, const std::vector<Vec3>& cad,
                                   const std::vector<Vec3>& cad_normals,
                                   double trimmed_fraction = 0.0, double huber_mm = 1.0) {
  Transform T = Transform::Identity();
  if (produced.size() < 6) return T;
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : produced) c += p;
  c /= static_cast<double>(produced.size());
  double scale = 0.0;  // rotation unknowns times the part's size: comparable with the shifts
  for (const Vec3& p : produced) scale = std::max(scale, (p - c).norm());
  scale = std::max(scale, 1.0);
  for (int iteration = 0; iteration < 30; ++iteration) {
    std::vector<double> r(produced.size());
    for (std::size_t i = 0; i < produced.size(); ++i)
      r[i] = cad_normals[i].dot(T * produced[i] - cad[i]);
    std::vector<double> magnitude(r.size());
    for (std::size_t i = 0; i < r.size(); ++i) magnitude[i] = std::abs(r[i]);
    const auto keep = static_cast<std::size_t>(
        std::ceil((1.0 - trimmed_fraction) * static_cast<double>(r.size())));
    std::nth_element(magnitude.begin(), magnitude.begin() + static_cast<long>(keep - 1),
                     magnitude.end());
    const double cut = magnitude[keep - 1];
    Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    for (std::size_t i = 0; i < produced.size(); ++i) {
      if (std::abs(r[i]) > cut) continue;
      const Vec3 p = T * produced[i];
      const Vec3& n = cad_normals[i];
      Eigen::Matrix<double, 6, 1> J;
      J << (p - c).cross(n) / scale, n;
      const double w = std::abs(r[i]) <= huber_mm ? 1.0 : huber_mm / std::abs(r[i]);
      A += w * J * J.transpose();
      b -= w * J * r[i];
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(A);
    Eigen::Matrix<double, 6, 1> x = Eigen::Matrix<double, 6, 1>::Zero();
    const double largest = eig.eigenvalues().maxCoeff();
    for (int k = 0; k < 6; ++k)
      if (eig.eigenvalues()(k) > 1e-9 * largest)
        x += eig.eigenvectors().col(k) * (eig.eigenvectors().col(k).dot(b) / eig.eigenvalues()(k));
    const Vec3 w = x.head<3>() / scale;
    const Transform step =
        Eigen::Translation3d(c + x.tail<3>()) *
        Eigen::AngleAxisd(w.norm(), w.norm() > 0 ? w.normalized() : Vec3::UnitZ()) *
        Eigen::Translation3d(-c);
    T = step * T;
    if (w.norm() * scale < 1e-9 && x.tail<3>().norm() < 1e-9) break;
  }
  return T;
}

/// Produces, scans and analyses `part`; fills the truth of every control point the report has.
inline FieldRun run_field_case(const parts::CadPart& cad, const FieldScenario& sc,
                               const v1::AnalysisSettings& settings = {}) {
  FieldRun run;
  std::vector<double> sb(cad.model.segmentation.bends.size(), sc.springback_deg.back());
  for (std::size_t k = 0; k < sb.size() && k < sc.springback_deg.size(); ++k)
    sb[k] = sc.springback_deg[k];
  auto part = parts::make_produced_part(cad.model, cad.shape, sb);
  EXPECT_TRUE(part) << part.message();
  if (!part) return run;
  parts::LaserScanSettings ls;
  ls.point_count = sc.points / 2;
  ls.noise_sigma_mm = sc.noise_mm;
  ls.outlier_fraction = sc.outliers;
  ls.missing_fraction = sc.missing;
  ls.T_scan_part = sc.pose;
  // Lines at a slant to the part's edges, as a part lies on the station: every line crosses
  // an edge at its own offset.
  ls.line_direction = Vec3(0.35, 1.0, 0.0).normalized();
  ls.threads = 2;
  parts::LaserScan scan;
  const double tilt = sc.tilt_deg * std::numbers::pi / 180.0;
  for (int side : {1, -1}) {
    const double axis = sc.tilt_axis_deg * std::numbers::pi / 180.0;
    ls.view_direction =
        Vec3(side * std::sin(tilt) * std::cos(axis), side * std::sin(tilt) * std::sin(axis),
             (sc.from_below ? 1.0 : -1.0) * std::cos(tilt));
    ls.seed = sc.seed * 2 + static_cast<std::uint64_t>(side + 1);
    auto pass = parts::laser_scan(*part, ls);
    EXPECT_TRUE(pass) << pass.message();
    if (!pass) return run;
    const auto append = [](auto& to, const auto& from) {
      to.insert(to.end(), from.begin(), from.end());
    };
    append(scan.cloud.points, pass->cloud.points);
    append(scan.cloud.normals, pass->cloud.normals);  // toward the scanner, as a scanner gives
    append(scan.cad_points, pass->cad_points);
    append(scan.outlier, pass->outlier);
    append(scan.cloud.face_ids, pass->cloud.face_ids);
  }
  // The CAD normal of every scan point (the produced normal taken back by its material's motion).
  std::vector<Vec3> cad_normal(scan.cad_points.size());
  for (std::size_t j = 0; j < cad_normal.size(); ++j)
    cad_normal[j] =
        part->local_transform(scan.cad_points[j], scan.cloud.face_ids[j]).linear().transpose() *
        (sc.pose.linear().transpose() * scan.cloud.normals[j]);
  // The true result frame, from the seen material (every 4th point is plenty for 6 unknowns).
  bool sprang = false;
  for (const parts::BendTruth& b : part->bends) sprang = sprang || b.springback_deg != 0.0;
  if (sprang) {
    // Evenly over the seen area (the best fit's measure is the surface, not the scan's density,
    // which two passes double where they overlap): one point per 1 mm cell of the CAD frame.
    std::vector<Vec3> produced, cad_at, normal_at;
    std::set<std::tuple<long, long, long>> cells;
    for (std::size_t j = 0; j < scan.cad_points.size(); ++j) {
      if (scan.outlier[j]) continue;
      const Vec3& m = scan.cad_points[j];
      if (!cells.emplace(std::lround(m.x()), std::lround(m.y()), std::lround(m.z())).second)
        continue;
      produced.push_back(part->produced(scan.cad_points[j], scan.cloud.face_ids[j]));
      cad_at.push_back(scan.cad_points[j]);
      normal_at.push_back(cad_normal[j]);
    }
    run.T_truth_part = true_result_frame(produced, cad_at, normal_at);
  }
  run.scan_faces = scan.cloud.face_ids;
  for (std::size_t j = 0; j < run.scan_faces.size(); ++j)
    if (scan.outlier[j]) run.scan_faces[j] = -1;
  scan.cloud.face_ids.clear();
  if (!sc.scanner_normals) scan.cloud.normals.clear();
  auto outcome = run_inspection(exact_model(cad), scan.cloud, settings);
  EXPECT_TRUE(outcome) << outcome.message();
  if (!outcome) return run;
  run.report = std::move(outcome->report);
  run.deviation = std::move(outcome->deviation_cloud.scalars);
  run.scan_cad_points = scan.cad_points;
  // The result frame: the datums' when the part has them, else the best fit (both the same
  // then).
  const Transform T_result_part = from_row_major(run.report.alignment().transform()) * sc.pose;
  run.T_result_part = T_result_part;
  run.bends = part->bends;

  // Control points: the report's model points (k-center picks of the model samples).
  const auto& field = run.report.deformation_field();
  run.control.assign(static_cast<std::size_t>(field.model_points()), Vec3::Zero());
  for (const auto& v : field.matching())
    run.control[static_cast<std::size_t>(v.model_index())] =
        Vec3(v.model().x(), v.model().y(), v.model().z());
  for (const auto& v : field.vectors())
    run.control[static_cast<std::size_t>(v.model_index())] =
        Vec3(v.model().x(), v.model().y(), v.model().z());
  const KdTree samples(cad.model.samples.points);
  std::vector<Vec3> seen, seen_normal;
  for (std::size_t j = 0; j < scan.cad_points.size(); ++j) {
    if (scan.outlier[j]) continue;
    seen.push_back(scan.cad_points[j]);
    seen_normal.push_back(cad_normal[j]);
  }
  const KdTree seen_tree(seen);
  std::vector<Neighbor> near;
  for (const Vec3& m : run.control) {
    const std::size_t k = samples.nearest(m)->index;
    const int face = cad.model.samples.face_ids[k];
    const Transform local = part->local_transform(m, face);
    run.truth.push_back(run.T_truth_part * (local * m));
    run.truth_normal.push_back(run.T_truth_part.linear() * local.linear() *
                               cad.model.samples.normals[k]);
    run.frame_error_mm =
        std::max(run.frame_error_mm, ((T_result_part * (local * m)) - run.truth.back()).norm());
    seen_tree.radius(m, 1.5, near);
    const Vec3& n = cad.model.samples.normals[k];
    // A shell has one surface, seen from either side; a solid's skins face away from each other.
    const auto same_skin = [&](const Neighbor& q) {
      const double c = seen_normal[q.index].dot(n);
      return (part->solid ? c : std::abs(c)) > 0.5;
    };
    run.scanned_points.push_back(
        static_cast<int>(std::count_if(near.begin(), near.end(), same_skin)));
    run.control_face.push_back(face);
  }
  return run;
}

inline Vec3 vec(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

/// Errors of `vectors` (model_index, scan) against the truth; `in_report_frame`: against the
/// truth carried into the report's own result frame, so that the frame's error cancels and only
/// the field's shape is measured (never alone: beside the errors in the true frame).
inline FieldErrors field_errors(const FieldRun& run,
                                const google::protobuf::RepeatedPtrField<v1::Correspondence>& vs,
                                bool in_report_frame = false) {
  FieldErrors e;
  std::vector<double> normal, full;
  const Transform to_report = in_report_frame
                                  ? Transform(run.T_result_part * run.T_truth_part.inverse())
                                  : Transform::Identity();
  for (const auto& v : vs) {
    const std::size_t i = static_cast<std::size_t>(v.model_index());
    const Vec3 err = vec(v.scan()) - to_report * run.truth[i];
    normal.push_back(std::abs(err.dot(to_report.linear() * run.truth_normal[i])));
    full.push_back(err.norm());
    e.max_full = std::max(e.max_full, err.norm());
    e.max_length = std::max(e.max_length, (vec(v.scan()) - vec(v.model())).norm());
  }
  e.p95_normal = p95(normal);
  e.p95_full = p95(full);
  e.vectors = full.size();
  return e;
}

// The part's half turn about its sheet normal, from the CAD alone: turned half round about the
// axis of least spread of its samples through the centre of their bounding box, then settled on
// the CAD as a best fit settles a rival orientation (point-to-plane updates with field_truth.hpp's
// Eigen solver on the nearest CAD points, the farthest fifth left out).
inline Transform settled_half_turn(const parts::CadPart& cad) {
  const std::vector<Vec3>& samples = cad.model.samples.points;
  Vec3 lo = samples.front(), hi = samples.front(), mean = Vec3::Zero();
  for (const Vec3& p : samples) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    mean += p;
  }
  mean /= static_cast<double>(samples.size());
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
  for (const Vec3& p : samples) spread += (p - mean) * (p - mean).transpose();
  const Vec3 normal = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(spread).eigenvectors().col(0);
  const Vec3 centre = 0.5 * (lo + hi);
  Transform turn = Eigen::Translation3d(centre) * Eigen::AngleAxisd(std::numbers::pi, normal) *
                   Eigen::Translation3d(-centre);
  const SurfaceDistance& distance = *exact_model(cad).distance;
  std::vector<Vec3> turned;
  for (const Vec3& p : samples) turned.push_back(turn * p);
  for (int round = 0; round < 30; ++round) {
    const std::vector<SurfaceHit> hits = closest_all(distance, turned);
    std::vector<Vec3> feet(hits.size()), normals(hits.size());
    for (std::size_t k = 0; k < hits.size(); ++k) {
      feet[k] = hits[k].foot;
      normals[k] = hits[k].normal;
    }
    const Transform step = true_result_frame(turned, feet, normals, 0.2, 0.2);
    for (Vec3& p : turned) p = step * p;
    turn = step * turn;
  }
  return turn;
}

// How many scan points can tell a near-symmetric part from its half turn, from the construction
// alone: the CAD point each scan point is the image of (the simulator's, noise-free; outliers
// left out) lies farther than 0.15 mm off the CAD once turned. The side panel's notched wall
// (face 73) gives 39 such points in the passes tilted about the diagonal, its turned copy none
// elsewhere; a view that leaves none cannot tell the two, and the part must be reported
// ambiguous (production_parts_test.cpp; bench/accuracy_sweep counts ambiguous draws whose view
// shows the asymmetry).
inline int points_telling_the_half_turn(const FieldRun& run, const parts::CadPart& cad) {
  static std::map<const parts::CadPart*, Transform> turns;
  if (!turns.count(&cad)) turns.emplace(&cad, settled_half_turn(cad));
  const Transform& turn = turns.at(&cad);
  std::vector<Vec3> turned;
  for (std::size_t i = 0; i < run.scan_cad_points.size(); ++i)
    if (run.scan_faces[i] >= 0) turned.push_back(turn * run.scan_cad_points[i]);
  int telling = 0;
  for (const SurfaceHit& hit : closest_all(*exact_model(cad).distance, turned))
    if (std::abs(hit.signed_distance_mm) > 0.15) ++telling;
  return telling;
}

}  // namespace springscan::analysis::testing
