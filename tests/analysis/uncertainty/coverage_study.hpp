#pragma once
// The calibration study of the expanded uncertainties (docs/uncertainty.md, issue 41): parts
// with known springback, curl and radius from the simulators (simulators/parts), scanned at new
// seeds and poses, analysed end to end (run_inspection, as the station), every reported value
// with its U compared with the truth of the construction. Nothing here reads analysis code's
// figures except the report fields under test. Shared by the test
// (tests/analysis/uncertainty/uncertainty_test.cpp) and bench/uncertainty_sweep.cpp.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "analysis/core/kdtree.hpp"
#include "analysis/inspection/pipeline.hpp"
#include "simulators/parts/produced_part.hpp"
#include "simulators/parts/shaped_profile.hpp"
#include "simulators/parts/sheet_part.hpp"
#include "tests/analysis/matching/field_truth.hpp"
#include "tests/analysis/synthetic.hpp"

namespace springscan::analysis::testing {

/// One reported value against its truth.
struct CoverageSample {
  std::string kind;    ///< "springback", "station angle", "bend radius", "curl radius"
  std::string family;  ///< how the part was made and seen
  double error = 0.0;  ///< measured - true
  double U = 0.0;      ///< its expanded uncertainty as reported
  std::string note;    ///< which part and frame (production), for the sweep's listing
};

/// What a study's cases gave: the samples, and the cases left out because the station reported
/// its fit ambiguous (it fails such a part; its bend table may be the turned copy's). Counted,
/// never skipped silently: the test asserts their number (issue 39's rule).
struct CoverageStudy {
  std::vector<CoverageSample> samples;
  int ambiguous = 0;
  std::vector<std::string> ambiguous_cases;  ///< "family: part" of each
};

/// Coverage of one (kind, family): the share with |error| <= U, the median U and 2 rms error.
struct CoverageRow {
  std::string kind, family;
  std::size_t values = 0;
  double covered = 0.0;  ///< share, 0..1
  double median_U = 0.0;
  double two_rms_error = 0.0;
};

inline std::vector<CoverageRow> coverage_table(const std::vector<CoverageSample>& samples) {
  std::map<std::pair<std::string, std::string>, std::vector<const CoverageSample*>> groups;
  for (const CoverageSample& s : samples) groups[{s.kind, s.family}].push_back(&s);
  std::vector<CoverageRow> rows;
  for (const auto& [key, group] : groups) {
    CoverageRow row{key.first, key.second, group.size()};
    std::vector<double> u;
    double sum2 = 0.0, in = 0.0;
    for (const CoverageSample* s : group) {
      in += std::abs(s->error) <= s->U ? 1.0 : 0.0;
      sum2 += s->error * s->error;
      u.push_back(s->U);
    }
    std::sort(u.begin(), u.end());
    row.covered = in / static_cast<double>(group.size());
    row.median_U = u[u.size() / 2];
    row.two_rms_error = 2.0 * std::sqrt(sum2 / static_cast<double>(group.size()));
    rows.push_back(row);
  }
  return rows;
}

inline void print_table(const std::vector<CoverageRow>& rows) {
  std::printf("| kind | family | values | covered | median U | 2 rms error |\n");
  std::printf("| --- | --- | ---: | ---: | ---: | ---: |\n");
  for (const CoverageRow& r : rows)
    std::printf("| %s | %s | %zu | %.1f %% | %.4f | %.4f |\n", r.kind.c_str(), r.family.c_str(),
                r.values, 100.0 * r.covered, r.median_U, r.two_rms_error);
}

/// A shaped profile case: the kind of flange and view it stands for.
enum class ProfileFamily { kClean, kNoisy, kCurled, kShortFlange };

inline const char* family_name(ProfileFamily f) {
  switch (f) {
    case ProfileFamily::kClean:
      return "profile sigma 0.02";
    case ProfileFamily::kNoisy:
      return "profile sigma 0.05 + 2 % outliers";
    case ProfileFamily::kCurled:
      return "profile, curled wall";
    case ProfileFamily::kShortFlange:
      return "profile, short flange";
  }
  return "?";
}

/// One random open surface profile, springback 0-3 deg per bend, scanned
/// with the scanner's normals in a random pose near the fixture's (the station's placement),
/// analysed; its values appended to `out`. `points`: scan points.
inline void run_profile_case(ProfileFamily family, std::mt19937_64& rng, std::int64_t points,
                             CoverageStudy& study) {
  std::vector<CoverageSample>& out = study.samples;
  std::uniform_real_distribution<double> length(25, 60), radius(2, 6), angle(60, 95), unit(0, 1),
      springback(0.0, 3.0);
  // 2-4 flanges of their own lengths, turns either way: no two orientations alike (a symmetric
  // profile's bends could swap under the best fit, and the study would compare the wrong ones).
  parts::ProfileSpec spec;
  const int n = 2 + static_cast<int>(rng() % 3);
  for (int k = 0; k < n; ++k) spec.flange_lengths_mm.push_back(length(rng));
  for (int k = 0; k + 1 < n; ++k) {
    spec.bend_angles_deg.push_back((unit(rng) < 0.5 ? -1.0 : 1.0) * angle(rng));
    spec.bend_radii_mm.push_back(radius(rng));
  }
  spec.width_mm = 60.0 + 60.0 * unit(rng);
  const std::size_t bends = spec.bend_angles_deg.size(), flanges = bends + 1;
  if (family == ProfileFamily::kShortFlange)  // a tab of 8-12 mm at one end
    spec.flange_lengths_mm[unit(rng) < 0.5 ? 0 : flanges - 1] = 8.0 + 4.0 * unit(rng);
  parts::ProfileShape shape;
  for (std::size_t b = 0; b < bends; ++b) shape.springback_deg.push_back(springback(rng));
  if (family == ProfileFamily::kCurled) {
    shape.curl_radius_mm.assign(flanges, 0.0);
    // An inner flange (a wall) of a U, Z or hat; the second flange of an L.
    const std::size_t wall = flanges == 2 ? 1 : 1 + rng() % (flanges - 2);
    shape.curl_radius_mm[wall] = (unit(rng) < 0.5 ? -1.0 : 1.0) * (300.0 + 1200.0 * unit(rng));
  }
  const auto model = parts::profile_part_model(spec, {.sample_count = 20000});
  ASSERT_TRUE(model) << model.message();
  parts::ScanSimulationSettings st;
  st.point_count = points;
  st.noise_sigma_mm = family == ProfileFamily::kNoisy ? 0.05 : 0.02;
  st.outlier_fraction = family == ProfileFamily::kNoisy ? 0.02 : 0.0;
  st.with_normals = true;
  st.seed = rng();
  // The part lies in the fixture within a few degrees and millimetres.
  std::normal_distribution<double> g;
  const Vec3 axis = Vec3(g(rng), g(rng), g(rng)).normalized();
  st.T_scan_part = Eigen::Translation3d(3.0 * Vec3(g(rng), g(rng), g(rng))) *
                   Eigen::AngleAxisd(3.0 * std::numbers::pi / 180.0 * unit(rng), axis);
  const auto scan = parts::simulate_shaped_scan(spec, shape, st);
  ASSERT_TRUE(scan) << scan.message();
  const auto outcome = run_inspection(*model, *scan);
  ASSERT_TRUE(outcome) << outcome.message();
  const v1::InspectionReport& report = outcome->report;
  const std::string name = family_name(family);
  if (report.global_fit().ambiguous()) {  // the part must fail; its bends are not judged
    ++study.ambiguous;
    study.ambiguous_cases.push_back(name);
    return;
  }
  const double mid = 0.5 * spec.width_mm;
  for (const v1::Bend& b : report.bends()) {
    if (!b.measured()) continue;
    const int k = b.id();
    const double nominal = std::abs(spec.bend_angles_deg[static_cast<std::size_t>(k)]);
    const double truth = nominal - parts::shaped_bend_angle_deg(spec, shape, k, mid);
    out.push_back(
        {"springback", name, b.springback_deg() - truth, b.springback_uncertainty_deg(), ""});
    // Station positions run along the bend's axis direction from its mid-width point.
    const double sign = b.axis_direction().y() < 0.0 ? -1.0 : 1.0;
    for (const v1::BendStation& s : b.angle_along_bend()) {
      const double y = mid + sign * s.position_mm();
      out.push_back({"station angle", name,
                     s.angle_deg() - parts::shaped_bend_angle_deg(spec, shape, k, y),
                     s.angle_uncertainty_deg(), ""});
    }
    if (b.has_measured_radius_mm() && b.measured_radius_mm() > 0.0)
      out.push_back({"bend radius", name,
                     b.measured_radius_mm() - spec.bend_radii_mm[static_cast<std::size_t>(k)],
                     b.radius_uncertainty_mm(), ""});
  }
  for (const v1::Segment& s : report.segments()) {
    const auto f = static_cast<std::size_t>(s.id());
    if (!s.has_curl_radius_mm() || f >= shape.curl_radius_mm.size() ||
        shape.curl_radius_mm[f] == 0.0)
      continue;
    out.push_back({"curl radius", name,
                   std::abs(s.curl_radius_mm()) - std::abs(shape.curl_radius_mm[f]),
                   s.curl_radius_uncertainty_mm(), ""});
  }
}

/// How a production solid is seen.
enum class ProductionView {
  kTwoPasses,  ///< two passes tilted 35 deg about a diagonal: walls along x and y seen
  kOneSided,   ///< one pass straight from above: walls edge-on
  kFromBelow,  ///< two tilted passes from below (the scanner's own normals)
};

/// The rotation angle of a rigid motion (degrees).
inline double turn_deg(const Transform& T) {
  return Eigen::AngleAxisd(T.linear()).angle() * 180.0 / std::numbers::pi;
}

/// The 95th percentile of |d| (as the station's deviation statistic: the value at rank
/// floor(0.95 (n - 1)) of the sorted magnitudes).
inline double p95_abs(std::vector<double> d) {
  if (d.empty()) return 0.0;
  for (double& x : d) x = std::abs(x);
  const auto k = static_cast<std::size_t>(0.95 * static_cast<double>(d.size() - 1));
  std::nth_element(d.begin(), d.begin() + static_cast<long>(k), d.end());
  return d[k];
}

/// A production solid (../shared/data/cad) with springback 0-3 deg per bend, laser-scanned in
/// a random pose as `view` says, analysed. Appended to `study`: each bend's springback; the
/// result frame's turn and largest move against the true frame (field_truth.hpp); the surface
/// statistic (p95 of |d|) against the same statistic of the produced part's noise-free surface
/// at the scan's points in the true frame; each trim edge's strips (in plane, across) against
/// the produced edge, in the true frame.
inline void run_production_case(const std::string& part, double noise_mm, ProductionView view,
                                std::mt19937_64& rng, std::int64_t points, CoverageStudy& study) {
  std::vector<CoverageSample>& out = study.samples;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const parts::CadPart& cad = field_part(part, nullptr);
  FieldScenario sc;
  for (std::size_t b = 0; b < cad.model.segmentation.bends.size(); ++b)
    sc.springback_deg.push_back(3.0 * unit(rng));
  if (sc.springback_deg.empty()) sc.springback_deg.push_back(0.0);
  std::mt19937 pose_rng(static_cast<std::uint32_t>(rng()));
  sc.pose = random_motion(pose_rng, 500.0);
  sc.tilt_axis_deg = 45.0;
  sc.tilt_deg = view == ProductionView::kOneSided ? 0.0 : 35.0;
  sc.from_below = view == ProductionView::kFromBelow;
  sc.noise_mm = noise_mm;
  sc.outliers = noise_mm > 0.03 ? 0.02 : 0.0;
  sc.points = points;
  sc.seed = rng() % 100000;
  const FieldRun run = run_field_case(cad, sc);
  char family[96];
  std::snprintf(family, sizeof family, "production, sigma %.2f%s%s", noise_mm,
                sc.outliers > 0 ? " + 2 % outliers" : "",
                view == ProductionView::kOneSided    ? ", one-sided view"
                : view == ProductionView::kFromBelow ? ", from below"
                                                     : "");
  if (run.report.global_fit().ambiguous()) {  // its bend table may be the mirror's
    ++study.ambiguous;
    study.ambiguous_cases.push_back(std::string(family) + ": " + part);
    return;
  }
  const std::string note = part + ", " + run.report.alignment().method() + " frame";
  // The result frame: its largest move against the true frame (field_truth.hpp), a magnitude,
  // and its turn.
  out.push_back({"frame translation", family, run.frame_error_mm,
                 run.report.alignment().uncertainty_translation_mm(), note});
  out.push_back({"frame rotation", family, turn_deg(run.T_result_part * run.T_truth_part.inverse()),
                 run.report.alignment().uncertainty_rotation_deg(), note});
  for (const parts::BendTruth& truth : run.bends) {
    if (truth.hem) continue;
    for (const v1::Bend& b : run.report.bends())
      if (b.id() == truth.bend_id && b.measured())
        out.push_back({"springback", family, b.springback_deg() - truth.springback_deg,
                       b.springback_uncertainty_deg(), note});
  }
  // The produced part again (deterministic: the same springback as run_field_case's).
  std::vector<double> sb(cad.model.segmentation.bends.size(), sc.springback_deg.back());
  for (std::size_t k = 0; k < sb.size() && k < sc.springback_deg.size(); ++k)
    sb[k] = sc.springback_deg[k];
  const auto produced = parts::make_produced_part(cad.model, cad.shape, sb);
  if (!produced) return;
  const KdTree samples(cad.model.samples.points);
  // The surface statistic: the produced surface where the scan saw it (every 4th point), in
  // the true frame, by its exact distance to the CAD surface as the statistic defines it (the
  // nearest surface, positive along its outward normal; a sprung flange's tip may come nearer
  // the other skin than its own).
  const PartModel& exact = exact_model(cad);
  std::vector<double> truth_d;
  for (std::size_t j = 0; j < run.scan_faces.size(); j += 4) {
    const int face = run.scan_faces[j];
    if (face < 0 || !exact.distance) continue;
    const Vec3 x = run.T_truth_part * produced->produced(run.scan_cad_points[j], face);
    truth_d.push_back(exact.distance->closest(x).signed_distance_mm);
  }
  const v1::Deviation& d = run.report.deviation();
  if (!truth_d.empty() && d.uncertainty_mm() > 0.0)
    out.push_back({"deviation p95", family, d.p95() - p95_abs(truth_d), d.uncertainty_mm(), note});
  // Trim edges: the material at each strip's CAD edge point, as produced, in the true frame.
  for (const v1::Segment& seg : run.report.segments())
    for (const v1::EdgeDeviation& e : seg.trim_edges()) {
      if (e.uncertainty_mm() <= 0.0) continue;
      const Vec3 outward(e.outward().x(), e.outward().y(), e.outward().z());
      const Vec3 along(e.direction().x(), e.direction().y(), e.direction().z());
      const Vec3 normal = along.cross(outward).normalized();
      for (int k = 0; k < e.cad_edge_size() && k < e.scan_edge_size(); ++k) {
        const Vec3 c(e.cad_edge(k).x(), e.cad_edge(k).y(), e.cad_edge(k).z());
        const Vec3 m(e.scan_edge(k).x(), e.scan_edge(k).y(), e.scan_edge(k).z());
        const int face = cad.model.samples.face_ids[samples.nearest(c)->index];
        const Vec3 truth = run.T_truth_part * produced->produced(c, face);
        out.push_back(
            {"edge in plane", family, (m - truth).dot(outward), e.in_plane_uncertainty_mm(), note});
        out.push_back(
            {"edge across", family, (m - truth).dot(normal), e.across_uncertainty_mm(), note});
      }
    }
}

}  // namespace springscan::analysis::testing
