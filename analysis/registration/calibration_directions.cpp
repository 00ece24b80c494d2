// The directions a head's view leaves free (analysis/registration/calibration.hpp).
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cstdio>

#include "analysis/registration/calibration.hpp"

namespace springscan::analysis {
namespace {

std::string vector_text(const Vec3& v) {
  char text[64];
  std::snprintf(text, sizeof text, "(%.3f, %.3f, %.3f)", v.x(), v.y(), v.z());
  return text;
}

}  // namespace

std::vector<CalibrationFreeDirection> free_directions(const Eigen::Matrix<double, 6, 6>& H,
                                                      double radius_mm, const Vec3& centre,
                                                      double min_ratio, double* weakest) {
  // Scaled by the radius, a rotation of 1/radius rad moves the view's points about 1 mm, as a
  // 1 mm translation does: the eigenvalues then compare like with like.
  Eigen::Matrix<double, 6, 6> D = Eigen::Matrix<double, 6, 6>::Identity();
  D.diagonal().head<3>().setConstant(1.0 / std::max(radius_mm, 1e-9));
  const Eigen::Matrix<double, 6, 6> scaled = D * H * D;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(scaled);
  const double strongest = eig.eigenvalues()[5];
  const auto ratio = [&](int j) { return strongest > 0 ? eig.eigenvalues()[j] / strongest : 0.0; };
  if (weakest) *weakest = ratio(0);
  std::vector<CalibrationFreeDirection> out;
  for (int j = 0; j < 6 && ratio(j) < min_ratio; ++j) {
    const Eigen::Matrix<double, 6, 1> v = eig.eigenvectors().col(j);
    CalibrationFreeDirection f;
    f.rotation = v.head<3>().norm() > v.tail<3>().norm();
    f.axis = (f.rotation ? Vec3(v.head<3>()) : Vec3(v.tail<3>())).normalized();
    f.centre = centre;
    f.ratio = ratio(j);
    f.description =
        f.rotation ? "rotation about " + vector_text(f.axis) + " through " + vector_text(f.centre)
                   : "translation along " + vector_text(f.axis);
    out.push_back(f);
  }
  return out;
}

}  // namespace springscan::analysis
