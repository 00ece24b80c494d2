#pragma once
// The bundled demo part (demo/hat-profile.step, demo/README.md): its profile, its springback
// as produced and the pose the demo scan is taken in. One definition for the demo program, the
// hardware-in-the-loop rig, the soak and analysis benches and the tests that rebuild the demo.

#include <Eigen/Geometry>
#include <vector>

#include "analysis/core/point_cloud.hpp"
#include "simulators/parts/sheet_profile.hpp"

namespace springscan::parts {

/// 25 mm brims, 30 mm walls, a 40 mm top, 60 degree bends of R4, 80 mm wide. Sloped walls (not
/// 90 degrees) so that a laser line looking along the sheet normal sees every flange, as on a
/// real station that scans a press part from above.
inline ProfileSpec demo_hat_profile() {
  ProfileSpec spec = hat_profile(25.0, 30.0, 40.0, 60.0, 4.0);
  spec.width_mm = 80.0;
  return spec;
}

/// The springback of each bend of the demo part as produced (deg).
inline const std::vector<double> kDemoHatSpringbackDeg{1.5, 0.8, 1.1, 0.4};

/// A pose far from the CAD frame, so that the demo exercises the PCA + ICP global fit.
inline analysis::Transform demo_hat_pose() {
  analysis::Transform T = analysis::Transform::Identity();
  T.linear() = (Eigen::AngleAxisd(0.6, analysis::Vec3(0.2, 0.3, 1.0).normalized()) *
                Eigen::AngleAxisd(-0.25, analysis::Vec3::UnitX()))
                   .toRotationMatrix();
  T.translation() = analysis::Vec3(120.0, -35.0, 410.0);
  return T;
}

}  // namespace springscan::parts
