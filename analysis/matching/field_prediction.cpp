// Step 1 of the field refinement: the predicted motion of every control point
// (field_prediction.hpp).
#include "analysis/matching/field_prediction.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "analysis/core/kdtree.hpp"
#include "analysis/core/spacing.hpp"
#include "analysis/matching/part_motion.hpp"

namespace springscan::analysis {
namespace {

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
  return std::max(median_neighbour_spacing(KdTree(points), points), 1e-6);
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

// The key of the cell of the plane normal to d (u, v spanning it) that p falls in: each cell,
// `strip_mm` square, is a strip of the part along d.
std::int64_t strip_key(const Vec3& p, const Vec3& u, const Vec3& v, double strip_mm) {
  const auto a = static_cast<std::int64_t>(std::floor(u.dot(p) / strip_mm));
  const auto b = static_cast<std::int64_t>(std::floor(v.dot(p) / strip_mm));
  return (a << 32) ^ (b & 0xffffffff);
}

double median_of(std::vector<double>& x) {
  std::nth_element(x.begin(), x.begin() + static_cast<long>(x.size() / 2), x.end());
  return x[x.size() / 2];
}

// The shift along d of the scan's sheet edges against the CAD's, strip by strip across d (cells
// of `strip_mm` in the plane normal to d). The CAD's ends are its samples' extremes along d
// (dense and noise-free, they reach the edges; per strip they would fall short by the sample
// spacing). A strip counts where the scan crosses the part from end to end along d: both of
// its edges (edge_along, ~2,000 points needed for the tails) within kSeenEdgeMm of the CAD's
// ends. Elsewhere it ends where the scanner stopped seeing, not at an edge: the front panel's
// sheet runs into walls seen edge-on, 1-5 mm short of them, and its edges scatter by a
// millimetre. The median of the strips' mid-points, NaN where fewer than 3 count (the best fit's
// value then stays). At most ~200k scan points (a fixed stride) take part.
double edge_shift(const std::vector<Vec3>& scan, const std::vector<Vec3>& cad, const Vec3& d,
                  double strip_mm) {
  constexpr double kSeenEdgeMm = 1.0;
  constexpr std::size_t kMinStrips = 3;  // one strip may pass by chance (a front panel's did)
  // The material ends at the CAD's ends, and a strip's edges can be no farther apart than those
  // whatever the pose: a strip that comes out longer by more than its edges' scatter (about
  // 0.05 mm, 0.3 at worst, on the profiles' strips) is not a sheet seen to its edges. There a
  // face seen at a slant piled its points up at the end and edge_along read the pile as
  // material going on: the front panel's walls facing along d, points only, gave strips 0.9-1.3
  // mm longer than the part, and their mid-points moved its field 0.11 mm.
  constexpr double kLongerMm = 0.5;
  double cad_lo = std::numeric_limits<double>::infinity(), cad_hi = -cad_lo;
  for (const Vec3& p : cad)
    cad_lo = std::min(cad_lo, d.dot(p)), cad_hi = std::max(cad_hi, d.dot(p));
  const Vec3 u = d.unitOrthogonal(), v = d.cross(u);
  const std::size_t stride = std::max<std::size_t>(1, scan.size() / 200000);
  std::unordered_map<std::int64_t, std::vector<double>> strips;
  for (std::size_t j = 0; j < scan.size(); j += stride)
    strips[strip_key(scan[j], u, v, strip_mm)].push_back(d.dot(scan[j]));
  std::vector<double> mids;
  for (auto& [key, s] : strips) {
    if (s.size() < 2000 / stride + 200) continue;
    const double l = edge_along(s, false) - cad_lo, h = edge_along(s, true) - cad_hi;
    const bool seen_ends = std::abs(l) <= kSeenEdgeMm && std::abs(h) <= kSeenEdgeMm;
    if (seen_ends && h - l <= kLongerMm) mids.push_back(0.5 * (l + h));
  }
  if (mids.size() < kMinStrips) return std::numeric_limits<double>::quiet_NaN();
  // The median's standard error, from the strips' own scatter (1.4826 MAD, times 1.2533 for a
  // median). Strips that agree measure the edges (0.003-0.023 mm on the profiles and the
  // side panel, noisy scans included); strips that scatter by half a millimetre measure where
  // the scanner stopped seeing (the front panel's noisy scan: 0.17 mm), and their median would
  // move the field by a random tenth. Then the best fit's value, pinned at the part's ends
  // (registration/boundary.hpp), stays.
  constexpr double kMaxStandardErrorMm = 0.05;
  const double median = median_of(mids);
  std::vector<double> spread(mids.size());
  for (std::size_t k = 0; k < mids.size(); ++k) spread[k] = std::abs(mids[k] - median);
  const double standard_error =
      1.4826 * median_of(spread) * 1.2533 / std::sqrt(static_cast<double>(mids.size()));
  return standard_error <= kMaxStandardErrorMm ? median : std::numeric_limits<double>::quiet_NaN();
}

// 5 mm strips first, wider ones where the scan is sparser (the side panel's 200k points over
// 300 x 160 mm leave 1,300 in a 5 mm strip: its free translation went unmeasured, 0.12 mm off).
double edge_shift(const std::vector<Vec3>& scan, const std::vector<Vec3>& cad, const Vec3& d) {
  for (const double strip_mm : {5.0, 10.0, 20.0, 40.0}) {
    const double shift = edge_shift(scan, cad, d, strip_mm);
    if (std::isfinite(shift)) return shift;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// Faces of neither flange nor bend (sheet edges, hole walls, the end faces of a bend zone): the
// motion of the material they bound at the point itself, the nearest flange or bend sample's
// motion_at the control point (in a bend zone's end face: the bend's turn at the point's own
// angle, which the nearest bend control point, up to w away, does not have). Without sample
// faces, the nearest control point of a flange or bend.
void place_other_faces(const FieldRefinementInput& in, const PartMotion& motion,
                       const std::vector<bool>& known, const std::vector<Vec3>& known_points,
                       const std::vector<std::uint32_t>& known_index, FieldPrediction& out) {
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

}  // namespace

FieldPrediction predict_field(const DeformationField& raw, const FieldRefinementInput& in) {
  const std::size_t n = in.model_points.size();
  FieldPrediction out;
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
    const double shift = edge_shift(in.scan_points, in.model_samples, d);
    if (!std::isfinite(shift)) {
      out.translations_from_fit.push_back(d);
      continue;
    }
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

}  // namespace springscan::analysis
