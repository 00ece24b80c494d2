#include "simulators/parts/laser_scan.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "analysis/core/parallel.hpp"

namespace springscan::parts {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr std::int32_t kNoTriangle = -1;

// splitmix64: one independent stream per ray, so the scan does not depend on the thread count.
std::uint64_t mix(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
struct RayRandom {
  std::uint64_t state;
  double uniform() {  // (0, 1)
    state = mix(state);
    return (static_cast<double>(state >> 11) + 0.5) * 0x1.0p-53;
  }
  double normal() {
    return std::sqrt(-2.0 * std::log(uniform())) * std::cos(2.0 * std::numbers::pi * uniform());
  }
};

// The pattern's rays: a grid in the view plane (a along the lines, b across them), and per ray
// the nearest front-facing triangle with its depth and barycentric coordinates.
struct Raster {
  Vec3 u, v, w;  // line direction, line step, view direction
  double a0 = 0.0, b0 = 0.0, ha = 1.0, hb = 1.0;
  std::int64_t na = 0, nb = 0;
  std::vector<double> depth;
  std::vector<std::int32_t> triangle;
  std::vector<Eigen::Vector2d> bary;  // weights of vertices 1 and 2
};

struct Pattern {
  Vec3 view, line;
  double ha, hb, max_incidence_deg;
};

// Writes triangle `id` (corners p) into every ray of the pattern it is the nearest hit of.
void draw(Raster& r, const std::array<Vec3, 3>& p, std::int32_t id) {
  const Eigen::Vector2d q0(p[0].dot(r.u), p[0].dot(r.v)), q1(p[1].dot(r.u), p[1].dot(r.v)),
      q2(p[2].dot(r.u), p[2].dot(r.v));
  const Eigen::Vector2d e1 = q1 - q0, e2 = q2 - q0;
  const double det = e1.x() * e2.y() - e2.x() * e1.y();
  if (std::abs(det) < 1e-18) return;  // seen edge-on
  const double z0 = p[0].dot(r.w), z1 = p[1].dot(r.w), z2 = p[2].dot(r.w);
  const Eigen::Vector2d lo = q0.cwiseMin(q1).cwiseMin(q2), hi = q0.cwiseMax(q1).cwiseMax(q2);
  const auto first = [](double x, double x0, double h) {
    return static_cast<std::int64_t>(std::ceil((x - x0) / h - 0.5));
  };
  const auto last = [](double x, double x0, double h) {
    return static_cast<std::int64_t>(std::floor((x - x0) / h - 0.5));
  };
  const std::int64_t i0 = std::max<std::int64_t>(0, first(lo.x(), r.a0, r.ha));
  const std::int64_t i1 = std::min<std::int64_t>(r.na - 1, last(hi.x(), r.a0, r.ha));
  const std::int64_t j0 = std::max<std::int64_t>(0, first(lo.y(), r.b0, r.hb));
  const std::int64_t j1 = std::min<std::int64_t>(r.nb - 1, last(hi.y(), r.b0, r.hb));
  for (std::int64_t j = j0; j <= j1; ++j) {
    const double b = r.b0 + (static_cast<double>(j) + 0.5) * r.hb - q0.y();
    for (std::int64_t i = i0; i <= i1; ++i) {
      const double a = r.a0 + (static_cast<double>(i) + 0.5) * r.ha - q0.x();
      const double l1 = (a * e2.y() - e2.x() * b) / det;
      const double l2 = (e1.x() * b - a * e1.y()) / det;
      constexpr double kEdge = -1e-12;  // rays on a shared edge hit both triangles: no cracks
      if (l1 < kEdge || l2 < kEdge || 1.0 - l1 - l2 < kEdge) continue;
      const double z = z0 + l1 * (z1 - z0) + l2 * (z2 - z0);
      const auto cell = static_cast<std::size_t>(j * r.na + i);
      if (z >= r.depth[cell]) continue;
      r.depth[cell] = z;
      r.triangle[cell] = id;
      r.bary[cell] = {l1, l2};
    }
  }
}

Expected<Raster> rasterize(const ProducedPart& part, const Pattern& pattern) {
  Raster r;
  r.w = pattern.view.normalized();
  r.u = (pattern.line - pattern.line.dot(r.w) * r.w).normalized();
  r.v = r.w.cross(r.u);
  const auto& verts = part.mesh.vertices;
  double amin = std::numeric_limits<double>::infinity(), amax = -amin, bmin = amin, bmax = -amin;
  for (const auto& p : verts) {
    amin = std::min(amin, p.dot(r.u)), amax = std::max(amax, p.dot(r.u));
    bmin = std::min(bmin, p.dot(r.v)), bmax = std::max(bmax, p.dot(r.v));
  }
  r.ha = pattern.ha, r.hb = pattern.hb;
  r.na = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil((amax - amin) / r.ha)));
  r.nb = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil((bmax - bmin) / r.hb)));
  if (static_cast<double>(r.na) * static_cast<double>(r.nb) > 1e8) {
    return fail("laser scan: " + std::to_string(r.na) + " x " + std::to_string(r.nb) +
                " rays is more than 100 million");
  }
  r.a0 = 0.5 * (amin + amax - static_cast<double>(r.na) * r.ha);  // centred on the part
  r.b0 = 0.5 * (bmin + bmax - static_cast<double>(r.nb) * r.hb);
  const auto cells = static_cast<std::size_t>(r.na * r.nb);
  r.depth.assign(cells, std::numeric_limits<double>::infinity());
  r.triangle.assign(cells, kNoTriangle);
  r.bary.assign(cells, Eigen::Vector2d::Zero());
  const double cos_max = std::cos(pattern.max_incidence_deg * kDeg);
  for (std::size_t t = 0; t < part.mesh.triangles.size(); ++t) {
    const auto& tri = part.mesh.triangles[t];
    const Vec3 n = (verts[tri[1]] - verts[tri[0]]).cross(verts[tri[2]] - verts[tri[0]]);
    const double facing = -n.dot(r.w);  // > 0: the triangle faces the scanner
    if (part.solid && facing <= 0.0) continue;
    // An oblique triangle gives no return but still hides what lies behind it.
    const bool seen = std::abs(facing) >= cos_max * n.norm();
    draw(r, {verts[tri[0]], verts[tri[1]], verts[tri[2]]},
         seen ? static_cast<std::int32_t>(t) : kNoTriangle);
  }
  return r;
}

std::int64_t count_hits(const Raster& r) {
  return std::count_if(r.triangle.begin(), r.triangle.end(),
                       [](std::int32_t t) { return t != kNoTriangle; });
}

// The CAD point of a hit, snapped from the chord onto its face's plane or cylinder, and the
// CAD surface normal there (outward).
void cad_hit(const ProducedPart& part, std::size_t t, const Eigen::Vector2d& l, Vec3& q, Vec3& n) {
  const auto& tri = part.cad_mesh.triangles[t];
  const auto& v = part.cad_mesh.vertices;
  q = (1.0 - l.x() - l.y()) * v[tri[0]] + l.x() * v[tri[1]] + l.y() * v[tri[2]];
  n = (v[tri[1]] - v[tri[0]]).cross(v[tri[2]] - v[tri[0]]).normalized();
  const auto face = static_cast<std::size_t>(part.cad_mesh.triangle_faces[t]);
  if (face >= part.faces.size()) return;
  const CadFaceInfo& info = part.faces[face];
  if (info.type == "plane") {
    q -= (q - info.inner_point).dot(info.direction) * info.direction;
    n = info.direction;
  } else if (info.type == "cylinder") {
    const Vec3 rel = q - info.axis_point;
    const Vec3 radial = rel - rel.dot(info.direction) * info.direction;
    if (radial.norm() < 1e-12) return;
    const Vec3 out = radial.normalized();
    q = info.axis_point + rel.dot(info.direction) * info.direction + info.radius_mm * out;
    n = out.dot(n) >= 0.0 ? out : Vec3(-out);
  }
}

struct ScanNoise {
  double sigma_mm = 0.0, outlier_fraction = 0.0, outlier_max_mm = 0.0;
  std::uint64_t seed = 1;
  int threads = 0;
};

// Every hit ray as a scan point (part frame), with noise and outliers.
LaserScan points_of(const ProducedPart& part, const Raster& r, const ScanNoise& noise) {
  std::vector<std::size_t> cells;
  for (std::size_t c = 0; c < r.triangle.size(); ++c) {
    if (r.triangle[c] != kNoTriangle) cells.push_back(c);
  }
  LaserScan scan;
  const std::size_t n = cells.size();
  scan.cloud.points.resize(n);
  scan.cloud.normals.resize(n);
  scan.cloud.face_ids.resize(n);
  scan.cad_points.resize(n);
  scan.outlier.assign(n, 0);
  parallel_blocks(n, noise.threads, [&](std::size_t, std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const std::size_t c = cells[k];
      const auto t = static_cast<std::size_t>(r.triangle[c]);
      Vec3 q, nq;
      cad_hit(part, t, r.bary[c], q, nq);
      const int face = part.cad_mesh.triangle_faces[t];
      const Transform T = part.local_transform(q, face);
      Vec3 normal = T.linear() * nq;
      if (normal.dot(r.w) > 0.0) normal = -normal;  // a shell is seen from either side
      RayRandom rng{noise.seed ^ mix(static_cast<std::uint64_t>(c))};
      Vec3 p = T * q + noise.sigma_mm * rng.normal() * r.w;
      if (noise.outlier_fraction > 0.0 && rng.uniform() < noise.outlier_fraction) {
        p += (2.0 * rng.uniform() - 1.0) * noise.outlier_max_mm * r.w;
        scan.outlier[k] = 1;
      }
      scan.cloud.points[k] = p;
      scan.cloud.normals[k] = normal;
      scan.cloud.face_ids[k] = face;
      scan.cad_points[k] = q;
    }
  });
  scan.outliers = std::count(scan.outlier.begin(), scan.outlier.end(), std::uint8_t{1});
  return scan;
}

// Cuts `fraction` of the seen area out in `patches` discs around random points (view plane).
std::int64_t cut_missing(LaserScan& scan, const Raster& r, double fraction, int patches,
                         std::uint64_t seed) {
  if (fraction <= 0.0 || patches <= 0 || scan.cloud.empty()) return 0;
  const double area = static_cast<double>(scan.cloud.size()) * r.ha * r.hb;
  const double radius = std::sqrt(fraction * area / (std::numbers::pi * patches));
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, scan.cloud.size() - 1);
  std::vector<Eigen::Vector2d> centres;
  for (int i = 0; i < patches; ++i) {
    const Vec3& p = scan.cloud.points[pick(rng)];
    centres.emplace_back(p.dot(r.u), p.dot(r.v));
  }
  std::vector<std::uint32_t> keep;
  for (std::size_t k = 0; k < scan.cloud.size(); ++k) {
    const Eigen::Vector2d q(scan.cloud.points[k].dot(r.u), scan.cloud.points[k].dot(r.v));
    const bool cut = std::any_of(centres.begin(), centres.end(),
                                 [&](const auto& c) { return (q - c).norm() < radius; });
    if (!cut) keep.push_back(static_cast<std::uint32_t>(k));
  }
  const auto missing = static_cast<std::int64_t>(scan.cloud.size() - keep.size());
  std::vector<Vec3> cad;
  std::vector<std::uint8_t> outlier;
  for (auto k : keep) cad.push_back(scan.cad_points[k]), outlier.push_back(scan.outlier[k]);
  scan.cloud = select(scan.cloud, keep);
  scan.cad_points = std::move(cad);
  scan.outlier = std::move(outlier);
  return missing;
}

Expected<bool> check(const LaserScanSettings& s) {
  const auto bad = [](const std::string& field, double value) {
    return fail("laser scan: " + field + " = " + std::to_string(value) + " is out of range");
  };
  if (s.view_direction.norm() < 1e-9) return bad("view_direction norm", s.view_direction.norm());
  const double across = s.line_direction.cross(s.view_direction.normalized()).norm();
  if (across < 1e-6) return bad("line_direction across the view", across);
  if (!(s.line_spacing_mm > 0.0)) return bad("line_spacing_mm", s.line_spacing_mm);
  if (!(s.point_spacing_mm >= 0.0)) return bad("point_spacing_mm", s.point_spacing_mm);
  if (s.point_count < 0) return bad("point_count", static_cast<double>(s.point_count));
  if (!(s.max_incidence_deg > 0.0 && s.max_incidence_deg <= 90.0)) {
    return bad("max_incidence_deg", s.max_incidence_deg);
  }
  if (!(s.noise_sigma_mm >= 0.0)) return bad("noise_sigma_mm", s.noise_sigma_mm);
  if (!(s.outlier_fraction >= 0.0 && s.outlier_fraction <= 0.5)) {
    return bad("outlier_fraction", s.outlier_fraction);
  }
  if (!(s.missing_fraction >= 0.0 && s.missing_fraction <= 0.8)) {
    return bad("missing_fraction", s.missing_fraction);
  }
  return true;
}

}  // namespace

Expected<LaserScan> laser_scan(const ProducedPart& part, const LaserScanSettings& settings) {
  if (part.mesh.triangles.empty() || !part.data) return fail("laser scan: the part has no mesh");
  if (auto ok = check(settings); !ok) return ok.error();
  Pattern pattern{settings.view_direction, settings.line_direction, settings.point_spacing_mm,
                  settings.line_spacing_mm, settings.max_incidence_deg};
  if (pattern.ha == 0.0) pattern.ha = pattern.hb;
  if (settings.point_count > 0) {
    // Spacing from a coarse pass, refined once or twice until the count is within 2 %.
    const double target =
        static_cast<double>(settings.point_count) / (1.0 - settings.missing_fraction);
    Eigen::AlignedBox3d box;
    for (const auto& p : part.mesh.vertices) box.extend(p);
    double h = std::max(box.diagonal().norm() / 256.0, 1e-3);
    for (int pass = 0; pass < 4; ++pass) {
      pattern.ha = pattern.hb = h;
      auto raster = rasterize(part, pattern);
      if (!raster) return raster.error();
      const auto hits = static_cast<double>(count_hits(*raster));
      if (hits == 0.0) break;
      if (pass > 0 && std::abs(hits - target) < 0.02 * target) break;
      h *= std::sqrt(hits / target);
    }
  }
  auto raster = rasterize(part, pattern);
  if (!raster) return raster.error();
  const Raster& r = *raster;
  const ScanNoise noise{settings.noise_sigma_mm, settings.outlier_fraction, settings.outlier_max_mm,
                        settings.seed, settings.threads};
  LaserScan scan = points_of(part, r, noise);
  scan.hits = static_cast<std::int64_t>(std::count_if(r.depth.begin(), r.depth.end(), [](double d) {
    return d < std::numeric_limits<double>::infinity();
  }));
  scan.grazing = scan.hits - static_cast<std::int64_t>(scan.cloud.size());
  scan.missing = cut_missing(scan, r, settings.missing_fraction, settings.missing_patches,
                             mix(settings.seed + 1));
  scan.outliers = std::count(scan.outlier.begin(), scan.outlier.end(), std::uint8_t{1});
  scan.line_spacing_mm = r.hb;
  scan.point_spacing_mm = r.ha;
  scan.lines = r.nb;
  scan.points_per_line = r.na;
  scan.T_scan_part = settings.T_scan_part;
  scan.cloud = transformed(scan.cloud, settings.T_scan_part);
  return scan;
}

Expected<LaserScan> probe_grid(const ProducedPart& part, const ProbeSettings& settings) {
  LaserScanSettings laser;
  laser.view_direction = settings.direction;
  laser.line_direction =
      std::abs(settings.direction.normalized().x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  laser.line_spacing_mm = settings.spacing_mm;
  laser.point_spacing_mm = settings.spacing_mm;
  laser.max_incidence_deg = settings.max_incidence_deg;
  laser.noise_sigma_mm = settings.noise_sigma_mm;
  laser.T_scan_part = settings.T_scan_part;
  laser.seed = settings.seed;
  return laser_scan(part, laser);
}

}  // namespace springscan::parts
