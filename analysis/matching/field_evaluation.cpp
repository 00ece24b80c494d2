// The deformation field at arbitrary points by local linear regression (field_evaluation.hpp).
#include "analysis/matching/field_evaluation.hpp"

#include <algorithm>
#include <cmath>

#include "analysis/core/kdtree.hpp"
#include "analysis/core/spacing.hpp"

namespace springscan::analysis {
namespace {

// Relative weight of the ridge on the gradient: small enough to leave a gradient the neighbours
// span (a turning flange), large enough to keep the 4x4 system regular on a flat patch.
constexpr double kRidge = 1e-3;

// The weighted rms of the vectors about the fitted d_i = a + B (p_i - x) (the same weights).
double spread(const DeformationField& field, const std::vector<Vec3>& anchors,
              const std::vector<Neighbor>& near, const Vec3& x, double sigma,
              const Eigen::Matrix<double, 4, 3>& solution) {
  if (!(sigma > 0.0)) return 0.0;
  double sum = 0.0, weight_sum = 0.0;
  for (const Neighbor& n : near) {
    const double w = std::exp(-n.squared_distance / (2.0 * sigma * sigma));
    Eigen::Vector4d row;
    row << 1.0, Vec3((anchors[n.index] - x) / sigma);
    const Vec3 fitted = solution.transpose() * row;
    sum += w * (field.vectors[n.index].displacement() - fitted).squaredNorm();
    weight_sum += w;
  }
  return weight_sum > 0.0 ? std::sqrt(sum / weight_sum) : 0.0;
}

}  // namespace

FieldAtPoints evaluate_field(const DeformationField& field, const std::vector<Vec3>& points,
                             const FieldEvaluationSettings& settings) {
  FieldAtPoints out;
  out.deformation.assign(points.size(), Vec3::Zero());
  out.covered.assign(points.size(), false);
  out.support.assign(points.size(), 0);
  out.spread_mm.assign(points.size(), 0.0);
  if (field.vectors.empty()) return out;
  std::vector<Vec3> anchors;
  anchors.reserve(field.vectors.size());
  for (const auto& v : field.vectors) anchors.push_back(v.model);
  const KdTree tree(anchors);
  const double sigma = settings.smoothing_radius_mm > 0.0
                           ? settings.smoothing_radius_mm
                           : settings.spacing_factor * median_neighbour_spacing(tree, anchors);
  out.smoothing_radius_mm = sigma;
  std::vector<Neighbor> near;
  for (std::size_t k = 0; k < points.size(); ++k) {
    const Vec3& x = points[k];
    if (sigma > 0.0) {
      tree.radius(x, 3.0 * sigma, near);
    } else {  // a single field vector: only its own point
      near.clear();
      if (const auto own = tree.nearest(x, 1e-9)) near.push_back(*own);
    }
    if (near.empty()) continue;
    // Weighted least squares for (a, B) in d_i = a + B (p_i - x), scaled by sigma.
    Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
    Eigen::Matrix<double, 4, 3> rhs = Eigen::Matrix<double, 4, 3>::Zero();
    double weight_sum = 0.0;
    for (const Neighbor& n : near) {
      const double w = sigma > 0.0 ? std::exp(-n.squared_distance / (2.0 * sigma * sigma)) : 1.0;
      Eigen::Vector4d row;
      row << 1.0, sigma > 0.0 ? Vec3((anchors[n.index] - x) / sigma) : Vec3::Zero();
      normal += w * row * row.transpose();
      rhs += w * row * field.vectors[n.index].displacement().transpose();
      weight_sum += w;
    }
    normal.bottomRightCorner<3, 3>() += kRidge * weight_sum * Eigen::Matrix3d::Identity();
    const Eigen::Matrix<double, 4, 3> solution = normal.ldlt().solve(rhs);
    out.deformation[k] = solution.row(0).transpose();
    for (const Vec3& free : settings.free_directions)
      out.deformation[k] -= out.deformation[k].dot(free) * free;
    out.covered[k] = true;
    out.support[k] = static_cast<int>(near.size());
    out.spread_mm[k] = spread(field, anchors, near, x, sigma, solution);
  }
  return out;
}

}  // namespace springscan::analysis
