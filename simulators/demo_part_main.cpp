// springscan-demo-part: writes the bundled demo part (demo/) with the project's own code:
// the nominal CAD of a hat profile (STEP, through OpenCASCADE) and a simulated laser scan of
// the part as produced, with a known springback per bend, noise and a pose the analysis must
// recover. demo/README.md records the command and the ground truth.
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/io/point_io.hpp"
#include "simulators/parts/cad_profile.hpp"
#include "simulators/parts/sheet_part.hpp"

namespace {

using namespace springscan::analysis;
using namespace springscan::parts;

struct DemoOptions {
  std::string out_dir = "demo";
  std::string surface_path;  // when set: only write the produced part's dense, noise-free surface
  std::vector<double> springback_deg = {1.5, 0.8, 1.1, 0.4};  // one per bend of the hat
  long points = 60000;
  double noise_mm = 0.02;
};

// "1.5,0.8" -> {1.5, 0.8}; an empty result when any item is not a number.
std::vector<double> parse_list(const std::string& text) {
  std::vector<double> values;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    double value = 0.0;
    const auto [end, error] = std::from_chars(item.data(), item.data() + item.size(), value);
    if (error != std::errc() || end != item.data() + item.size()) return {};
    values.push_back(value);
  }
  return values;
}

// The demo hat profile: 25 mm brims, 30 mm walls, a 40 mm top, 60 degree bends of R4, 80 mm
// wide. Sloped walls (not 90 degrees) so that a laser line looking along the sheet normal sees
// every flange, as on a real station that scans a press part from above.
ProfileSpec demo_profile() {
  ProfileSpec spec = hat_profile(25.0, 30.0, 40.0, 60.0, 4.0);
  spec.width_mm = 80.0;
  return spec;
}

// A pose far from the CAD frame, so that the demo exercises the PCA + ICP global fit.
Transform demo_pose() {
  Transform T = Transform::Identity();
  T.linear() = (Eigen::AngleAxisd(0.6, Vec3(0.2, 0.3, 1.0).normalized()) *
                Eigen::AngleAxisd(-0.25, Vec3::UnitX()))
                   .toRotationMatrix();
  T.translation() = Vec3(120.0, -35.0, 410.0);
  return T;
}

// The part as produced, densely and without noise: the surface the simulated scanner measures
// (springscan-scanner-sim --part FILE) in the station demo.
int write_surface(const DemoOptions& options) {
  ScanSimulationSettings dense;
  dense.point_count = 400000;
  dense.noise_sigma_mm = 0.0;
  auto surface = simulate_scan(demo_profile(), options.springback_deg, dense);
  if (!surface) {
    std::cerr << "springscan-demo-part: " << surface.message() << '\n';
    return 1;
  }
  if (auto written = write_point_cloud(options.surface_path, *surface); !written) {
    std::cerr << "springscan-demo-part: " << written.message() << '\n';
    return 1;
  }
  return 0;
}

int run(const DemoOptions& options) {
  if (!options.surface_path.empty()) return write_surface(options);
  const ProfileSpec spec = demo_profile();
  const std::string cad_path = options.out_dir + "/hat-profile.step";
  if (auto written = write_profile_cad(spec, cad_path); !written) {
    std::cerr << "springscan-demo-part: " << written.message() << '\n';
    return 1;
  }
  ScanSimulationSettings scan_settings;
  scan_settings.point_count = options.points;
  scan_settings.noise_sigma_mm = options.noise_mm;
  scan_settings.outlier_fraction = 0.005;
  scan_settings.T_scan_part = demo_pose();
  auto scan = simulate_scan(spec, options.springback_deg, scan_settings);
  if (!scan) {
    std::cerr << "springscan-demo-part: " << scan.message() << '\n';
    return 1;
  }
  PointWriteOptions write_options;
  write_options.single_precision = true;
  const std::string scan_path = options.out_dir + "/hat-profile-scan.ply";
  if (auto written = write_point_cloud(scan_path, *scan, write_options); !written) {
    std::cerr << "springscan-demo-part: " << written.message() << '\n';
    return 1;
  }
  std::cout << "wrote " << cad_path << " and " << scan_path << " (" << scan->size()
            << " points, springback";
  for (double s : options.springback_deg) std::cout << ' ' << s;
  std::cout << " deg)\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  DemoOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--surface" && has_value) {
      options.surface_path = argv[++i];
    } else if (arg == "--out" && has_value) {
      options.out_dir = argv[++i];
    } else if (arg == "--springback" && has_value) {
      options.springback_deg = parse_list(argv[++i]);
      if (options.springback_deg.empty()) {
        std::cerr << "springscan-demo-part: --springback expects numbers like 1.5,0.8,1.1,0.4\n";
        return 2;
      }
    } else if (arg == "--points" && has_value) {
      options.points = std::atol(argv[++i]);
      if (options.points <= 0) {
        std::cerr << "springscan-demo-part: --points expects a positive number\n";
        return 2;
      }
    } else {
      std::cerr << "usage: springscan-demo-part [--out DIR | --surface FILE] "
                   "[--springback S1,S2,S3,S4] [--points N]\n";
      return 2;
    }
  }
  return run(options);
}
