// The inspection pipeline (DESIGN.md "Analysis pipeline"): one commented line per stage.
#include "analysis/inspection/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <tuple>
#include <utility>

#include "analysis/core/kdtree.hpp"
#include "analysis/core/parallel.hpp"
#include "analysis/core/spatial_order.hpp"
#include "analysis/deviation/deviation.hpp"
#include "analysis/inspection/verdict.hpp"
#include "analysis/matching/compensation.hpp"
#include "analysis/matching/deformation_field.hpp"
#include "analysis/matching/field_refinement.hpp"
#include "analysis/messages/alignment_proto.hpp"
#include "analysis/messages/cad_model_proto.hpp"
#include "analysis/messages/fit_proto.hpp"
#include "analysis/messages/matching_proto.hpp"
#include "analysis/messages/settings_proto.hpp"
#include "analysis/messages/springback_proto.hpp"
#include "analysis/messages/uncertainty_proto.hpp"
#include "analysis/messages/verdict_proto.hpp"
#include "analysis/preprocess/normals.hpp"
#include "analysis/preprocess/reduction.hpp"
#include "analysis/registration/datum.hpp"
#include "analysis/registration/facing.hpp"
#include "analysis/registration/global_fit.hpp"
#include "analysis/registration/orientation_settle.hpp"
#include "analysis/uncertainty/frame_uncertainty.hpp"
#include "analysis/uncertainty/uncertainty.hpp"

namespace springscan::analysis {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Every stage's settings, from the C++ defaults plus the proto overrides.
struct PipelineSettings {
  NormalSettings normals;
  ReductionSettings reduction;
  GlobalFitSettings global_fit;
  DatumAlignmentSettings alignment;
  DeviationSettings deviation;
  SpringbackSettings springback;
  DeformationFieldSettings field;
  CompensationSettings compensation;
  VerdictSettings verdict;
  UncertaintySettings uncertainty;
  int threads = 0;
};

Expected<PipelineSettings> load_settings(const v1::AnalysisSettings& m) {
  PipelineSettings s;
  auto threads = threads_from_proto(m);
  auto normals = from_proto(m.normals());
  auto reduction = from_proto(m.reduction());
  auto fit = from_proto(m.registration());
  auto alignment = from_proto(m.alignment());
  auto springback = from_proto(m.springback());
  auto field = from_proto(m.deformation_field());
  auto compensation = from_proto(m.compensation());
  // Every tolerance, the deviation section's tolerance_mm included, is the verdict's.
  auto verdict = verdict_settings_from_proto(m);
  auto uncertainty = from_proto(m.uncertainty());
  for (const std::string* error :
       {threads ? nullptr : &threads.message(), normals ? nullptr : &normals.message(),
        reduction ? nullptr : &reduction.message(), fit ? nullptr : &fit.message(),
        alignment ? nullptr : &alignment.message(), springback ? nullptr : &springback.message(),
        field ? nullptr : &field.message(), compensation ? nullptr : &compensation.message(),
        verdict ? nullptr : &verdict.message(), uncertainty ? nullptr : &uncertainty.message()})
    if (error) return fail(*error);
  s.threads = *threads;
  s.normals = *normals;
  s.reduction = *reduction;
  s.global_fit = *fit;
  s.alignment = *alignment;
  s.springback = *springback;
  s.field = *field;
  s.compensation = *compensation;
  s.verdict = *verdict;
  s.uncertainty = *uncertainty;
  s.springback.threads = s.field.refinement.threads = s.threads;
  s.normals.threads = s.global_fit.icp.threads = s.global_fit.pca.threads = s.threads;
  s.global_fit.boundary.threads = s.threads;
  s.deviation.threads = s.reduction.curvature.threads = s.alignment.threads = s.threads;
  return s;
}

// report.settings: the overrides as given (other stages' sections kept), ours with defaults.
void record_settings(const PipelineSettings& s, const v1::AnalysisSettings& given,
                     v1::AnalysisSettings* out) {
  *out = given;
  to_proto(s.normals, out->mutable_normals());
  to_proto(s.reduction, out->mutable_reduction());
  to_proto(s.global_fit, out->mutable_registration());
  to_proto(s.alignment, out->mutable_alignment());
  // deviation.tolerance_mm is the older spelling of verdict.tolerance_mm: both show the value
  // in force, so a reader of either sees the tolerance the part was judged by.
  out->mutable_deviation()->set_tolerance_mm(s.verdict.tolerance_mm);
  to_proto(s.springback, out->mutable_springback());
  to_proto(s.field, out->mutable_deformation_field());
  to_proto(s.compensation, out->mutable_compensation());
  to_proto(s.verdict, out->mutable_verdict());
  to_proto(s.uncertainty, out->mutable_uncertainty());
  out->set_threads(s.threads);
}

// Refuses what no fit can use (an error); warns about what makes a fit doubtful (a report
// warning, the analysis goes on).
std::optional<Error> check_inputs(const PartModel& model, const PointCloud& scan,
                                  v1::InspectionReport& report) {
  if (scan.empty()) return fail("scan: no points");
  if (scan.size() < 3)
    return fail("scan: needs at least 3 points, got " + std::to_string(scan.size()));
  if (model.samples.size() < 3) return fail("model: fewer than 3 samples");
  if (!all_finite(scan.points)) return fail("scan: non-finite (NaN/inf) coordinates");
  if (!all_finite(model.samples.points)) return fail("model: non-finite (NaN/inf) coordinates");
  if (model.samples.normals.size() != model.samples.size())
    return fail("model: the samples need normals (" + std::to_string(model.samples.normals.size()) +
                " for " + std::to_string(model.samples.size()) + " points)");
  const auto [slo, shi] = bounding_box(scan.points);
  const auto [mlo, mhi] = bounding_box(model.samples.points);
  const double scan_size = (shi - slo).norm(), model_size = (mhi - mlo).norm();
  const double ratio =
      std::max(scan_size, model_size) / std::max(std::min(scan_size, model_size), 1e-12);
  std::ostringstream text;
  text << "scan extent " << scan_size << " mm vs model extent " << model_size << " mm (ratio "
       << ratio << ")";
  if (ratio >= 100.0)
    return fail(text.str() +
                ": the scan and the model are probably in different units (mm vs m "
                "or inch); convert one of them");
  if (ratio >= 5.0)
    report.add_warnings(text.str() + ": a partial scan, or different units (inch vs mm?)");
  return std::nullopt;
}

// The scan in the CAD frame (core transformed(), on `threads` threads: a 1M-point scan).
PointCloud scan_in_frame(const PointCloud& scan, const Transform& T, int threads) {
  PointCloud out = scan;
  const Mat3 R = T.linear();
  const bool normals = out.normals.size() == out.size();
  parallel_blocks(out.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) out.points[i] = T * out.points[i];
    if (normals)
      for (std::size_t i = begin; i < end; ++i) out.normals[i] = R * out.normals[i];
  });
  if (!normals)
    for (auto& n : out.normals) n = R * n;
  return out;
}

// deviation.ply content: scan in the CAD frame, signed deviation and its colour.
PointCloud deviation_cloud(PointCloud scan_in_cad, const DeviationResult& deviation,
                           double color_scale_mm, int threads) {
  scan_in_cad.scalars = deviation.signed_distance_mm;
  scan_in_cad.colors.resize(scan_in_cad.size());
  parallel_blocks(
      scan_in_cad.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i)
          scan_in_cad.colors[i] = deviation_color(scan_in_cad.scalars[i], color_scale_mm);
      });
  return scan_in_cad;
}

// The diagonal of the points' extent: the length a calibration's length error spreads over.
double part_extent_mm(const PointCloud& cloud) {
  if (cloud.empty()) return 0.0;
  const auto [lo, hi] = bounding_box(cloud.points);
  return (hi - lo).norm();
}

// Stages 6-7: local best fits of the CAD flanges and the bend table (docs/springback.md). A
// model without flanges has no bends to measure; a model the stage cannot use (no face ids)
// gives a warning rather than failing the whole inspection.
// Returns the stage's result for the deformation field (its flange motions) and the verdict
// (its bends), if it ran.
std::optional<SpringbackResult> add_bend_table(const PartModel& model,
                                               const PointCloud& scan_in_cad,
                                               const PipelineSettings& settings,
                                               const FrameUncertainty& frame_u,
                                               v1::InspectionReport& report) {
  if (model.segmentation.flanges.empty()) return std::nullopt;
  auto result = measure_springback(model, scan_in_cad, settings.springback);
  if (!result) {
    report.add_warnings(result.message());
    return std::nullopt;
  }
  // 7b. The expanded uncertainty of every value it measured (docs/uncertainty.md).
  attach_uncertainty(
      estimate_uncertainty(*result, part_extent_mm(scan_in_cad), settings.uncertainty), *result,
      &frame_u);
  fill_springback_report(*result, report);
  for (const BendMeasurement& bend : result->bends)
    if (!bend.measured) report.add_warnings(bend.status);
  return std::move(result).value();
}

// The sample normal and face id of each k-center model point (they are model samples).
void control_point_attributes(const PartModel& model, const KdTree& model_tree,
                              const std::vector<Vec3>& centers, std::vector<Vec3>& normals,
                              std::vector<int>& faces) {
  normals.resize(centers.size());
  faces.assign(centers.size(), -1);
  for (std::size_t i = 0; i < centers.size(); ++i) {
    const std::size_t k = model_tree.nearest(centers[i])->index;
    normals[i] = model.samples.normals[k];
    if (k < model.samples.face_ids.size()) faces[i] = model.samples.face_ids[k];
  }
}

// Stages 8-9: the deformation field between the k-center-reduced model and scan (paper §5,
// exact matching with its certificate), refined to sub-sample accuracy with the flanges'
// motions and the scan's local surface, and the compensation vectors at the k-center model
// points (docs/matching.md). Returns the field's coverage for the verdict.
Expected<FieldCoverage> add_deformation(const PartModel& model, const KdTree& model_tree,
                                        const ReductionOutcome& reduced,
                                        const Transform& T_cad_scan, const PointCloud& scan_in_cad,
                                        const SpringbackResult* springback,
                                        const PipelineSettings& s, InspectionOutcome& out) {
  v1::InspectionReport& report = out.report;
  std::vector<Vec3> scan_centers;
  scan_centers.reserve(reduced.scan_centers.size());
  for (const Vec3& p : reduced.scan_centers) scan_centers.push_back(T_cad_scan * p);
  auto raw = deformation_field(reduced.model_centers, scan_centers, s.field);
  if (!raw) return raw.error();
  std::vector<Vec3> normals;
  std::vector<int> faces;
  control_point_attributes(model, model_tree, reduced.model_centers, normals, faces);
  // Where the scanner looked from, for normals the refinement estimates (a points-only scan).
  const Vec3 viewpoint = T_cad_scan * s.normals.viewpoint;
  const FieldRefinementInput input{reduced.model_centers,
                                   normals,
                                   faces,
                                   model.segmentation,
                                   springback,
                                   scan_in_cad.points,
                                   model.samples.points,
                                   &scan_in_cad.normals,
                                   &model.samples.face_ids,
                                   &model.samples.normals,
                                   &viewpoint};
  const auto field = refine_field(*raw, input, s.field.refinement);
  to_proto(field, report.mutable_deformation_field());
  if (!field.uncovered.empty())
    report.add_warnings("deformation field: " + std::to_string(field.uncovered.size()) +
                        " model control points are not covered by the scan (no vector)");
  // On a scanned skin this means the result frame has the scan on the model's other side.
  if (field.seen_from_far_side > 0)
    report.add_warnings("deformation field: " + std::to_string(field.seen_from_far_side) +
                        " of them are seen from the other side of the sheet only (the scan's "
                        "normals point into the material there)");
  for (const Vec3& d : field.translations_from_fit) {
    char direction[64];
    std::snprintf(direction, sizeof direction, "(%.3f %.3f %.3f)", d.x(), d.y(), d.z());
    report.add_warnings(std::string("deformation field: its translation along ") + direction +
                        " (CAD frame) is not measured: no fitted flange faces along it and the "
                        "scan does not show the sheet's edges across it consistently; the "
                        "vectors' component along it is the alignment's placement of the part");
  }
  if (field.unmeasured_motion > 0)
    report.add_warnings("deformation field: " + std::to_string(field.unmeasured_motion) +
                        " of them are scanned, but their flange or bend moves through an "
                        "unmeasured bend (only the normal component is known there)");
  if (s.field.method == CorrespondenceMethod::kMinCostMatching && !field.optimality_certified)
    report.add_warnings("deformation field: the matching's optimality certificate failed: " +
                        field.matching.certificate.failure);
  auto comp = compensation(field, reduced.model_centers, s.compensation);
  if (!comp) return comp.error();
  append_to_report(*comp, &report);
  if (comp->unsupported > 0)
    report.add_warnings("compensation: " + std::to_string(comp->unsupported) +
                        " model control points have no deformation vector nearby");
  if (comp->clipped > 0)
    report.add_warnings("compensation: " + std::to_string(comp->clipped) + " vectors clipped to " +
                        std::to_string(s.compensation.max_magnitude_mm) + " mm");
  // The compensated surface: every CAD tessellation vertex moved by the interpolated c.
  if (!model.mesh.vertices.empty()) {
    auto moved = compensation(field, model.mesh.vertices, s.compensation);
    if (!moved) return moved.error();
    out.compensated_surface = model.mesh;
    for (std::size_t k = 0; k < moved->vectors.size(); ++k)
      out.compensated_surface.vertices[k] += moved->vectors[k].vector;
  }
  out.compensation = std::move(comp).value();
  return FieldCoverage{field.coverage, field.model_points, to_string(field.method)};
}

// A solid model (its flanges have two skins) seen by a one-sided scan: the global fit pairs by
// the facing rule (registration/facing.hpp) and needs the fit points' normals toward the
// scanner. A scan that brings normals keeps them (voxel-averaged); otherwise they are estimated
// on the fit points and turned toward the scanner's viewpoint (settings.normals). A surface
// model (no thickness) has no far skin: no normals, nearest pairs.
Expected<std::vector<Vec3>> fit_point_normals(const PartModel& model, const PointCloud& fit_points,
                                              const NormalSettings& settings) {
  const bool solid =
      std::any_of(model.segmentation.flanges.begin(), model.segmentation.flanges.end(),
                  [](const Flange& f) { return f.thickness_mm > 0.0; });
  if (!solid) return std::vector<Vec3>{};
  if (fit_points.normals.size() == fit_points.size()) return fit_points.normals;
  auto estimated = estimate_normals(fit_points.points, settings);
  if (!estimated) return estimated.error().prepend("global fit: scan normals: ");
  return std::move(estimated->normals);
}

// The scan's normals when it has one per point, else none. By reference: the conditional of a
// vector and a temporary would copy a 1M-point scan's normals.
const std::vector<Vec3>& normals_of(const PointCloud& scan) {
  static const std::vector<Vec3> kNoNormals;
  return scan.normals.size() == scan.size() ? scan.normals : kNoNormals;
}

// The fit points' estimated normals with the signs the scan tells (registration/facing.hpp
// orient_fit_points_along_skins: facing the viewpoint within 45 deg, or grown along the skin from
// such a point, on a sample finer than the sheet where the fit voxels are not), for a points-only
// scan of a solid; empty otherwise (the scan's normals, or a surface).
SkinNormals skin_normals(const PointCloud& scan, const PartModel& model,
                         const ReductionOutcome& reduced, const std::vector<Vec3>& fit_normals,
                         const Vec3& viewpoint, int threads) {
  if (!normals_of(scan).empty() || fit_normals.empty()) return {};
  double thickness = std::numeric_limits<double>::infinity();
  for (const Flange& f : model.segmentation.flanges)
    if (f.thickness_mm > 0.0) thickness = std::min(thickness, f.thickness_mm);
  return orient_fit_points_along_skins(scan.points, reduced.scan_for_fit.points, fit_normals,
                                       reduced.voxel_size_mm, viewpoint, thickness, threads);
}

// The rule before the signs were grown: the fit points whose estimated normal faces the
// viewpoint within 60 deg are known, the others (the standing walls) left out. The exact updates
// before the orientation is settled and the rivals' comparison keep it: with the walls in, a
// points-only sprung side panel's few notch points no longer decided its half turn
// (production_parts_test.cpp FewNotchPointsDecideUnderNoise, again with the flat seeds first);
// the walls join the last least squares only (least_squares_best_fit).
SkinNormals viewpoint_facing(const SkinNormals& skins, const PointCloud& fit_points,
                             const std::vector<Vec3>& fit_normals, const Vec3& viewpoint) {
  if (skins.normals.empty()) return {};
  constexpr double kMinFacingViewpoint = 0.5;  // cos 60 deg
  SkinNormals out{fit_normals, std::vector<std::uint8_t>(fit_normals.size(), 0)};
  for (std::size_t i = 0; i < fit_normals.size(); ++i)
    out.known[i] =
        fit_normals[i].dot((viewpoint - fit_points.points[i]).normalized()) >= kMinFacingViewpoint;
  return out;
}

// The exact updates' points under each sign rule (exact_update_points).
struct ExactUpdatePoints {
  FacingSample skins, facing;
};

// The sampled points whose nearest fit point's sign `signs` tells, each with that normal.
FacingSample with_known_signs(const std::vector<Vec3>& sample,
                              const std::vector<std::uint32_t>& nearest_fit,
                              const SkinNormals& signs) {
  FacingSample out;
  for (std::size_t k = 0; k < sample.size(); ++k)
    if (signs.known[nearest_fit[k]]) {
      out.points.push_back(sample[k]);
      out.normals.push_back(signs.normals[nearest_fit[k]]);
    }
  return out;
}

// The scan points the exact-surface updates pair (global_fit.hpp, finish_best_fit): an
// evenly strided sample of `count`, with the scan's normals when it has them. A points-only
// scan of a solid lends a point the normal of its nearest fit point, so that the facing rule
// holds: without it a point near a closed hem (four skins within 1.8 mm) paired across the
// sheet, and the cover flange's points-only field went 0.3 -> 1.2 mm. Only where the scan tells
// that normal's sign (`skins`): a standing wall's estimated normal is horizontal, and its sign,
// which the viewpoint decides by a small vertical part, is a guess until it is grown along the
// skin from a flange that faces the scanner (issue 32: with the walls left out, the frame sat on
// the flanges, 0.33 mm off on a perfect front panel). Such points are left out of the updates.
// The sample and each point's nearest fit point are found once (one k-d tree) for both rules
// the pipeline signs by (`skins` and `facing`, run_inspection).
ExactUpdatePoints exact_update_points(const PointCloud& scan, const PointCloud& fit_points,
                                      const SkinNormals& skins, const SkinNormals& facing,
                                      std::size_t count) {
  ExactUpdatePoints out;
  if (skins.normals.empty()) {
    out.skins = facing_sample(scan.points, normals_of(scan), count);
    out.facing = out.skins;
    return out;
  }
  const KdTree fit_tree(fit_points.points);
  std::vector<Vec3> sample;
  std::vector<std::uint32_t> nearest_fit;
  for (const Vec3& p : strided_sample(scan.points, count))
    if (const auto nn = fit_tree.nearest(p)) {
      sample.push_back(p);
      nearest_fit.push_back(nn->index);
    }
  out.skins = with_known_signs(sample, nearest_fit, skins);
  out.facing = with_known_signs(sample, nearest_fit, facing);
  return out;
}

// The fit's points for the least-squares updates on the samples (finish_best_fit): all of them
// with their normals, but for a points-only scan of a solid those whose normal's sign the scan
// tells (as exact_update_points). A standing wall's guessed normal may point to either skin, and
// with no share trimmed such points pulled the motor bracket's frame 0.5 mm toward the other
// skin; the trimmed ICP before had left them out.
FacingSample facing_fit_points(const PointCloud& fit_points, const std::vector<Vec3>& fit_normals,
                               const SkinNormals& skins) {
  if (skins.normals.empty()) return FacingSample{fit_points.points, fit_normals};
  FacingSample out;
  for (std::size_t i = 0; i < fit_points.size(); ++i)
    if (skins.known[i]) {
      out.points.push_back(fit_points.points[i]);
      out.normals.push_back(skins.normals[i]);
    }
  return out;
}

// The chosen pose's last updates, the paper's best fit (global_fit.hpp final_iterations): least
// squares over the whole seen surface, no share trimmed, paired as the fit before (on the exact
// surface with `exact_points` where the samples are biased, on the samples with the fit's points
// elsewhere); then the part's ends pin what the surface leaves free, as after the first fit.
// Only now: the rival orientations were compared on trimmed fits, where a near-symmetric part's
// few telling points weigh (untrimmed, the side panel's half turn scored within 0.1 %).
Expected<BoundaryResult> least_squares_best_fit(
    const BoundaryScan& boundary_scan, const ReductionOutcome& reduced,
    const std::vector<Vec3>& fit_normals, const SkinNormals& skins, const PartModel& model,
    const KdTree& model_tree, const SurfaceDistance* exact_updates,
    const FacingSample& exact_points, const PipelineSettings& config, GlobalFitResult& fit) {
  const FacingSample points =
      exact_updates ? exact_points : facing_fit_points(reduced.scan_for_fit, fit_normals, skins);
  IcpResult polished = fit.icp;
  polished.T_target_source = fit.T_cad_scan;
  if (auto error = finish_best_fit(points.points, points.normals, exact_updates, model_tree,
                                   model.samples.normals, config.global_fit,
                                   config.global_fit.final_iterations,
                                   config.global_fit.final_trimmed_fraction, polished))
    return *error;
  fit.icp = std::move(polished);
  auto pinned = pin_to_boundary(boundary_scan, fit.icp.T_target_source, model, model_tree,
                                config.global_fit.boundary);
  if (!pinned) return pinned.error();
  fit.T_cad_scan = pinned->T_cad_scan;
  return pinned;
}

// True when a bend's inner radius is below the model samples' spacing: there a scan point's
// nearest sample lies up to a spacing away along a tight curve, and its tangent plane is off the
// surface by about d^2 / 2R toward the convex side (a closed hem's 0.05 mm fold tilted the cover
// flange's fit 0.16 deg). Elsewhere the sample pairs are unbiased, and the exact updates are
// left out: on the front panel and the analytic profiles of the tests they moved the frame along
// its weakly fixed directions (up to 0.1 mm and 0.6 deg, docs/alignment.md).
bool samples_biased_at_bends(const PartModel& model, const KdTree& model_tree) {
  const double spacing = model_sample_spacing(model_tree);
  return std::any_of(model.segmentation.bends.begin(), model.segmentation.bends.end(),
                     [&](const Bend& b) { return b.radius_mm < spacing; });
}

// Stage 4b: the result frame. With datums (registration/datum.hpp), the datum frame solved from
// the datum features measured in the scan, the best fit kept beside it; without, the best fit.
// A datum that cannot be measured: the best fit's frame, the alignment marked not achieved (the
// datum named and why), and the verdict fails (run_inspection).
Expected<Transform> result_frame(const PointCloud& scan, const Transform& T_best,
                                 const PartModel& model, const DatumAlignmentSettings& settings,
                                 v1::Alignment* out) {
  if (settings.datums.empty()) {
    alignment_to_proto(T_best, nullptr, out);
    return T_best;
  }
  auto datum = align_to_datums(scan.points, normals_of(scan), T_best, model, settings);
  if (!datum) return datum.error();
  alignment_to_proto(T_best, &*datum, out);
  return datum->T_cad_scan;
}

// The report's head: schema, the settings in force, what went in.
void start_report(const PipelineSettings& config, const v1::AnalysisSettings& settings,
                  const PartModel& model, const PointCloud& scan, v1::InspectionReport& report) {
  report.set_schema("springscan.report.v1");
  record_settings(config, settings, report.mutable_settings());
  v1::InputSummary& input = *report.mutable_input();
  input.set_scan_points(static_cast<std::int64_t>(scan.size()));
  input.set_model_points(static_cast<std::int64_t>(model.samples.size()));
  input.set_cad_faces(model.face_count);
  input.set_cad_sha256(model.source_sha256);
}

// to[k] = from[indices[k]] on `threads` threads (indices: a permutation of from's); nothing for
// an attribute not given per point (empty, or of another count: no stage would use it).
template <typename T>
void gather(const std::vector<T>& from, const std::vector<std::uint32_t>& indices,
            std::vector<T>& to, int threads) {
  if (from.size() != indices.size()) return;
  to.resize(indices.size());
  parallel_blocks(indices.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) to[k] = from[indices[k]];
  });
}

// The scan in canonical_order, and that order, on `threads` threads. The points come from the
// copy the order's sort made (1M points' gather is some 20 ms on one thread), the other
// attributes are gathered.
std::pair<PointCloud, std::vector<std::uint32_t>> in_canonical_order(const PointCloud& cloud,
                                                                     int threads) {
  OrderedPoints ordered = canonically_ordered(cloud.points, threads);
  PointCloud out;
  out.points = std::move(ordered.points);
  gather(cloud.normals, ordered.order, out.normals, threads);
  gather(cloud.scalars, ordered.order, out.scalars, threads);
  gather(cloud.colors, ordered.order, out.colors, threads);
  gather(cloud.face_ids, ordered.order, out.face_ids, threads);
  return {std::move(out), std::move(ordered.order)};
}

// to[order[k]] = from[k] on `threads` threads (order: a permutation); nothing for an attribute
// not given per point.
template <typename T>
void scatter(const std::vector<T>& from, const std::vector<std::uint32_t>& order,
             std::vector<T>& to, int threads) {
  if (from.size() != order.size()) return;
  to.resize(order.size());
  parallel_blocks(order.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) to[order[k]] = from[k];
  });
}

// `ordered`'s points (ordered[k] is the scan's point order[k]) back in the scan's order.
PointCloud in_input_order(const PointCloud& ordered, const std::vector<std::uint32_t>& order,
                          int threads) {
  PointCloud out;
  scatter(ordered.points, order, out.points, threads);
  scatter(ordered.normals, order, out.normals, threads);
  scatter(ordered.scalars, order, out.scalars, threads);
  scatter(ordered.colors, order, out.colors, threads);
  scatter(ordered.face_ids, order, out.face_ids, threads);
  return out;
}

}  // namespace

// Some 70 lines on purpose: the stages in the paper's order, each a call, its report section
// and its time; split, the data flow from one stage to the next would no longer read in one place.
Expected<InspectionOutcome> run_inspection(const PartModel& model, const PointCloud& input_scan,
                                           const v1::AnalysisSettings& settings) {
  const auto start = Clock::now();
  auto config = load_settings(settings);
  if (!config) return config.error();
  InspectionOutcome out;
  v1::InspectionReport& report = out.report;
  start_report(*config, settings, model, input_scan, report);
  if (auto error = check_inputs(model, input_scan, report)) return *error;
  auto& timings = *report.mutable_timings_ms();

  auto t = Clock::now();
  // A scan in no spatial order (a file's, merged heads') is taken in one canonical space order
  // (issue 37; its time counts in the reduce's): every search then runs in space order, and
  // since the stages sample the scan by index, every such order of the same points gives the
  // same report. A scan in scanner lines is taken as it came: already coherent, and its lines
  // are the neighbourhoods the noise estimate reads (reordered, a side panel's few notch points
  // no longer decided its orientation: docs/performance.md).
  std::vector<std::uint32_t> scan_order;
  PointCloud reordered;
  if (!spatially_coherent(input_scan.points))
    std::tie(reordered, scan_order) = in_canonical_order(input_scan, config->threads);
  const PointCloud& scan = scan_order.empty() ? input_scan : reordered;
  // 3. Reduce: voxel centroids of the scan for the fit, k-center of both (paper §2).
  auto reduced = reduce(scan, model.samples, config->reduction);
  if (!reduced) return reduced.error();
  to_proto(*reduced, config->reduction, model.samples.size(), scan.size(),
           report.mutable_reduction());
  timings.set_reduce(ms_since(t));

  t = Clock::now();
  // 4. Global fit: PCA with every proper axis candidate, then ICP (paper §3).
  const KdTree model_tree(model.samples.points);
  auto fit_normals = fit_point_normals(model, reduced->scan_for_fit, config->normals);
  if (!fit_normals) return fit_normals.error();
  auto fit = global_fit(reduced->scan_for_fit.points, model_tree, model.samples.normals,
                        config->global_fit, *fit_normals);
  if (!fit) return fit.error();
  // Its last updates on the exact CAD surface, on the scan's own points, where the samples'
  // tangent planes are biased (a bend radius below their spacing).
  const SurfaceDistance* exact_updates =
      samples_biased_at_bends(model, model_tree) ? model.distance.get() : nullptr;
  const SkinNormals skins =
      skin_normals(scan, model, *reduced, *fit_normals, config->normals.viewpoint, config->threads);
  const SkinNormals facing =
      viewpoint_facing(skins, reduced->scan_for_fit, *fit_normals, config->normals.viewpoint);
  const ExactUpdatePoints exact = exact_updates
                                      ? exact_update_points(scan, reduced->scan_for_fit, skins,
                                                            facing, config->global_fit.exact_points)
                                      : ExactUpdatePoints{};
  const FacingSample& exact_points = exact.skins;
  const FacingSample& settle_points = exact.facing;
  if (auto error = finish_best_fit(settle_points.points, settle_points.normals, exact_updates,
                                   model_tree, model.samples.normals, config->global_fit,
                                   config->global_fit.exact_iterations,
                                   config->global_fit.icp.trimmed_fraction, fit->icp))
    return *error;
  fit->T_cad_scan = fit->icp.T_target_source;
  // The part's ends fix what the surface leaves free (registration/boundary.hpp); the scan's
  // samples for it drawn once for the three pins below.
  const BoundaryScan boundary_scan(scan.points, config->global_fit.boundary);
  auto pinned = pin_to_boundary(boundary_scan, fit->T_cad_scan, model, model_tree,
                                config->global_fit.boundary);
  if (!pinned) return pinned.error();
  fit->T_cad_scan = pinned->T_cad_scan;
  // A near-symmetric part's rival orientations compared on converged fits (trimmed alike).
  pinned = settle_orientation(
      {reduced->scan_for_fit.points, *fit_normals, scan.points, settle_points.points,
       settle_points.normals, model, model_tree, exact_updates, &boundary_scan},
      config->global_fit, *fit, std::move(*pinned));
  if (!pinned) return pinned.error();
  // The pose chosen, its last updates are the paper's best fit: least squares over the whole
  // seen surface, no share trimmed (global_fit.hpp final_trimmed_fraction), then the ends again.
  pinned = least_squares_best_fit(boundary_scan, *reduced, *fit_normals, skins, model, model_tree,
                                  exact_updates, exact_points, *config, *fit);
  if (!pinned) return pinned.error();
  fit->rms_final_mm =
      rms_nearest_distance(reduced->scan_for_fit.points, fit->T_cad_scan, model_tree,
                           config->global_fit.icp.trimmed_fraction, config->threads);
  to_proto(*fit, config->global_fit, report.mutable_global_fit());
  to_proto(pinned->free_directions, report.mutable_global_fit());
  for (const auto& warning : fit->warnings) report.add_warnings(warning);
  for (const FreeDirection& d : pinned->free_directions)
    if (!d.pinned) report.add_warnings("global fit: a direction is left free, " + d.rule);
  const auto T_cad_scan =
      result_frame(scan, fit->T_cad_scan, model, config->alignment, report.mutable_alignment());
  if (!T_cad_scan) return T_cad_scan.error();
  // The result frame's U (k = 2) from the fit points' pairs (docs/uncertainty.md).
  const FrameUncertainty frame_u =
      frame_uncertainty(transformed(reduced->scan_for_fit, *T_cad_scan).points, model_tree,
                        model.samples.normals, config->uncertainty);
  report.mutable_alignment()->set_uncertainty_rotation_deg(frame_u.rotation_deg);
  report.mutable_alignment()->set_uncertainty_translation_mm(frame_u.translation_mm);
  timings.set_global_fit(ms_since(t));

  t = Clock::now();
  // 5. Deviation: signed distance of every scan point to the model (DESIGN.md stage 5).
  PointCloud scan_in_cad = scan_in_frame(scan, *T_cad_scan, config->threads);
  auto deviation = signed_deviation(scan_in_cad.points, model, model_tree, config->deviation);
  if (!deviation) return deviation.error();
  // deviation.ply's colour scale: the setting, else the surface tolerance it is judged by.
  const double color_scale_mm = config->deviation.color_scale_mm > 0.0
                                    ? config->deviation.color_scale_mm
                                    : config->verdict.tolerance_mm;
  to_proto(*deviation, color_scale_mm, report.mutable_deviation());
  // The fit's health figure: the distance of the scan to the surface after the fit, trimmed
  // like ICP's pairs. rms_final (to the nearest model sample) grows with the sample spacing,
  // and on a thick sheet the nearest sample may lie on the other side.
  const double fit_rms_residual_mm =
      trimmed_rms(deviation->signed_distance_mm, config->global_fit.icp.trimmed_fraction);
  report.mutable_global_fit()->set_rms_residual(fit_rms_residual_mm);
  out.deviation_cloud =
      deviation_cloud(std::move(scan_in_cad), *deviation, color_scale_mm, config->threads);
  timings.set_deviation(ms_since(t));

  t = Clock::now();
  // 6-7. Local best fits per flange and springback per bend (paper §4, automated).
  const auto springback = add_bend_table(model, out.deviation_cloud, *config, frame_u, report);
  // The surface statistic's U: the flanges' noise (else the fit's residual), and how far the
  // result frame's own U moves the statistic (its sensitivity to the frame, on these points).
  const auto frame_sigma = [&](double quantile) {
    return frame_statistic_sigma(frame_u, out.deviation_cloud.points, deviation->signed_distance_mm,
                                 quantile, model_tree, model.samples.normals);
  };
  // The noise: of the distances themselves where the scan's order tells it, else the flanges'.
  const double noise_mm =
      std::max(neighbour_noise_mm(out.deviation_cloud.points, deviation->signed_distance_mm),
               springback ? part_noise_mm(*springback) : fit_rms_residual_mm);
  attach_deviation_uncertainty(noise_mm, frame_sigma(0.95), frame_sigma(1.0),
                               p95_outlier_shift_mm(deviation->signed_distance_mm),
                               part_extent_mm(out.deviation_cloud), config->uncertainty,
                               deviation->statistics);
  // deviation.uncertainty_mm: the verdict copies the U of the statistic it judged.
  timings.set_local_fits(ms_since(t));

  t = Clock::now();
  // 8-9. Deformation field by exact matching (paper §5) and compensation vectors.
  auto coverage = add_deformation(model, model_tree, *reduced, *T_cad_scan, out.deviation_cloud,
                                  springback ? &*springback : nullptr, *config, out);
  if (!coverage) return coverage.error();
  timings.set_deformation(ms_since(t));

  // 9. Verdict from the stage results: deviation and springback against the tolerances,
  // analysis health; the report copies its decisions, the per-bend pass included.
  const VerdictResult verdict = decide_verdict(
      {deviation->statistics, deviation->signed_distance_mm,
       springback ? springback->bends : std::vector<BendMeasurement>{},
       springback ? flange_shapes(springback->flanges) : std::vector<FlangeShapeSummary>{},
       std::move(*coverage), fit_rms_residual_mm, fit->ambiguous, fit->orientation.ambiguity},
      config->verdict);
  to_proto(verdict, &report);
  // No datum frame (a datum not measurable): the results are the best fit's, never a PASS.
  if (!report.alignment().achieved()) {
    report.mutable_verdict()->set_pass(false);
    report.mutable_verdict()->set_decision(v1::Verdict::FAIL);
    report.mutable_verdict()->add_reasons("alignment: " + report.alignment().failure() +
                                          "; the results are in the best-fit frame");
  }

  if (!scan_order.empty())
    out.deviation_cloud = in_input_order(out.deviation_cloud, scan_order, config->threads);
  timings.set_total(ms_since(start));
  return out;
}

Expected<bool> check_analysis_settings(const v1::AnalysisSettings& settings) {
  auto stages = load_settings(settings);
  if (!stages) return stages.error();
  auto model = from_proto(settings.cad_model());
  if (!model) return model.error();
  return true;
}

Expected<InspectionOutcome> run_mesh_inspection(
    const PartModel& model, const PointCloud& scan,
    const std::vector<std::array<std::uint32_t, 3>>& triangles,
    const v1::AnalysisSettings& settings) {
  auto reduction = from_proto(settings.reduction());
  if (!reduction) return reduction.error();
  auto threads = threads_from_proto(settings);
  if (!threads) return threads.error();
  DecimationSettings decimation = reduction->mesh_decimation;
  MeshScanReduction summary{.decimated = decimation.enabled,
                            .vertices_in = scan.size(),
                            .triangles_in = triangles.size(),
                            .vertices_out = scan.size(),
                            .triangles_out = triangles.size()};
  if (!decimation.enabled) {
    auto out = run_inspection(model, scan, settings);
    if (out) out->mesh_reduction = summary;
    return out;
  }
  // 2b. Mesh decimation of the scanner triangulation (paper §2), before every other stage.
  const auto start = Clock::now();
  decimation.threads = *threads;
  auto decimated = decimate_scan(scan, triangles, decimation);
  if (!decimated) return decimated.error().prepend("scan: ");
  summary.time_ms = ms_since(start);
  summary.vertices_out = decimated->cloud.size();
  summary.triangles_out = decimated->result.mesh.triangles.size();
  summary.max_deviation_mm = decimated->result.max_deviation_mm;
  auto out = run_inspection(model, decimated->cloud, settings);
  if (!out) return out;
  out->mesh_reduction = summary;
  auto& timings = *out->report.mutable_timings_ms();
  timings.set_reduce(timings.reduce() + summary.time_ms);
  timings.set_total(timings.total() + summary.time_ms);
  return out;
}

}  // namespace springscan::analysis
