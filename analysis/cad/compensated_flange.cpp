// One flange's planar faces refitted together (compensated_internal.hpp fit_flange): a flange the
// field moved rigidly stays one flange, its sides parallel and each side one plane, however
// noisy the field (the segmentation merges a side's faces only within 0.02 mm and 0.5 degrees,
// docs/cad-model.md, tighter than the field's noise on a sparse scan).
#include <BRep_Tool.hxx>
#include <Eigen/Eigenvalues>
#include <GeomAdaptor_Surface.hxx>
#include <algorithm>
#include <cmath>

#include "analysis/cad/compensated_internal.hpp"

namespace springscan::analysis::compensated {
namespace {

// Faces whose old planes coincide are one side of the sheet (within this, mm).
constexpr double kSamePlaneMm = 0.05;

struct Side {
  Vec3 old_normal = Vec3::Zero();  // the first face's old normal (Pu x Pv)
  double old_offset = 0.0;         // old_normal . (a point of the old plane)
  Vec3 mean = Vec3::Zero();        // weighted mean of the moved samples
  double weight = 0.0;
};

Vec3 v3(const gp_XYZ& p) { return {p.X(), p.Y(), p.Z()}; }
double weight(const FaceSample& s) {
  return 1.0 / std::max(s.allowance_mm * s.allowance_mm, 1e-12);
}

// The side of the sheet a face lies on: an existing one with its old plane, else a new one.
std::size_t side_of(const gp_Ax3& plane, std::vector<Side>& sides) {
  const Vec3 normal = v3(plane.XDirection().XYZ()).cross(v3(plane.YDirection().XYZ()));
  const Vec3 point = v3(plane.Location().XYZ());
  for (std::size_t i = 0; i < sides.size(); ++i) {
    const double along = sides[i].old_normal.dot(normal);
    if (std::abs(std::abs(along) - 1.0) < 1e-6 &&
        std::abs(sides[i].old_normal.dot(point) - sides[i].old_offset) < kSamePlaneMm)
      return i;
  }
  sides.push_back({normal, normal.dot(point)});
  return sides.size() - 1;
}

}  // namespace

bool fit_flange(const std::vector<TopoDS_Face>& faces,
                const std::vector<const std::vector<FaceSample>*>& samples,
                const CompensatedShapeSettings& settings, std::vector<FaceFit>& fits,
                double& worst) {
  std::vector<Side> sides;
  std::vector<std::size_t> side(faces.size());
  std::vector<gp_Ax3> old(faces.size());
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const GeomAdaptor_Surface surface(BRep_Tool::Surface(faces[f]));
    if (surface.GetType() != GeomAbs_Plane || samples[f]->empty()) return false;
    old[f] = surface.Plane().Position();
    side[f] = side_of(old[f], sides);
    for (const FaceSample& s : *samples[f]) {
      sides[side[f]].mean += weight(s) * s.moved;
      sides[side[f]].weight += weight(s);
    }
  }
  for (Side& s : sides) s.mean /= s.weight;
  // One normal for all sides: the pooled scatter about each side's own mean.
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (const FaceSample& s : *samples[f]) {
      const Vec3 d = s.moved - sides[side[f]].mean;
      scatter += weight(s) * d * d.transpose();
    }
  const Vec3 normal = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvectors().col(0);
  worst = 0.0;
  std::vector<FaceSample> all;
  std::vector<double> residual;
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (const FaceSample& s : *samples[f]) {
      all.push_back(s);
      residual.push_back(std::abs(normal.dot(s.moved - sides[side[f]].mean)));
      worst = std::max(worst, residual.back());
    }
  if (!within_allowance(all, residual, settings)) return false;
  fits.clear();
  for (std::size_t f = 0; f < faces.size(); ++f) {
    fits.push_back(plane_surface(old[f], sides[side[f]].mean, normal));
    fits.back().canonical_deviation_mm = fits.back().max_deviation_mm = worst;
  }
  return true;
}

}  // namespace springscan::analysis::compensated
