// The deformation field refined to sub-sample accuracy (field_refinement.hpp).
#include "analysis/matching/field_refinement.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

#include "analysis/core/kdtree.hpp"
#include "analysis/core/parallel.hpp"
#include "analysis/matching/part_motion.hpp"

namespace springscan::analysis {
namespace {

constexpr std::uint32_t kNoScan = std::numeric_limits<std::uint32_t>::max();
// On a solid, a scan normal more than 60 deg from the CAD normal expected where the scan point
// lies belongs to another face: a sheet edge beside a skin is at 90 deg, the far skin at 180.
constexpr double kMinNormalCosine = 0.5;

// The predicted motion of every control point (step 1).
struct Prediction {
  std::vector<Transform> motion;  // T_result_cad of the material at the point
  std::vector<int> bend;          // bend index when the point lies in a bend zone, else -1
  std::vector<bool> guessed;      // the motion rests on an unmeasured bend (motion_measured)
  std::vector<Vec3> curvature;    // other faces: (a, b, c) of the CAD surface's height
                                  // h = (a x^2 + 2 b x y + c y^2) / 2 over the tangent plane
};

// The tangent basis of a normal in which Prediction::curvature is given.
void tangent_basis(const Vec3& n, Vec3& u, Vec3& v) {
  u = n.unitOrthogonal();
  v = n.cross(u);
}

// The CAD surface's second-order shape at a control point of a curved face of neither flange
// nor bend (a hole wall, a rounded corner; a bend zone's residual is radial already), from the
// exact normals of that face's samples within 3 mm: the tangent part of a sample normal at
// tangent offset t is -K t. Over a 1.5 mm support on a 5 mm hole the surface leaves the tangent
// plane by 0.2 mm, which the normal offset would otherwise average in.
Vec3 face_curvature(const FieldRefinementInput& in, const KdTree& samples, std::size_t i,
                    std::vector<Neighbor>& near) {
  const Vec3& m = in.model_points[i];
  const Vec3& n = in.model_normals[i];
  Vec3 u, v;
  tangent_basis(n, u, v);
  samples.radius(m, 3.0, near);
  Mat3 A = 1e-3 * Mat3::Identity();  // a ridge: a narrow wall leaves c barely determined
  Vec3 rhs = Vec3::Zero();
  for (const Neighbor& k : near) {
    if ((*in.model_sample_faces)[k.index] != in.model_faces[i]) continue;
    const Vec3 d = in.model_samples[k.index] - m;
    const double x = u.dot(d), y = v.dot(d);
    const Vec3& ns = (*in.model_sample_normals)[k.index];
    // n_u = -(a x + b y), n_v = -(b x + c y)
    const Vec3 ju(x, y, 0.0), jv(0.0, x, y);
    A += ju * ju.transpose() + jv * jv.transpose();
    rhs -= ju * u.dot(ns) + jv * v.dot(ns);
  }
  return A.ldlt().solve(rhs);
}

// Without a segmentation: the matching's displacement, Gaussian-averaged over the pairs within
// three median spacings (the pairs' along-surface scatter averages out).
Transform smoothed_seed(const DeformationField& raw, const KdTree& anchors, double sigma,
                        const Vec3& p, std::vector<Neighbor>& near) {
  anchors.radius(p, 3.0 * sigma, near);
  Vec3 sum = Vec3::Zero();
  double weight = 0.0;
  for (const Neighbor& n : near) {
    const double w = std::exp(-n.squared_distance / (2.0 * sigma * sigma));
    sum += w * raw.vectors[n.index].displacement();
    weight += w;
  }
  Transform T = Transform::Identity();
  if (weight > 0.0) T.pretranslate(sum / weight);
  return T;
}

double median_spacing(const std::vector<Vec3>& points) {
  if (points.size() < 2) return 1.0;
  const KdTree tree(points);
  std::vector<double> d;
  std::vector<Neighbor> two;
  for (const Vec3& p : points) {
    tree.knn(p, 2, two);
    if (two.size() == 2) d.push_back(std::sqrt(two[1].squared_distance));
  }
  std::nth_element(d.begin(), d.begin() + static_cast<long>(d.size() / 2), d.end());
  return std::max(d[d.size() / 2], 1e-6);
}

// One end of a point set along d: the points are uniform in d near a straight edge, so the edge
// lies past the band [q - L, q) of the 99.9 % quantile q by the tail's count over the density
// of the band before it. Averaged over every laser line that crosses the edge, which the
// extreme point alone (quantised by the point spacing) is not.
double edge_along(std::vector<double>& s, bool upper) {
  constexpr double kBand = 3.0;  // mm
  const std::size_t n = s.size();
  if (upper)
    for (double& v : s) v = -v;
  std::sort(s.begin(), s.end());
  const double q = s[n / 1000];
  std::size_t tail = 0, band = 0;
  for (const double v : s) {
    if (v < q + kBand)
      ++tail;
    else if (v < q + 2.0 * kBand)
      ++band;
  }
  double edge = s.front();
  if (band > 10) edge = q + kBand - static_cast<double>(tail) * kBand / static_cast<double>(band);
  if (upper)
    for (double& v : s) v = -v;
  return upper ? -edge : edge;
}

// The sheet's mid-line along d from its two edges, edge by edge in strips across d (5 mm
// cells of the plane normal to d) and the median over the strips: a missing area or a cut-out
// at one edge moves a few strips only. At most ~200k points (a fixed stride) take part.
double mid_along(const std::vector<Vec3>& points, const Vec3& d) {
  constexpr double kStrip = 5.0;  // mm
  const Vec3 u = d.unitOrthogonal(), v = d.cross(u);
  const std::size_t stride = std::max<std::size_t>(1, points.size() / 200000);
  std::unordered_map<std::int64_t, std::vector<double>> strips;
  for (std::size_t j = 0; j < points.size(); j += stride) {
    const auto a = static_cast<std::int64_t>(std::floor(u.dot(points[j]) / kStrip));
    const auto b = static_cast<std::int64_t>(std::floor(v.dot(points[j]) / kStrip));
    strips[(a << 32) ^ (b & 0xffffffff)].push_back(d.dot(points[j]));
  }
  std::vector<double> lo, hi;
  for (auto& [key, s] : strips) {
    if (s.size() < 2000 / stride + 200) continue;
    lo.push_back(edge_along(s, false));
    hi.push_back(edge_along(s, true));
  }
  if (lo.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto median = [](std::vector<double>& x) {
    std::nth_element(x.begin(), x.begin() + static_cast<long>(x.size() / 2), x.end());
    return x[x.size() / 2];
  };
  return 0.5 * (median(lo) + median(hi));
}

// The CAD's extent along d: its samples are dense and reach the edges (no noise, no lines).
double extent_mid(const std::vector<Vec3>& points, const Vec3& d) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Vec3& p : points) lo = std::min(lo, d.dot(p)), hi = std::max(hi, d.dot(p));
  return points.empty() ? 0.0 : 0.5 * (lo + hi);
}

// Faces of neither flange nor bend (sheet edges, hole walls, the end faces of a bend zone): the
// motion of the material they bound at the point itself, the nearest flange or bend sample's
// motion_at the control point (in a bend zone's end face: the bend's turn at the point's own
// angle, which the nearest bend control point, up to w away, does not have). Without sample
// faces, the nearest control point of a flange or bend.
void place_other_faces(const FieldRefinementInput& in, const PartMotion& motion,
                       const std::vector<bool>& known, const std::vector<Vec3>& known_points,
                       const std::vector<std::uint32_t>& known_index, Prediction& out) {
  std::vector<Vec3> material;
  std::vector<int> material_face;
  const std::vector<int>* faces = in.model_sample_faces;
  if (faces && faces->size() == in.model_samples.size()) {
    for (std::size_t k = 0; k < faces->size(); ++k) {
      const int f = (*faces)[k];
      if (f < 0 || static_cast<std::size_t>(f) >= motion.face_flange.size()) continue;
      const auto face = static_cast<std::size_t>(f);
      if (motion.face_flange[face] < 0 && motion.face_bend[face] < 0) continue;
      material.push_back(in.model_samples[k]);
      material_face.push_back(f);
    }
  }
  const KdTree samples(material);
  const KdTree controls(known_points);
  const bool shaped = faces && faces->size() == in.model_samples.size() &&
                      in.model_sample_normals &&
                      in.model_sample_normals->size() == in.model_samples.size();
  const KdTree all_samples(shaped ? in.model_samples : std::vector<Vec3>{});
  std::vector<Neighbor> near_samples;
  for (std::size_t i = 0; i < known.size(); ++i) {
    if (known[i]) continue;
    const Vec3& p = in.model_points[i];
    if (shaped) out.curvature[i] = face_curvature(in, all_samples, i, near_samples);
    const auto near = samples.nearest(p);
    if (near && motion_at(motion, in.segmentation, p, material_face[near->index], out.motion[i])) {
      out.guessed[i] = !motion_measured(motion, in.segmentation, material_face[near->index]);
    } else {
      const std::uint32_t k = known_index[controls.nearest(p)->index];
      out.motion[i] = out.motion[k];
      out.guessed[i] = out.guessed[k];
    }
  }
}

Prediction predict(const DeformationField& raw, const FieldRefinementInput& in) {
  const std::size_t n = in.model_points.size();
  Prediction out;
  out.motion.assign(n, Transform::Identity());
  out.bend.assign(n, -1);
  out.guessed.assign(n, false);
  out.curvature.assign(n, Vec3::Zero());
  PartMotion motion;
  if (in.springback)
    motion = part_motion(in.segmentation, *in.springback, in.model_points, in.model_normals,
                         in.model_faces);
  // The directions no flange plane fixes: where the scan's sheet edges are against the CAD's.
  for (const Vec3& d : motion.free_translations) {
    const double shift = mid_along(in.scan_points, d) - extent_mid(in.model_samples, d);
    if (!std::isfinite(shift)) continue;
    for (Transform& T : motion.flange) T.pretranslate(shift * d);
  }
  std::vector<bool> known(n, false);
  std::vector<Vec3> known_points;
  std::vector<std::uint32_t> known_index;
  for (std::size_t i = 0; i < n; ++i) {
    known[i] =
        motion_at(motion, in.segmentation, in.model_points[i], in.model_faces[i], out.motion[i]);
    if (!known[i]) continue;
    const int face = in.model_faces[i];
    out.guessed[i] = !motion_measured(motion, in.segmentation, face);
    if (motion.face_flange[static_cast<std::size_t>(face)] < 0)
      out.bend[i] = motion.face_bend[static_cast<std::size_t>(face)];
    known_points.push_back(in.model_points[i]);
    known_index.push_back(static_cast<std::uint32_t>(i));
  }
  if (!known_points.empty()) {
    place_other_faces(in, motion, known, known_points, known_index, out);
    return out;
  }
  std::vector<Vec3> anchors;
  for (const auto& v : raw.vectors) anchors.push_back(v.model);
  if (anchors.empty()) return out;
  const double sigma = median_spacing(anchors);
  const KdTree tree(anchors);
  std::vector<Neighbor> near;
  for (std::size_t i = 0; i < n; ++i)
    out.motion[i] = smoothed_seed(raw, tree, sigma, in.model_points[i], near);
  return out;
}

// The scan points near the predicted positions, bucketed by a dense grid of cells marked around
// the predictions: one pass over the scan, no tree over a million points.
struct ScanGrid {
  Vec3 origin = Vec3::Zero();
  double cell = 1.0;
  Eigen::Array3i dims = Eigen::Array3i::Zero();
  std::vector<std::int32_t> slot;      // per cell: bucket, or -1 when not marked
  std::vector<std::uint32_t> offsets;  // per bucket: start in `indices`
  std::vector<std::uint32_t> indices;  // scan point indices, bucket by bucket

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

Support support_of(const FieldRefinementInput& in, const Prediction& pred, const ScanGrid& g,
                   std::size_t i, double thickness, const FieldRefinementSettings& s,
                   std::vector<double>& r) {
  r.clear();
  const std::vector<Vec3>* scan_normals =
      thickness > 0.0 && in.scan_normals && in.scan_normals->size() == in.scan_points.size()
          ? in.scan_normals
          : nullptr;
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
          const Vec3 d = Rt * (in.scan_points[g.indices[k]] - P);  // CAD frame, from m
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
          if (scan_normals) {
            // A scanner sees a surface from outside the material only: a scan normal against
            // this skin's outward normal was seen from the other side of the sheet (the far
            // skin); one across it lies on another face (a skin beside a sheet edge or a hole
            // wall, or that wall beside a skin), whose points the window does not separate.
            const double cos_in = expected.dot(Rt * (*scan_normals)[g.indices[k]]);
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
  const Prediction pred = predict(raw, in);
  std::vector<Vec3> centers(n);
  for (std::size_t i = 0; i < n; ++i) centers[i] = pred.motion[i] * in.model_points[i];
  const double reach = std::hypot(s.support_radius_mm, s.normal_window_mm);
  const ScanGrid grid = build_grid(centers, reach, in.scan_points, s.threads);

  const std::vector<double> thickness = face_thickness(in.segmentation);
  std::vector<Support> support(n);
  for_each_block(n, 16, s.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    std::vector<double> scratch;
    for (std::size_t i = begin; i < end; ++i)
      support[i] =
          support_of(in, pred, grid, i, thickness_at(thickness, in.model_faces[i]), s, scratch);
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
