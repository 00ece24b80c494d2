// The deformation field refined to sub-sample accuracy (field_refinement.hpp).
#include "analysis/matching/field_refinement.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

#include "analysis/core/kdtree.hpp"
#include "analysis/core/parallel.hpp"
#include "analysis/matching/field_prediction.hpp"
#include "analysis/preprocess/normals.hpp"

namespace springscan::analysis {
namespace {

constexpr std::uint32_t kNoScan = std::numeric_limits<std::uint32_t>::max();
// On a solid, a scan normal more than 60 deg from the CAD normal expected where the scan point
// lies belongs to another face: a sheet edge beside a skin is at 90 deg, the far skin at 180.
constexpr double kMinNormalCosine = 0.5;

// The scan points near the predicted positions, bucketed by a dense grid of cells marked around
// the predictions: one pass over the scan, no tree over a million points.
struct ScanGrid {
  Vec3 origin = Vec3::Zero();
  double cell = 1.0;
  Eigen::Array3i dims = Eigen::Array3i::Zero();
  std::vector<std::int32_t> slot;      // per cell: bucket, or -1 when not marked
  std::vector<std::uint32_t> offsets;  // per bucket: start in `indices`
  std::vector<std::uint32_t> indices;  // scan point indices, bucket by bucket
  std::vector<Vec3> points;            // those points, copied in the same order: the support
                                       // reads a bucket's points side by side in memory
                                       // (in a shuffled scan, each read would miss the cache)

  bool cell_of(const Vec3& p, Eigen::Array3i& c) const {
    const Eigen::Array3d f = ((p - origin) / cell).array().floor();
    if ((f < 0.0).any() || (f >= dims.cast<double>()).any()) return false;
    c = f.cast<int>();
    return true;
  }
  std::size_t flat(const Eigen::Array3i& c) const {
    return (static_cast<std::size_t>(c.z()) * static_cast<std::size_t>(dims.y()) +
            static_cast<std::size_t>(c.y())) *
               static_cast<std::size_t>(dims.x()) +
           static_cast<std::size_t>(c.x());
  }
};

ScanGrid build_grid(const std::vector<Vec3>& centers, double reach, const std::vector<Vec3>& scan,
                    int threads) {
  ScanGrid g;
  if (centers.empty()) return g;
  Vec3 lo = centers[0], hi = centers[0];
  for (const Vec3& p : centers) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  g.cell = reach;
  g.origin = lo - Vec3::Constant(2.0 * reach);
  // At most 2^25 cells: coarser cells for a huge part (more candidates, same answer).
  for (;;) {
    g.dims = (((hi - g.origin) / g.cell).array() + 3.0).ceil().cast<int>();
    if (static_cast<double>(g.dims.prod()) <= 33554432.0) break;
    g.cell *= 1.5;
  }
  g.slot.assign(static_cast<std::size_t>(g.dims.prod()), -1);
  std::int32_t buckets = 0;
  for (const Vec3& p : centers) {
    Eigen::Array3i c;
    if (!g.cell_of(p, c)) continue;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          std::int32_t& s = g.slot[g.flat(c + Eigen::Array3i(dx, dy, dz))];
          if (s < 0) s = buckets++;
        }
  }
  // Each scan point's bucket (parallel), then a counting sort (serial, in scan order).
  std::vector<std::int32_t> bucket_of(scan.size(), -1);
  parallel_blocks(scan.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    Eigen::Array3i c;
    for (std::size_t j = begin; j < end; ++j)
      if (g.cell_of(scan[j], c)) bucket_of[j] = g.slot[g.flat(c)];
  });
  g.offsets.assign(static_cast<std::size_t>(buckets) + 1, 0);
  for (const std::int32_t b : bucket_of)
    if (b >= 0) ++g.offsets[static_cast<std::size_t>(b) + 1];
  for (std::size_t b = 1; b < g.offsets.size(); ++b) g.offsets[b] += g.offsets[b - 1];
  g.indices.resize(g.offsets.back());
  std::vector<std::uint32_t> fill(g.offsets.begin(), g.offsets.end() - 1);
  for (std::size_t j = 0; j < scan.size(); ++j)
    if (bucket_of[j] >= 0)
      g.indices[fill[static_cast<std::size_t>(bucket_of[j])]++] = static_cast<std::uint32_t>(j);
  g.points.resize(g.indices.size());
  parallel_blocks(g.indices.size(), threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) g.points[k] = scan[g.indices[k]];
  });
  return g;
}

// The sheet thickness at every face id (the last entry: faces of unknown id): a flange's own,
// a bend's thinner flange's, and for the other faces of a solid (rims, holes) the thinnest
// flange's. All 0 on a surface model, which has no far side: a shell is seen from either side.
std::vector<double> face_thickness(const PartSegmentation& s) {
  double thinnest = 0.0;
  int faces = 0;
  for (const Flange& f : s.flanges) {
    if (f.thickness_mm > 0.0 && (thinnest == 0.0 || f.thickness_mm < thinnest))
      thinnest = f.thickness_mm;
    for (const int id : f.face_ids) faces = std::max(faces, id + 1);
  }
  for (const Bend& b : s.bends)
    for (const int id : b.face_ids) faces = std::max(faces, id + 1);
  for (const int id : s.other_faces) faces = std::max(faces, id + 1);
  std::vector<double> t(static_cast<std::size_t>(faces) + 1, thinnest);
  std::unordered_map<int, double> by_id;
  for (const Flange& f : s.flanges) {
    by_id[f.id] = f.thickness_mm;
    for (const int id : f.face_ids) t[static_cast<std::size_t>(id)] = f.thickness_mm;
  }
  for (const Bend& b : s.bends) {
    const auto a = by_id.find(b.flange_a), c = by_id.find(b.flange_b);
    if (a == by_id.end() || c == by_id.end()) continue;
    for (const int id : b.face_ids)
      t[static_cast<std::size_t>(id)] = std::min(a->second, c->second);
  }
  return t;
}

double thickness_at(const std::vector<double>& by_face, int face) {
  if (face < 0 || static_cast<std::size_t>(face) + 1 >= by_face.size()) return by_face.back();
  return by_face[static_cast<std::size_t>(face)];
}

// The normal offset of the scan around one prediction (step 2).
struct Support {
  double offset = 0.0;  // mm along the moved normal
  double sigma = 0.0;   // robust spread of the residuals
  double sum_sq = 0.0;  // of the kept residuals about `offset`
  int count = 0;
  int far_side = 0;  // solids: candidates whose normal points into the material here
};

// On a solid (thickness > 0) the window along the normal stays within half the thickness: the
// other skin, one thickness behind, never enters it, whatever the scan's normals.
double normal_window(const FieldRefinementSettings& s, double thickness) {
  return thickness > 0.0 ? std::min(s.normal_window_mm, 0.5 * thickness) : s.normal_window_mm;
}

// The control points whose support may reach another face: a CAD sample of another face
// within `reach` (a sheet edge, a hole wall, the skin beside a rim; the caller gives 1.5 x the
// grid's reach, which covers the sample spacing: at 1 x the motor bracket's p95 went from 0.005
// to 0.012 mm). Only there does the cone
// of kMinNormalCosine part faces that the window along the normal does not; elsewhere the one
// face within reach is all the window can hold. All of them without sample faces.
std::vector<bool> near_other_face(const FieldRefinementInput& in, double reach) {
  const std::size_t n = in.model_points.size();
  const std::vector<int>* faces = in.model_sample_faces;
  if (!faces || faces->size() != in.model_samples.size()) return std::vector<bool>(n, true);
  const KdTree samples(in.model_samples);
  std::vector<bool> out(n, false);
  std::vector<Neighbor> near;
  for (std::size_t i = 0; i < n; ++i) {
    samples.radius(in.model_points[i], reach, near);
    for (const Neighbor& k : near)
      if ((*faces)[k.index] != in.model_faces[i]) {
        out[i] = true;
        break;
      }
  }
  return out;
}

// The normals of the grid's scan points (by position in g.indices, result frame, toward the
// scanner): the scan's own, or on a solid without them estimated (k nearest, turned toward the
// viewpoint) for the points in the cells of control points near another face (within
// `face_reach`, near_other_face), zero elsewhere. On the side panel's 1M points the field took 81
// ms so, 120 ms with every grid point estimated (bench_production). A sheet edge's points get a
// normal between its skin's and its rim's; the cone still parts the two faces beyond a
// neighbourhood from the edge. Empty: none (a surface model needs none).
std::vector<Vec3> grid_normals(const FieldRefinementInput& in, const ScanGrid& g,
                               const std::vector<Vec3>& centers, double face_reach, int threads) {
  std::vector<Vec3> out;
  if (in.scan_normals && in.scan_normals->size() == in.scan_points.size()) {
    out.reserve(g.indices.size());
    for (const std::uint32_t j : g.indices) out.push_back((*in.scan_normals)[j]);
    return out;
  }
  if (!in.scan_viewpoint) return out;
  // Only a points-only scan pays for this (a tree over the samples, a query per control point).
  const std::vector<bool> needed = near_other_face(in, face_reach);
  std::vector<std::uint8_t> bucket_needed(g.offsets.size(), 0);
  for (std::size_t i = 0; i < centers.size(); ++i) {
    Eigen::Array3i c;
    if (!needed[i] || !g.cell_of(centers[i], c)) continue;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          bucket_needed[static_cast<std::size_t>(g.slot[g.flat(c + Eigen::Array3i(dx, dy, dz))])] =
              1;
  }
  std::vector<std::uint32_t> at;  // grid positions estimated
  std::vector<Vec3> points;
  for (std::size_t b = 0; b + 1 < g.offsets.size(); ++b)
    if (bucket_needed[b])
      for (std::uint32_t k = g.offsets[b]; k < g.offsets[b + 1]; ++k) {
        at.push_back(k);
        points.push_back(g.points[k]);
      }
  out.assign(g.indices.size(), Vec3::Zero());
  if (points.size() < 3) return out;
  const KdTree tree(points);
  NormalSettings settings;
  settings.viewpoint = *in.scan_viewpoint;
  settings.threads = threads;
  const NormalResult estimated = estimate_normals(tree, settings);
  for (std::size_t j = 0; j < at.size(); ++j) out[at[j]] = estimated.normals[j];
  return out;
}

Support support_of(const FieldRefinementInput& in, const FieldPrediction& pred, const ScanGrid& g,
                   std::size_t i, double thickness, const FieldRefinementSettings& s,
                   const std::vector<Vec3>& normals, std::vector<double>& r) {
  r.clear();
  const bool use_normals = thickness > 0.0 && normals.size() == g.indices.size();
  const double window = normal_window(s, thickness);
  int far_side = 0;
  const Transform& M = pred.motion[i];
  const Vec3 m = in.model_points[i];
  const Vec3 n = in.model_normals[i];
  const Vec3 P = M * m;
  const Mat3 Rt = M.linear().transpose();
  const Bend* bend =
      pred.bend[i] >= 0 ? &in.segmentation.bends[static_cast<std::size_t>(pred.bend[i])] : nullptr;
  const Vec3& K = pred.curvature[i];
  Vec3 tu, tv;
  tangent_basis(n, tu, tv);
  Vec3 w = Vec3::Zero(), um = Vec3::Zero();
  double rho_m = 0.0, sign = 1.0;
  if (bend) {
    w = bend->axis_direction.normalized();
    um = m - bend->axis_point;
    um -= um.dot(w) * w;
    rho_m = um.norm();
    sign = n.dot(um) >= 0.0 ? 1.0 : -1.0;
  }
  const double r2 = s.support_radius_mm * s.support_radius_mm;
  Eigen::Array3i c;
  if (!g.cell_of(P, c)) return {};
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const std::int32_t b = g.slot[g.flat(c + Eigen::Array3i(dx, dy, dz))];
        for (std::uint32_t k = g.offsets[static_cast<std::size_t>(b)];
             k < g.offsets[static_cast<std::size_t>(b) + 1]; ++k) {
          const Vec3 d = Rt * (g.points[k] - P);  // CAD frame, from m
          const double along = n.dot(d);
          if ((d - along * n).squaredNorm() > r2) continue;
          double res = along;
          Vec3 expected = n;  // the outward CAD normal where the candidate lies
          if (!K.isZero()) {  // a curved face: the height over the tangent plane, the normal
            const double x = tu.dot(d), y = tv.dot(d);
            res -= 0.5 * (K.x() * x * x + 2.0 * K.y() * x * y + K.z() * y * y);
            expected =
                (n - (K.x() * x + K.y() * y) * tu - (K.y() * x + K.z() * y) * tv).normalized();
          }
          if (bend) {
            Vec3 uq = m + d - bend->axis_point;
            uq -= uq.dot(w) * w;
            res = sign * (uq.norm() - rho_m);
            expected = sign * uq.normalized();
          }
          if (std::abs(res) > window) continue;
          if (use_normals) {
            // A scanner sees a surface from outside the material only: a scan normal against
            // this skin's outward normal was seen from the other side of the sheet (the far
            // skin); one across it lies on another face (a skin beside a sheet edge or a hole
            // wall, or that wall beside a skin), whose points the window does not separate.
            if (normals[k].isZero()) {  // not estimated here: one face within reach
              r.push_back(res);
              continue;
            }
            const double cos_in = expected.dot(Rt * normals[k]);
            if (cos_in < 0.0) ++far_side;
            if (cos_in < kMinNormalCosine) continue;
          }
          r.push_back(res);
        }
      }
  if (r.size() < static_cast<std::size_t>(std::max(s.min_support_points, 1))) {
    Support none;
    none.far_side = far_side;
    return none;
  }
  // Robust mean: median and MAD, then the mean of the residuals within outlier_mad_factor.
  const auto mid = r.begin() + static_cast<long>(r.size() / 2);
  std::nth_element(r.begin(), mid, r.end());
  const double median = *mid;
  std::vector<double> dev(r.size());
  for (std::size_t k = 0; k < r.size(); ++k) dev[k] = std::abs(r[k] - median);
  std::nth_element(dev.begin(), dev.begin() + static_cast<long>(dev.size() / 2), dev.end());
  const double robust = std::max(1.4826 * dev[dev.size() / 2], 1e-4);
  Support out;
  double sum = 0.0;
  for (const double x : r)
    if (std::abs(x - median) <= s.outlier_mad_factor * robust) sum += x, ++out.count;
  if (out.count < s.min_support_points) return {};
  out.offset = sum / out.count;
  for (const double x : r)
    if (std::abs(x - median) <= s.outlier_mad_factor * robust)
      out.sum_sq += (x - out.offset) * (x - out.offset);
  out.sigma = std::sqrt(out.sum_sq / std::max(out.count - 1, 1));
  return out;
}

}  // namespace

DeformationField refine_field(const DeformationField& raw, const FieldRefinementInput& in,
                              const FieldRefinementSettings& s) {
  if (!s.enabled) return raw;
  DeformationField out = raw;
  out.refined = true;
  out.matched = raw.vectors;
  out.vectors.clear();
  const std::size_t n = in.model_points.size();
  if (n == 0 || in.model_normals.size() != n || in.model_faces.size() != n) return out;
  const FieldPrediction pred = predict_field(raw, in);
  out.translations_from_fit = pred.translations_from_fit;
  std::vector<Vec3> centers(n);
  for (std::size_t i = 0; i < n; ++i) centers[i] = pred.motion[i] * in.model_points[i];
  const double reach = std::hypot(s.support_radius_mm, s.normal_window_mm);
  const ScanGrid grid = build_grid(centers, reach, in.scan_points, s.threads);

  const std::vector<double> thickness = face_thickness(in.segmentation);
  const bool solid =
      std::any_of(thickness.begin(), thickness.end(), [](double t) { return t > 0; });
  const std::vector<Vec3> normals =
      solid ? grid_normals(in, grid, centers, 1.5 * reach, s.threads) : std::vector<Vec3>{};
  std::vector<Support> support(n);
  for_each_block(n, 16, s.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    std::vector<double> scratch;
    for (std::size_t i = begin; i < end; ++i)
      support[i] = support_of(in, pred, grid, i, thickness_at(thickness, in.model_faces[i]), s,
                              normals, scratch);
  });
  std::vector<std::uint32_t> partner(n, kNoScan);
  for (const auto& v : raw.vectors) partner[v.model_index] = v.scan_index;
  double sum_sq = 0.0;
  std::size_t used = 0;
  for (std::size_t i = 0; i < n; ++i) {
    // The scan fixes a vector along the normal only; its other components come from the
    // material's motion, which an unmeasured bend leaves unknown (a wall seen edge-on moves
    // by its springback times its height, unseen): no vector rather than a guessed one.
    if (pred.guessed[i] && support[i].count > 0) {
      ++out.unmeasured_motion;
      support[i].count = 0;
    }
    if (support[i].count == 0) {
      out.uncovered.push_back(static_cast<std::uint32_t>(i));
      out.uncovered_points.push_back(in.model_points[i]);
      if (support[i].far_side >= s.min_support_points) ++out.seen_from_far_side;
      continue;
    }
    DeformationVector v;
    v.model_index = static_cast<std::uint32_t>(i);
    v.scan_index = partner[i];
    v.model = in.model_points[i];
    const Vec3 normal = (pred.motion[i].linear() * in.model_normals[i]).normalized();
    v.scan = centers[i] + support[i].offset * normal;
    v.squared_distance_mm2 = (v.scan - v.model).squaredNorm();
    v.support_points = support[i].count;
    v.uncertainty_mm = support[i].sigma / std::sqrt(static_cast<double>(support[i].count));
    out.vectors.push_back(v);
    sum_sq += support[i].sum_sq;
    used += static_cast<std::size_t>(support[i].count);
  }
  out.scan_coverage = static_cast<double>(out.vectors.size()) / static_cast<double>(n);
  out.residual_rms_mm = used > 0 ? std::sqrt(sum_sq / static_cast<double>(used)) : 0.0;
  return out;
}

}  // namespace springscan::analysis
