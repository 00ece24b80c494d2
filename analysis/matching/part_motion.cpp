// Rigid motions of flanges and bend zones from the bend table (part_motion.hpp).
#include "analysis/matching/part_motion.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <deque>
#include <numbers>

#include "analysis/core/small_solvers.hpp"

namespace springscan::analysis {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// The turn by `angle_rad` about the line through `point` along the unit `axis`.
Transform turn_about(const Vec3& point, const Vec3& axis, double angle_rad) {
  return Eigen::Translation3d(point) * Eigen::AngleAxisd(angle_rad, axis) *
         Eigen::Translation3d(-point);
}

int index_of_flange(const PartSegmentation& s, int id) {
  for (std::size_t k = 0; k < s.flanges.size(); ++k)
    if (s.flanges[k].id == id) return static_cast<int>(k);
  return -1;
}

const BendMeasurement* measurement_of(const SpringbackResult& r, int bend_id) {
  for (const BendMeasurement& m : r.bends)
    if (m.bend_id == bend_id) return &m;
  return nullptr;
}

const FlangeFit* fit_of(const SpringbackResult& r, int flange_id) {
  for (const FlangeFit& f : r.flanges)
    if (f.flange_id == flange_id && f.fitted) return &f;
  return nullptr;
}

// The bend's axis oriented so that the nominal turn from flange_a to flange_b is positive (the
// measurement's convention), its flanges, and the CAD geometry when it was not measured.
struct BendFrame {
  Vec3 point = Vec3::Zero();
  Vec3 axis = Vec3::UnitX();
  int a = -1, b = -1;  // flange indices
};

BendFrame bend_frame(const PartSegmentation& s, const SpringbackResult& r, std::size_t k) {
  const Bend& bend = s.bends[k];
  BendFrame f;
  const BendMeasurement* m = measurement_of(r, bend.id);
  f.point = m ? m->axis_point : bend.axis_point;
  f.axis = (m ? m->axis_direction : bend.axis_direction).normalized();
  f.a = index_of_flange(s, m ? m->flange_a : bend.flange_a);
  f.b = index_of_flange(s, m ? m->flange_b : bend.flange_b);
  return f;
}

// The chain: the root stays, each flange reached through a bend turns about its axis.
// measured[f]: every bend on f's chain was measured.
std::vector<Transform> chain(const PartSegmentation& s, const SpringbackResult& r,
                             const std::vector<double>& turn,
                             const std::vector<bool>& bend_measured, int root,
                             std::vector<bool>& measured) {
  std::vector<Transform> T(s.flanges.size(), Transform::Identity());
  std::vector<bool> placed(s.flanges.size(), false);
  measured.assign(s.flanges.size(), false);
  measured[static_cast<std::size_t>(root)] = true;
  std::deque<int> queue{root};
  placed[static_cast<std::size_t>(root)] = true;
  while (!queue.empty()) {
    const int f = queue.front();
    queue.pop_front();
    for (std::size_t k = 0; k < s.bends.size(); ++k) {
      const BendFrame bf = bend_frame(s, r, k);
      if (bf.a < 0 || bf.b < 0) continue;
      // K_b = K_a * R(turn) about the CAD axis: b turns relative to a.
      int next = -1;
      Transform T_next;
      if (bf.a == f && !placed[static_cast<std::size_t>(bf.b)]) {
        next = bf.b;
        T_next = T[static_cast<std::size_t>(f)] * turn_about(bf.point, bf.axis, turn[k]);
      } else if (bf.b == f && !placed[static_cast<std::size_t>(bf.a)]) {
        next = bf.a;
        T_next = T[static_cast<std::size_t>(f)] * turn_about(bf.point, bf.axis, -turn[k]);
      }
      if (next < 0) continue;
      T[static_cast<std::size_t>(next)] = T_next;
      placed[static_cast<std::size_t>(next)] = true;
      measured[static_cast<std::size_t>(next)] =
          measured[static_cast<std::size_t>(f)] && bend_measured[k];
      queue.push_back(next);
    }
  }
  return T;
}

// Point-to-plane Gauss-Newton for G: G * K_f * x on the plane of flange f's local fit. The
// directions no flange plane constrains (along the bend lines of an extrusion) keep the best
// fit's value: their eigenvalues are dropped.
Transform fit_correction(const std::vector<Vec3>& y, const std::vector<Vec3>& z,
                         const std::vector<Vec3>& n) {
  Transform G = Transform::Identity();
  if (y.size() < 3) return G;
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : z) c += p;
  c /= static_cast<double>(z.size());
  double L2 = 0.0;
  for (const Vec3& p : z) L2 += (p - c).squaredNorm();
  const double L = std::max(std::sqrt(L2 / static_cast<double>(z.size())), 1e-6);
  for (int iteration = 0; iteration < 4; ++iteration) {
    Mat6 H = Mat6::Zero();
    Vec6 g = Vec6::Zero();
    for (std::size_t i = 0; i < y.size(); ++i) {
      const Vec3 p = G * y[i] - c;
      Vec6 J;
      J << p.cross(n[i]) / L, n[i];
      const double res = n[i].dot(p + c - z[i]);
      H += J * J.transpose();
      g += J * res;
    }
    const SymmetricEigen6 eig = symmetric_eigen(H);
    const Vec6 rhs = eig.vectors.transpose() * (-g);
    const double top = eig.values.maxCoeff();
    Vec6 x = Vec6::Zero();
    for (int k = 0; k < 6; ++k)
      if (eig.values(k) > 1e-4 * top) x += eig.vectors.col(k) * (rhs(k) / eig.values(k));
    const Vec3 w = x.head<3>() / L;
    Transform step = Transform::Identity();
    if (w.norm() > 0.0) step = turn_about(c, w.normalized(), w.norm());
    step.pretranslate(x.tail<3>());
    G = step * G;
    if (x.norm() < 1e-10) break;
  }
  return G;
}

// Fills out.face_flange and out.face_bend (CAD face id -> flange / bend index, -1: neither);
// returns the number of face ids.
int index_faces(const PartSegmentation& s, PartMotion& out) {
  int faces = 0;
  for (const Flange& f : s.flanges)
    for (int id : f.face_ids) faces = std::max(faces, id + 1);
  for (const Bend& b : s.bends)
    for (int id : b.face_ids) faces = std::max(faces, id + 1);
  out.face_flange.assign(static_cast<std::size_t>(faces), -1);
  out.face_bend.assign(static_cast<std::size_t>(faces), -1);
  for (std::size_t k = 0; k < s.flanges.size(); ++k)
    for (int id : s.flanges[k].face_ids)
      out.face_flange[static_cast<std::size_t>(id)] = static_cast<int>(k);
  for (std::size_t k = 0; k < s.bends.size(); ++k)
    for (int id : s.bends[k].face_ids)
      out.face_bend[static_cast<std::size_t>(id)] = static_cast<int>(k);
  return faces;
}

}  // namespace

PartMotion part_motion(const PartSegmentation& s, const SpringbackResult& r,
                       const std::vector<Vec3>& points, const std::vector<Vec3>& normals,
                       const std::vector<int>& face_ids) {
  PartMotion out;
  const int faces = index_faces(s, out);

  // The root: the largest fitted flange.
  out.flange_fitted.assign(s.flanges.size(), false);
  for (std::size_t k = 0; k < s.flanges.size(); ++k) {
    out.flange_fitted[k] = fit_of(r, s.flanges[k].id) != nullptr;
    if (out.flange_fitted[k] &&
        (out.root_flange < 0 ||
         s.flanges[k].area_mm2 > s.flanges[static_cast<std::size_t>(out.root_flange)].area_mm2))
      out.root_flange = static_cast<int>(k);
  }
  out.bend_turn_rad.assign(s.bends.size(), 0.0);
  out.bend_measured.assign(s.bends.size(), false);
  for (std::size_t k = 0; k < s.bends.size(); ++k) {
    const BendMeasurement* m = measurement_of(r, s.bends[k].id);
    // The bend opened by springback: b turns back by it relative to a (measurement convention:
    // the nominal turn a -> b is positive about axis_direction).
    if (m && m->measured && std::isfinite(m->springback_deg)) {
      out.bend_turn_rad[k] = -m->springback_deg * kDeg;
      out.bend_measured[k] = true;
    }
  }
  if (out.root_flange < 0) return out;
  out.usable = true;
  const std::vector<Transform> K =
      chain(s, r, out.bend_turn_rad, out.bend_measured, out.root_flange, out.flange_measured);
  // G rests on measurements only: a flange reached through an unmeasured bend has a guessed
  // chain motion, and its plane would pull G by the guess's error (the cover flange's closed
  // hems: their fits, on a fold lying on the sheet, 0.06 and 0.8 mm off the chain; the whole
  // field moved 0.09 mm).
  for (std::size_t k = 0; k < s.flanges.size(); ++k)
    out.flange_fitted[k] = out.flange_fitted[k] && out.flange_measured[k];

  // G from the control points on fitted flanges: the chain's position against the measured plane.
  std::vector<Vec3> y, z, n;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int face = face_ids[i];
    if (face < 0 || face >= faces) continue;
    const int f = out.face_flange[static_cast<std::size_t>(face)];
    if (f < 0 || !out.flange_fitted[static_cast<std::size_t>(f)]) continue;
    const Transform M =
        fit_of(r, s.flanges[static_cast<std::size_t>(f)].id)->fit.T_model_subset.inverse();
    y.push_back(K[static_cast<std::size_t>(f)] * points[i]);
    z.push_back(M * points[i]);
    n.push_back((M.linear() * normals[i]).normalized());
  }
  out.correction = fit_correction(y, z, n);
  // Free translations from the CAD normals (exact: the measured ones carry the fits' noise) of
  // the flanges G was fitted to: a flange whose fit was rejected (a wall seen edge-on) fixes
  // nothing, and the direction it alone would fix keeps the best fit's value unless it is
  // listed here (the front panel's walls at both ends of its bend lines: 0.6 mm along them).
  Mat3 N = Mat3::Zero();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int face = face_ids[i];
    if (face < 0 || face >= faces) continue;
    const int f = out.face_flange[static_cast<std::size_t>(face)];
    if (f >= 0 && out.flange_fitted[static_cast<std::size_t>(f)])
      N += normals[i] * normals[i].transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Mat3> nn(N);
  for (int k = 0; k < 3; ++k)
    if (nn.eigenvalues()(k) < 1e-6 * nn.eigenvalues().maxCoeff())
      out.free_translations.push_back(nn.eigenvectors().col(k).normalized());
  out.flange.reserve(K.size());
  for (const Transform& k : K) out.flange.push_back(out.correction * k);
  return out;
}

bool motion_measured(const PartMotion& motion, const PartSegmentation& s, int face_id) {
  if (!motion.usable || face_id < 0 || face_id >= static_cast<int>(motion.face_flange.size()))
    return false;
  const std::size_t face = static_cast<std::size_t>(face_id);
  if (motion.face_flange[face] >= 0)
    return motion.flange_measured[static_cast<std::size_t>(motion.face_flange[face])];
  const int k = motion.face_bend[face];
  if (k < 0 || !motion.bend_measured[static_cast<std::size_t>(k)]) return false;
  const Bend& bend = s.bends[static_cast<std::size_t>(k)];
  const int a = index_of_flange(s, bend.flange_a), b = index_of_flange(s, bend.flange_b);
  return a >= 0 && b >= 0 && motion.flange_measured[static_cast<std::size_t>(a)] &&
         motion.flange_measured[static_cast<std::size_t>(b)];
}

bool motion_at(const PartMotion& motion, const PartSegmentation& s, const Vec3& p, int face_id,
               Transform& out) {
  if (!motion.usable || face_id < 0 || face_id >= static_cast<int>(motion.face_flange.size()))
    return false;
  const std::size_t face = static_cast<std::size_t>(face_id);
  if (motion.face_flange[face] >= 0) {
    out = motion.flange[static_cast<std::size_t>(motion.face_flange[face])];
    return true;
  }
  const int k = motion.face_bend[face];
  if (k < 0) return false;
  const Bend& bend = s.bends[static_cast<std::size_t>(k)];
  const int a = index_of_flange(s, bend.flange_a);
  const int b = index_of_flange(s, bend.flange_b);
  if (a < 0 || b < 0) return false;
  // Angular position from flange a's tangent line: the radial direction there is a's normal.
  const Vec3 w = bend.axis_direction.normalized();
  const Flange& fa = s.flanges[static_cast<std::size_t>(a)];
  const double side = fa.normal.dot(bend.axis_point - fa.point);
  Vec3 ua = side > 0.0 ? Vec3(-fa.normal) : fa.normal;
  ua -= ua.dot(w) * w;
  Vec3 um = p - bend.axis_point;
  um -= um.dot(w) * w;
  const double phi = std::atan2(ua.cross(um).norm(), ua.dot(um));
  const double span = std::abs(bend.nominal_angle_deg) * kDeg;
  const double t = span > 0.0 ? std::clamp(phi / span, 0.0, 1.0) : 0.5;
  // The turn of b relative to a about the measured axis (its orientation may be the opposite
  // of the CAD bend's, so the turn is applied through the chain's own flanges).
  const Transform& Ta = motion.flange[static_cast<std::size_t>(a)];
  const Transform& Tb = motion.flange[static_cast<std::size_t>(b)];
  const Transform rel = Ta.inverse() * Tb;  // CAD frame: a rotation about the bend axis
  const Eigen::AngleAxisd aa(rel.linear());
  const Vec3 axis_point = bend.axis_point;
  out = Ta * turn_about(axis_point, aa.axis(), aa.angle() * t);
  // A pure turn about the axis keeps the axis point: correct the drift of a non-tree bend.
  const Vec3 drift = rel * axis_point - axis_point;
  out.pretranslate(Ta.linear() * (t * drift));
  return true;
}

}  // namespace springscan::analysis
