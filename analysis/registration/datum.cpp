// Datum (RPS) alignment: the settings' checks, the gathering of each datum's scan points, the
// datum frame solve and the measure-and-solve passes (datum.hpp).
#include "analysis/registration/datum.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <set>
#include <sstream>

#include "analysis/core/kdtree.hpp"
#include "analysis/core/parallel.hpp"
#include "analysis/core/small_solvers.hpp"
#include "analysis/core/spacing.hpp"
#include "analysis/registration/datum_internal.hpp"

namespace springscan::analysis {
namespace {

using datum_detail::FeatureFit;
using datum_detail::FeaturePoints;
using datum_detail::fixed_directions;

constexpr double kRankRatio = 1e-8;     // a direction's information below this x the largest
constexpr double kConvergedMm = 1e-4;   // a pass moving the frame less than this ends them
constexpr double kOnPlaneMm = 0.05;     // a datum point this close to a flange's skin is on it
constexpr double kParallelDot = 0.999;  // a flange's normal this close to the datum's
// The capture rounds read at most this many scan points (every stride-th): a coarse solve
// needs a few points per square millimetre of skin, not the laser's full density.
constexpr std::size_t kCapturePoints = 200'000;
constexpr std::size_t kMinCapturePoints = 6;  // a feature's points in the strided capture

// Every how many scan points the capture rounds read one (at most kCapturePoints in all).
std::size_t capture_stride(std::size_t scan_points) {
  return std::max<std::size_t>(1, (scan_points + kCapturePoints - 1) / kCapturePoints);
}

std::optional<Error> bad(std::string_view context, const Datum& d, const std::string& what) {
  return fail(ErrorCode::kInvalidSettings,
              std::string(context) + "datum '" + d.name + "' (" + to_string(d.kind) + "): " + what);
}

std::optional<Error> check_datum(const Datum& d, std::string_view context) {
  if (d.name.empty()) return bad(context, d, "needs a name");
  if (!d.point.allFinite() || !d.normal.allFinite() || !d.direction.allFinite())
    return bad(context, d, "non-finite point, normal or direction");
  if (std::abs(d.normal.norm() - 1.0) > 1e-6) return bad(context, d, "normal must be unit");
  const bool needs_direction = d.kind == DatumKind::kSlot || d.kind == DatumKind::kEdge;
  if (needs_direction && d.direction.isZero()) return bad(context, d, "needs a direction");
  if (!d.direction.isZero() &&
      (std::abs(d.direction.norm() - 1.0) > 1e-6 || std::abs(d.direction.dot(d.normal)) > 1e-6))
    return bad(context, d, "direction must be unit and across the normal");
  if (d.kind == DatumKind::kPad && !d.direction.isZero())
    return bad(context, d, "a pad fixes its normal: no direction");
  if ((d.kind == DatumKind::kPad || d.kind == DatumKind::kEdge) && !(d.radius_mm > 0.0))
    return bad(context, d, "radius_mm must be > 0");
  if ((d.kind == DatumKind::kHole || d.kind == DatumKind::kSlot) && !(d.diameter_mm > 0.0))
    return bad(context, d, "diameter_mm must be > 0");
  if (d.kind == DatumKind::kSlot && !(d.length_mm > d.diameter_mm))
    return bad(context, d, "length_mm must exceed the width (diameter_mm)");
  if (!(d.weight > 0.0) || !std::isfinite(d.weight)) return bad(context, d, "weight must be > 0");
  if (!(d.thickness_mm >= 0.0)) return bad(context, d, "thickness_mm must be >= 0");
  return std::nullopt;
}

// The weighted normal matrix of the datums' constraint rows [(m - o) x d, d] at the nominal
// points, rotations scaled by the datums' spread so that the eigenvalues compare.
struct Information {
  Mat6 matrix = Mat6::Zero();
  Vec3 origin = Vec3::Zero();
  double length = 1.0;
};

Information information(const std::vector<Datum>& datums) {
  Information info;
  double weight = 0.0;
  for (const Datum& d : datums) info.origin += d.weight * d.point, weight += d.weight;
  info.origin /= weight;
  double spread = 0.0;
  for (const Datum& d : datums) spread += d.weight * (d.point - info.origin).squaredNorm();
  info.length = std::max(std::sqrt(spread / weight), 1.0);
  for (const Datum& d : datums)
    for (const Vec3& dir : fixed_directions(d)) {
      Vec6 row;
      row << (d.point - info.origin).cross(dir) / info.length, dir;
      info.matrix += d.weight * row * row.transpose();
    }
  return info;
}

// "(0 0 1)": a unit direction to three digits, its largest component positive.
std::string direction_text(Vec3 u) {
  u.normalize();
  Eigen::Index largest;
  u.cwiseAbs().maxCoeff(&largest);
  if (u(largest) < 0.0) u = -u;
  std::ostringstream o;
  o.precision(3);
  o << "(";
  for (int k = 0; k < 3; ++k) o << (k ? " " : "") << (std::abs(u(k)) < 5e-4 ? 0.0 : u(k));
  return o.str() + ")";
}

std::string describe_free(const Vec6& v) {
  const Vec3 rot = v.head<3>(), shift = v.tail<3>();
  if (rot.norm() >= shift.norm()) return "the rotation about " + direction_text(rot);
  return "the translation along " + direction_text(shift);
}

// Which skin's flange a datum lies on: its thickness is the wall's height.
double flange_thickness(const Datum& d, const PartModel& model) {
  for (const Flange& f : model.segmentation.flanges) {
    if (std::abs(f.normal.dot(d.normal)) < kParallelDot) continue;
    const double h = (d.point - f.point).dot(f.normal);
    if (std::abs(h) <= kOnPlaneMm || std::abs(std::abs(h) - f.thickness_mm) <= kOnPlaneMm)
      return f.thickness_mm;
  }
  return 0.0;
}

// The datums' spheres (scan frame) on a coarse grid over their box: per cell, the datums whose
// sphere reaches into it, so that a point is tested against those only (most of a scan lies
// near no datum: 5 sphere tests per point were most of the pass over 1M points).
class SphereGrid {
 public:
  SphereGrid(const std::vector<Vec3>& centres, const std::vector<double>& radii) {
    lo_ = hi_ = centres.front();
    for (std::size_t k = 0; k < centres.size(); ++k) {
      lo_ = lo_.cwiseMin(centres[k] - Vec3::Constant(radii[k]));
      hi_ = hi_.cwiseMax(centres[k] + Vec3::Constant(radii[k]));
    }
    const Vec3 size = hi_ - lo_;
    cell_ = std::max(kMinCellMm, std::cbrt(size.prod() / kMaxCells));
    for (int a = 0; a < 3; ++a) n_[a] = std::max(1, static_cast<int>(std::ceil(size(a) / cell_)));
    masks_.assign(static_cast<std::size_t>(n_[0]) * n_[1] * n_[2], 0);
    // Each sphere marks the cells of its box that it reaches.
    for (std::size_t k = 0; k < centres.size(); ++k) {
      int from[3], to[3];
      for (int a = 0; a < 3; ++a) {
        from[a] = std::max(0, static_cast<int>((centres[k](a) - radii[k] - lo_(a)) / cell_));
        to[a] = std::min(n_[a] - 1, static_cast<int>((centres[k](a) + radii[k] - lo_(a)) / cell_));
      }
      for (int z = from[2]; z <= to[2]; ++z)
        for (int y = from[1]; y <= to[1]; ++y)
          for (int x = from[0]; x <= to[0]; ++x) {
            const Vec3 box_lo = lo_ + cell_ * Vec3(x, y, z);
            const Vec3 nearest =
                centres[k].cwiseMax(box_lo).cwiseMin(box_lo + Vec3::Constant(cell_));
            if ((nearest - centres[k]).squaredNorm() <= radii[k] * radii[k])
              masks_[index(x, y, z)] |= std::uint64_t{1} << k;
          }
    }
  }

  /// The datums whose sphere reaches the cell of `p` (a bit each), 0 outside the box.
  std::uint64_t at(const Vec3& p) const {
    // Written so that a non-finite coordinate is outside too.
    if (!(p.array() >= lo_.array()).all() || !(p.array() < hi_.array()).all()) return 0;
    const Vec3 c = (p - lo_) / cell_;
    return masks_[index(std::min(static_cast<int>(c.x()), n_[0] - 1),
                        std::min(static_cast<int>(c.y()), n_[1] - 1),
                        std::min(static_cast<int>(c.z()), n_[2] - 1))];
  }

  static constexpr std::size_t kMaxDatums = 64;

 private:
  static constexpr double kMinCellMm = 1.0;
  static constexpr double kMaxCells = 32768.0;
  std::size_t index(int x, int y, int z) const {
    return (static_cast<std::size_t>(z) * n_[1] + y) * n_[0] + x;
  }
  Vec3 lo_, hi_;
  double cell_ = 1.0;
  int n_[3] = {1, 1, 1};
  std::vector<std::uint64_t> masks_;
};

// Per datum, the scan points (scan frame, with their normals) within `reach` of its point in
// the frame `T`: one pass over the scan (each datum's sphere carried into the scan frame)
// before the first round, copied once so that the rounds read them in order (an index into
// the scan per point and round cost a cache miss each: 50 ms on 1M points). Later rounds pick
// their points from these (the frame moves less than the search distance).
std::vector<FeaturePoints> within_reach(const std::vector<Vec3>& scan,
                                        const std::vector<Vec3>& normals, const Transform& T,
                                        const std::vector<Datum>& datums,
                                        const std::vector<double>& reach, int threads,
                                        std::size_t stride = 1) {
  const Transform T_inv = T.inverse();
  std::vector<Vec3> centres;
  std::vector<double> r2;
  for (std::size_t k = 0; k < datums.size(); ++k) {
    centres.push_back(T_inv * datums[k].point);
    r2.push_back(reach[k] * reach[k]);
  }
  const std::size_t count = (scan.size() + stride - 1) / stride;
  // Each block copies its points while they are in cache (an index kept and the point read
  // again after the pass missed the cache per point).
  std::vector<std::vector<FeaturePoints>> blocks(block_count(count));
  std::optional<SphereGrid> grid;
  if (datums.size() <= SphereGrid::kMaxDatums) grid.emplace(centres, reach);
  parallel_blocks(count, threads, [&](std::size_t b, std::size_t begin, std::size_t end) {
    auto& mine = blocks[b];
    mine.resize(datums.size());
    const auto keep = [&](std::size_t k, std::size_t i) {
      mine[k].points.push_back(scan[i]);
      if (!normals.empty()) mine[k].normals.push_back(normals[i]);
    };
    for (std::size_t j = begin; j < end; ++j) {
      const Vec3& p = scan[j * stride];
      if (!grid) {
        for (std::size_t k = 0; k < datums.size(); ++k)
          if ((p - centres[k]).squaredNorm() <= r2[k]) keep(k, j * stride);
        continue;
      }
      for (std::uint64_t m = grid->at(p); m != 0; m &= m - 1) {
        const auto k = static_cast<std::size_t>(std::countr_zero(m));
        if ((p - centres[k]).squaredNorm() <= r2[k]) keep(k, j * stride);
      }
    }
  });
  std::vector<FeaturePoints> out(datums.size());
  for (std::size_t k = 0; k < datums.size(); ++k) {
    std::size_t n = 0;
    for (const auto& block : blocks) n += block.empty() ? 0 : block[k].points.size();
    out[k].points.reserve(n);
    if (!normals.empty()) out[k].normals.reserve(n);
    for (const auto& block : blocks) {
      if (block.empty()) continue;
      out[k].points.insert(out[k].points.end(), block[k].points.begin(), block[k].points.end());
      out[k].normals.insert(out[k].normals.end(), block[k].normals.begin(), block[k].normals.end());
    }
  }
  return out;
}

// The datum's points of `candidates` (scan frame) in the CAD frame of `T` within `radius` of
// its point.
// The sphere is tested in the scan frame (a rigid motion keeps distances): only the points kept
// are carried into the CAD frame.
FeaturePoints near_points(const FeaturePoints& candidates, const Transform& T, const Datum& datum,
                          double radius) {
  FeaturePoints near;
  const Vec3 centre = T.inverse() * datum.point;
  const double r2 = radius * radius;
  for (std::size_t i = 0; i < candidates.points.size(); ++i) {
    if ((candidates.points[i] - centre).squaredNorm() > r2) continue;
    near.points.push_back(T * candidates.points[i]);
    if (!candidates.normals.empty()) near.normals.push_back(T.linear() * candidates.normals[i]);
  }
  return near;
}

struct Constraint {
  Vec3 measured, nominal, direction;
  double weight;
};

// The rigid motion that takes every measured point onto its nominal along its direction,
// weighted least squares: Gauss-Newton with exact rotations about the datums' centre.
Transform solve_frame(std::vector<Constraint> c, const Vec3& origin) {
  Transform T = Transform::Identity();
  for (int it = 0; it < 10; ++it) {
    Mat6 A = Mat6::Zero();
    Vec6 b = Vec6::Zero();
    for (const Constraint& k : c) {
      Vec6 row;
      row << (k.measured - origin).cross(k.direction), k.direction;
      A += k.weight * row * row.transpose();
      b -= k.weight * row * k.direction.dot(k.measured - k.nominal);
    }
    const Vec6 x = ldlt_solve(A, b);
    const Vec3 w = x.head<3>();
    Transform step = Transform::Identity();
    if (w.norm() > 0.0) step.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).matrix();
    step.translation() = origin - step.linear() * origin + x.tail<3>();
    for (Constraint& k : c) k.measured = step * k.measured;
    T = step * T;
    if (x.norm() < 1e-13) break;
  }
  return T;
}

Vec3 residual_of(const Datum& d, const Vec3& measured) {
  Vec3 r = Vec3::Zero();
  for (const Vec3& dir : fixed_directions(d)) r += dir.dot(measured - d.point) * dir;
  return r;
}

std::string not_measurable(const Datum& d, const FeatureFit& fit) {
  return "datum '" + d.name + "' (" + to_string(d.kind) + ") cannot be measured: " + fit.failure;
}

}  // namespace

std::string to_string(DatumKind kind) {
  switch (kind) {
    case DatumKind::kPad:
      return "pad";
    case DatumKind::kHole:
      return "hole";
    case DatumKind::kSlot:
      return "slot";
    case DatumKind::kEdge:
      return "edge";
  }
  return "?";
}

std::optional<Error> validate(const DatumAlignmentSettings& s, std::string_view context) {
  const auto range = [&](const std::string& what) {
    return fail(ErrorCode::kInvalidSettings, std::string(context) + what);
  };
  if (!(s.search_mm > 0.0) || !(s.band_mm > 0.0)) return range("search_mm and band_mm must be > 0");
  if (!(s.capture_mm >= 0.0) || s.capture_mm > 50.0) return range("capture_mm must be 0..50");
  if (s.max_capture_rounds < 0) return range("max_capture_rounds must be >= 0");
  if (s.min_points < 3) return range("min_points must be >= 3");
  if (!(s.outlier_sigmas >= 1.0)) return range("outlier_sigmas must be >= 1");
  if (s.min_hole_sectors < 3 || s.min_hole_sectors > 12)
    return range("min_hole_sectors must be 3..12");
  if (s.max_passes < 1) return range("max_passes must be >= 1");
  if (s.datums.empty()) return std::nullopt;
  std::set<std::string> names;
  for (const Datum& d : s.datums) {
    if (auto e = check_datum(d, context)) return e;
    if (!names.insert(d.name).second) return bad(context, d, "the name is used twice");
  }
  const Information info = information(s.datums);
  const SymmetricEigen6 eig = symmetric_eigen(info.matrix);
  if (eig.values(0) <= kRankRatio * eig.values(5))
    return range("the datums leave " + describe_free(eig.vectors.col(0)) +
                 " free: a 3-2-1 set needs three pads, a hole and a second hole, slot or edge");
  return std::nullopt;
}

namespace {

// The datum alignment from the start T_cad_scan_best (method in datum.hpp); `datums` with their
// wall heights resolved.
DatumAlignmentResult align_from(const std::vector<Vec3>& scan,
                                const std::vector<Vec3>& scan_normals,
                                const Transform& T_cad_scan_best, const std::vector<Datum>& datums,
                                const DatumAlignmentSettings& settings);

// Half turns of the CAD part about its principal axes through its centroid (its samples'): the
// rivals of a near-symmetric part's best fit (docs/alignment.md "Near-symmetry").
std::vector<Transform> half_turns(const PartModel& model) {
  const std::vector<Vec3>& pts = model.samples.points;
  if (pts.size() < 3) return {};
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : pts) c += p / static_cast<double>(pts.size());
  Mat3 cov = Mat3::Zero();
  for (const Vec3& p : pts) cov += (p - c) * (p - c).transpose();
  const Mat3 axes = Eigen::SelfAdjointEigenSolver<Mat3>(cov).eigenvectors();
  std::vector<Transform> out;
  for (int k = 2; k >= 0; --k) {
    Transform H = Transform::Identity();
    H.linear() = Eigen::AngleAxisd(std::numbers::pi, axes.col(k)).toRotationMatrix();
    H.translation() = c - H.linear() * c;
    out.push_back(H);
  }
  return out;
}

// How far the whole surface is from the scan placed near a frame: every k-th scan point (at
// most kMisfitPoints) carried by the frame, the frame fitted to the surface by a few
// point-to-plane steps (so that a half turn and its other half are compared each at its own
// fit, not at a pose off by the half turn's own error), then the mean distance of those points
// from the model's nearest sample: along its normal, plus how far beyond kAcrossSpacings
// sample spacings it lies across (a scan point over a hole of the CAD is that far from its rim:
// what tells a part's halves apart), each capped at kMisfitCapMm (springback and strays weigh alike
// in either half).
class SurfaceMisfit {
 public:
  SurfaceMisfit(const PartModel& model, const std::vector<Vec3>& scan) : model_(model) {
    const std::size_t step = std::max<std::size_t>(1, scan.size() / kMisfitPoints);
    for (std::size_t i = 0; i < scan.size(); i += step) scan_.push_back(scan[i]);
    if (model.samples.points.empty()) return;
    tree_.emplace(model.samples.points);
    std::vector<Vec3> probes;
    const std::size_t every = std::max<std::size_t>(1, model.samples.points.size() / 200);
    for (std::size_t i = 0; i < model.samples.points.size(); i += every)
      probes.push_back(model.samples.points[i]);
    spacing_ = median_neighbour_spacing(*tree_, probes);
  }

  /// Per scan point kept, its capped distance at the fitted frame (the same points in the
  /// same order for every frame: the halves are compared point by point).
  std::vector<double> operator()(Transform T) const {
    if (!tree_) return std::vector<double>(scan_.size(), 0.0);
    for (int it = 0; it < kFitSteps; ++it) {
      Mat6 A = Mat6::Zero();
      Vec6 b = Vec6::Zero();
      for (const Vec3& p : scan_) {
        const Vec3 q = T * p;
        Vec3 n;
        const double r = along_normal(q, n);
        if (std::abs(r) > kMisfitCapMm) continue;
        Vec6 row;
        row << q.cross(n), n;
        A += row * row.transpose();
        b -= row * r;
      }
      const Vec6 x = ldlt_solve(A, b);
      if (!x.allFinite()) break;
      Transform step = Transform::Identity();
      const Vec3 w = x.head<3>();
      if (w.norm() > 0.0) step.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).matrix();
      step.translation() = x.tail<3>();
      T = step * T;
    }
    std::vector<double> out;
    out.reserve(scan_.size());
    for (const Vec3& p : scan_) out.push_back(std::min(distance(T * p), kMisfitCapMm));
    return out;
  }

 private:
  static constexpr std::size_t kMisfitPoints = 20'000;
  static constexpr double kMisfitCapMm = 1.0;
  static constexpr int kFitSteps = 6;
  // A surface point lies within this many sample spacings of the nearest sample (of an even
  // random spread, but for 0.2 %).
  static constexpr double kAcrossSpacings = 3.0;

  bool has_normals() const { return model_.samples.normals.size() == model_.samples.points.size(); }

  // The signed distance along the nearest sample's normal (without normals: toward it).
  double along_normal(const Vec3& q, Vec3& n) const {
    const auto hit = tree_->nearest(q);
    if (!hit) return kMisfitCapMm * 2.0;
    const Vec3 v = q - model_.samples.points[hit->index];
    n = has_normals() ? model_.samples.normals[hit->index] : Vec3(v.normalized());
    return v.dot(n);
  }

  double distance(const Vec3& q) const {
    const auto hit = tree_->nearest(q);
    if (!hit) return kMisfitCapMm;
    const Vec3 v = q - model_.samples.points[hit->index];
    if (!has_normals()) return v.norm();
    const double h = v.dot(model_.samples.normals[hit->index]);
    const double across = std::sqrt(std::max(v.squaredNorm() - h * h, 0.0));
    return std::abs(h) + std::max(across - kAcrossSpacings * spacing_, 0.0);
  }

  const PartModel& model_;
  std::vector<Vec3> scan_;
  std::optional<KdTree> tree_;
  double spacing_ = 0.0;
};

// A half turn is taken when the surface fits it better than the other half at the same pose by
// this many standard errors of the paired difference (a symmetric part's halves fit alike, to
// the samples' own asymmetry).
constexpr double kTurnEvidenceSigmas = 5.0;

// The capture reads every stride-th scan point: a feature needs that share of min_points there
// (at least kMinCapturePoints; the search round, on every point, asks for all of them). A small
// pad of a sparse scan (the front panel's 2.5 mm pads, 50 points in all) held fewer than 12 of
// the capture's third.
DatumAlignmentSettings strided(DatumAlignmentSettings s, std::size_t stride) {
  s.min_points =
      std::min(s.min_points, std::max(kMinCapturePoints, (s.min_points + stride - 1) / stride));
  return s;
}

// The datums the scan contradicts at the frame T: each looked for as the capture round does (its
// feature up to capture_mm off, every stride-th point), and not found where the scan shows
// something else instead (a skin facing away from a pad, skin inside a hole's outline). A datum
// merely out of the scan contradicts nothing. Their names, comma separated.
std::string contradicted_datums(const std::vector<Vec3>& scan, const std::vector<Vec3>& normals,
                                const Transform& T, const std::vector<Datum>& datums,
                                const DatumAlignmentSettings& settings) {
  const double capture = std::max(settings.capture_mm, settings.search_mm);
  std::vector<double> reach;
  for (const Datum& d : datums) reach.push_back(datum_detail::capture_radius(d, capture) + capture);
  const std::size_t stride = capture_stride(scan.size());
  const std::vector<FeaturePoints> near =
      within_reach(scan, normals, T, datums, reach, settings.threads, stride);
  std::string names;
  for (std::size_t k = 0; k < datums.size(); ++k) {
    const FeatureFit f =
        datum_detail::capture_feature(datums[k], near_points(near[k], T, datums[k], reach[k]),
                                      capture, strided(settings, stride));
    if (!f.measured && f.contradicted) names += (names.empty() ? "" : ", ") + datums[k].name;
  }
  return names;
}

}  // namespace

Expected<DatumAlignmentResult> align_to_datums(const std::vector<Vec3>& scan,
                                               const std::vector<Vec3>& scan_normals,
                                               const Transform& T_cad_scan_best,
                                               const PartModel& model,
                                               const DatumAlignmentSettings& settings) {
  if (auto e = validate(settings)) return *e;
  if (!scan_normals.empty() && scan_normals.size() != scan.size())
    return fail("alignment: the scan's normals do not match its points");
  std::vector<Datum> datums = settings.datums;
  for (Datum& d : datums) {
    if (d.thickness_mm == 0.0) d.thickness_mm = flange_thickness(d, model);
    // A hole of a surface model is measured by its rim; a slot needs its walls.
    if (d.kind == DatumKind::kSlot && d.thickness_mm <= 0.0)
      return fail(ErrorCode::kAnalysisFailed,
                  "alignment: datum '" + d.name + "' (" + to_string(d.kind) +
                      "): no wall height (no solid flange at its point; set thickness_mm)");
  }
  DatumAlignmentResult out = align_from(scan, scan_normals, T_cad_scan_best, datums, settings);
  if (out.achieved) return out;
  // A near-symmetric part's best fit may lie turned half round (the side panel's, seen all
  // round): its datums are then where the scan shows other features or none. A half turn of
  // the part from which every datum is measured is weighed on two kinds of evidence against the
  // other half at the same pose: the datums (the scan contradicts one of them there: a skin
  // facing away from a pad, skin where a hole should be) and the whole surface (its fit, in
  // standard errors of the paired difference). The datums decide when they tell the halves
  // apart and the surface does not favour the other half; else the surface decides (a part
  // whose halves both carry the datum features, or whose datum is only out of the scan, is not
  // turned on its datums alone). Of several taken, the one the surface fits best. Else the best
  // fit's failure, and why a half turn that measured was not taken.
  std::optional<SurfaceMisfit> misfit;
  std::optional<DatumAlignmentResult> taken;
  double taken_misfit = 0.0;
  std::string refused;
  for (const Transform& H : half_turns(model)) {
    DatumAlignmentResult turned =
        align_from(scan, scan_normals, H * T_cad_scan_best, datums, settings);
    if (!turned.achieved) continue;
    if (!misfit) misfit.emplace(model, scan);
    // The turned frame against the other half at the same datum pose (H is its own inverse):
    // springback's pull on the best fit weighs in neither.
    const Transform other_half = H * turned.T_cad_scan;
    const std::vector<double> here = (*misfit)(turned.T_cad_scan);
    const std::vector<double> there = (*misfit)(other_half);
    // The paired difference (the other half's distance less this one's, point by point): its
    // mean in standard errors. Springback far from the features is capped alike in both, and a
    // symmetric part's halves fit alike: the difference is then the samples' noise.
    double m = 0.0, other = 0.0, sum = 0.0, sum2 = 0.0;
    for (std::size_t i = 0; i < here.size(); ++i) {
      const double d = there[i] - here[i];
      m += here[i], other += there[i], sum += d, sum2 += d * d;
    }
    const auto n = static_cast<double>(std::max<std::size_t>(here.size(), 1));
    m /= n, other /= n;
    const double mean = sum / n;
    const double standard_error = std::sqrt(std::max(sum2 / n - mean * mean, 0.0) / n);
    const double sigmas = mean / std::max(standard_error, 1e-12);
    const std::string against =
        contradicted_datums(scan, scan_normals, other_half, datums, settings);
    const bool by_surface = sigmas > kTurnEvidenceSigmas;
    const bool by_datums = !against.empty() && sigmas > -kTurnEvidenceSigmas;
    if (!by_surface && !by_datums) {
      char fit[120];
      std::snprintf(fit, sizeof fit, "%.4f mm against %.4f mm, %.1f standard errors", m, other,
                    sigmas);
      const std::string why =
          against.empty()
              ? "; turned half round every datum is measured, but the surface fits that half no "
                "better than the other (" +
                    std::string(fit) +
                    ") and no datum tells them apart: the part's halves are not told apart"
              : "; turned half round every datum is measured and the other half contradicts " +
                    against + ", but the surface fits the other half better (" + fit +
                    "): the evidence conflicts";
      if (refused.empty()) refused = why;
      continue;
    }
    if (taken && m >= taken_misfit) continue;
    turned.T_datum_best = turned.T_cad_scan * T_cad_scan_best.inverse();
    turned.rounds.insert(turned.rounds.begin(), DatumRound{"half turn", 0.0, 0.0, 180.0});
    for (const Datum& d : datums)
      turned.rounds.front().moved_mm =
          std::max(turned.rounds.front().moved_mm, (H * d.point - d.point).norm());
    turned.passes = static_cast<int>(turned.rounds.size());
    const Transform back = turned.T_datum_best.inverse();
    for (DatumResult& r : turned.datums)
      r.best_fit_residual = residual_of(r.datum, back * r.measured);
    taken = std::move(turned);
    taken_misfit = m;
  }
  if (taken) return *taken;
  out.failure += refused;
  out.T_cad_scan = T_cad_scan_best;
  return out;
}

namespace {

DatumAlignmentResult align_from(const std::vector<Vec3>& scan,
                                const std::vector<Vec3>& scan_normals,
                                const Transform& T_cad_scan_best, const std::vector<Datum>& datums,
                                const DatumAlignmentSettings& settings) {
  const Information info = information(datums);
  const bool capture = settings.capture_mm > settings.search_mm && settings.max_capture_rounds > 0;
  // The capture rounds read every stride-th scan point (at most kCapturePoints), gathered
  // within their wide reach of the best fit; the later rounds every point within their reach
  // of the captured frame: two passes over the scan, the first a strided one.
  std::vector<double> capture_reach, reach;
  for (const Datum& d : datums) {
    capture_reach.push_back(datum_detail::capture_radius(d, settings.capture_mm) +
                            settings.capture_mm);
    reach.push_back(datum_detail::gather_radius(d, settings.search_mm) + settings.search_mm);
  }
  const std::size_t stride = capture_stride(scan.size());
  std::vector<FeaturePoints> candidates;
  if (capture)
    candidates = within_reach(scan, scan_normals, T_cad_scan_best, datums, capture_reach,
                              settings.threads, stride);
  const DatumAlignmentSettings capture_settings = strided(settings, stride);
  DatumAlignmentResult out;
  out.T_cad_scan = T_cad_scan_best;
  std::vector<FeatureFit> fits;
  // One round: measure every datum (`capture`: the wide search), solve, move the frame.
  // The datums are measured side by side (each from its own points, into its own slot).
  const auto round = [&](const std::string& stage, double band) -> bool {
    fits.assign(datums.size(), FeatureFit{});
    parallel_tasks(datums.size(), settings.threads, [&](std::size_t k) {
      if (stage == "capture") {
        const FeaturePoints near = near_points(candidates[k], out.T_cad_scan, datums[k],
                                               datum_detail::capture_radius(datums[k], band));
        fits[k] = datum_detail::capture_feature(datums[k], near, band, capture_settings);
      } else {
        const FeaturePoints near = near_points(candidates[k], out.T_cad_scan, datums[k],
                                               datum_detail::gather_radius(datums[k], band));
        fits[k] = datum_detail::measure_feature(datums[k], near, band, settings);
      }
    });
    std::vector<Constraint> constraints;
    for (std::size_t k = 0; k < datums.size(); ++k) {
      if (!fits[k].measured) {
        out.failed_datum = datums[k].name;
        out.failure = not_measurable(datums[k], fits[k]);
        return false;
      }
      for (const Vec3& dir : fixed_directions(datums[k]))
        constraints.push_back({fits[k].point, datums[k].point, dir, datums[k].weight});
    }
    const Transform step = solve_frame(std::move(constraints), info.origin);
    out.T_cad_scan = step * out.T_cad_scan;
    for (FeatureFit& f : fits) f.point = step * f.point, f.normal = step.linear() * f.normal;
    DatumRound r{stage, band, 0.0,
                 Eigen::AngleAxisd(step.linear()).angle() * 180.0 / std::numbers::pi};
    for (const Datum& d : datums)
      r.moved_mm = std::max(r.moved_mm, (step * d.point - d.point).norm());
    out.rounds.push_back(r);
    out.passes = static_cast<int>(out.rounds.size());
    return true;
  };
  // A datum not measurable: the best fit, and why (the caller fails the verdict).
  const auto not_achieved = [&] {
    out.achieved = false;
    out.T_cad_scan = T_cad_scan_best;
    out.T_datum_best = Transform::Identity();
    return out;
  };
  for (int k = 0; capture && k < settings.max_capture_rounds; ++k) {
    if (!round("capture", settings.capture_mm)) return not_achieved();
    if (out.rounds.back().moved_mm < 0.5 * settings.search_mm) break;
  }
  candidates = within_reach(scan, scan_normals, out.T_cad_scan, datums, reach, settings.threads);
  for (int pass = 0; pass < settings.max_passes; ++pass) {
    if (!round(pass == 0 ? "search" : "narrow", pass == 0 ? settings.search_mm : settings.band_mm))
      return not_achieved();
    const double moved = out.rounds.back().moved_mm;
    if (pass > 0 && moved < kConvergedMm) break;
  }
  out.T_datum_best = out.T_cad_scan * T_cad_scan_best.inverse();
  const Transform back = out.T_datum_best.inverse();
  for (std::size_t k = 0; k < datums.size(); ++k) {
    DatumResult r;
    r.datum = datums[k];
    r.measured = fits[k].point;
    r.measured_normal = fits[k].normal;
    r.measured_diameter_mm = fits[k].diameter_mm;
    r.residual = residual_of(datums[k], fits[k].point);
    r.best_fit_residual = residual_of(datums[k], back * fits[k].point);
    r.constraints = static_cast<int>(fixed_directions(datums[k]).size());
    r.points = fits[k].points;
    r.fit_rms_mm = fits[k].rms_mm;
    r.measured_by = fits[k].measured_by;
    out.datums.push_back(std::move(r));
  }
  return out;
}

}  // namespace

}  // namespace springscan::analysis
