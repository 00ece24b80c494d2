// springscan-demo-part: writes the bundled demo part (demo/) with the project's own code:
// the nominal CAD of a hat profile (STEP, through OpenCASCADE) and a simulated laser scan of
// the part as produced, with a known springback per bend, noise and a pose the analysis must
// recover. demo/README.md records the command and the ground truth. With --production CAD it
// writes any segmented CAD part (e.g. the openamr motor bracket) as produced and laser-scanned
// from above (simulators/parts/produced_part.hpp, laser_scan.hpp), with its truth as JSON; with
// --surface FILE as well, the produced part's seen surface for the scanner simulator instead.
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/io/point_io.hpp"
#include "simulators/parts/cad_profile.hpp"
#include "simulators/parts/demo_hat.hpp"
#include "simulators/parts/laser_scan.hpp"
#include "simulators/parts/produced_part.hpp"
#include "simulators/parts/sheet_part.hpp"

namespace {

using namespace springscan::analysis;
using namespace springscan::parts;

struct DemoOptions {
  std::string out_dir = "demo";
  std::string surface_path;    // when set: only write the produced part's dense, noise-free surface
  std::string production_cad;  // when set: scan this CAD part as produced instead of the hat
  std::vector<double> springback_deg = kDemoHatSpringbackDeg;  // one per bend of the hat
  bool springback_given = false;
  long points = 0;         // 0: 60,000 for the hat, 200,000 for a production part
  double tilt_deg = 30.0;  // production part: two passes tilted by +-this about y (0: one pass)
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

// The part as produced, densely and without noise: the surface the simulated scanner measures
// (springscan-scanner-sim --part FILE) in the station demo.
int write_surface(const DemoOptions& options) {
  ScanSimulationSettings dense;
  dense.point_count = 400000;
  dense.noise_sigma_mm = 0.0;
  auto surface = simulate_scan(demo_hat_profile(), options.springback_deg, dense);
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

void write_vec(std::ostream& out, const Vec3& v) {
  out << '[' << v.x() + 0.0 << ", " << v.y() + 0.0 << ", " << v.z() + 0.0 << ']';  // no "-0"
}

void write_transform(std::ostream& out, const Transform& T) {
  out << '[';
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) out << (r + c > 0 ? ", " : "") << T.matrix()(r, c);
  }
  out << ']';
}

// The ground truth of a production-part scan: every bend, the pose, the scan's figures.
void write_truth(std::ostream& out, const std::string& cad, const ProducedPart& part,
                 const LaserScan& scan, const LaserScanSettings& settings, double tilt_deg) {
  out << std::setprecision(12) << "{\n  \"cad\": \"" << cad << "\",\n";
  out << "  \"root_flange\": " << part.report.root_flange << ",\n";
  out << "  \"points\": " << scan.cloud.size() << ",\n";
  out << "  \"noise_sigma_mm\": " << settings.noise_sigma_mm << ",\n";
  out << "  \"outlier_fraction\": " << settings.outlier_fraction << ",\n";
  out << "  \"tilt_deg\": " << tilt_deg << ",\n";
  out << "  \"line_spacing_mm\": " << scan.line_spacing_mm << ",\n";
  out << "  \"T_scan_part\": ";
  write_transform(out, scan.T_scan_part);
  out << ",\n  \"T_cad_scan\": ";
  write_transform(out, scan.T_scan_part.inverse());
  out << ",\n  \"bends\": [";
  for (std::size_t i = 0; i < part.bends.size(); ++i) {
    const BendTruth& b = part.bends[i];
    out << (i > 0 ? "," : "") << "\n    {\"id\": " << b.bend_id
        << ", \"nominal_angle_deg\": " << b.nominal_angle_deg
        << ", \"springback_deg\": " << b.springback_deg
        << ", \"produced_angle_deg\": " << b.produced_angle_deg
        << ", \"hem\": " << (b.hem ? "true" : "false") << ", \"radius_mm\": " << b.radius_mm
        << ", \"flanges\": [" << b.parent_flange << ", " << b.child_flange << "]"
        << ", \"axis_point\": ";
    write_vec(out, b.axis_point);
    out << ", \"axis_direction\": ";
    write_vec(out, b.axis_direction);
    out << '}';
  }
  out << "\n  ]\n}\n";
}

// Default springback of a production part: 0.6 to 2.2 degrees, cycling over the bends.
std::vector<double> production_springback(std::size_t bends) {
  std::vector<double> sb;
  for (std::size_t i = 0; i < bends; ++i) sb.push_back(0.6 + 0.4 * static_cast<double>(i % 5));
  return sb;
}

// One pass from straight above (tilt 0), or two passes tilted by +-tilt_deg about y, merged:
// a hat's vertical walls give no return from above, and each tilted pass sees the inner face
// of one wall (the scan frame's truth, T_scan_part, is the same for both passes).
Expected<LaserScan> scan_passes(const ProducedPart& part, LaserScanSettings settings,
                                double tilt_deg) {
  if (tilt_deg == 0.0) return laser_scan(part, settings);
  const double tilt = tilt_deg * std::numbers::pi / 180.0;
  settings.point_count /= 2;
  settings.line_direction = Vec3::UnitY();
  LaserScan merged;
  for (int side : {1, -1}) {
    settings.view_direction = Vec3(side * std::sin(tilt), 0.0, -std::cos(tilt));
    settings.seed += 1;
    auto pass = laser_scan(part, settings);
    if (!pass) return pass.error();
    if (merged.cloud.empty()) {
      merged = std::move(*pass);
      continue;
    }
    const auto append = [](auto& to, const auto& from) {
      to.insert(to.end(), from.begin(), from.end());
    };
    append(merged.cloud.points, pass->cloud.points);
    append(merged.cloud.normals, pass->cloud.normals);
    append(merged.cloud.face_ids, pass->cloud.face_ids);
    append(merged.cad_points, pass->cad_points);
    append(merged.outlier, pass->outlier);
    merged.outliers += pass->outliers;
  }
  return merged;
}

// A CAD part as produced and scanned: the part with its bends' truth, the merged passes.
struct ProducedScan {
  ProducedPart part;
  LaserScan scan;
  LaserScanSettings settings;
};

Expected<ProducedScan> produce_and_scan(const DemoOptions& options, LaserScanSettings settings) {
  auto cad = load_cad_part(options.production_cad);
  if (!cad) return cad.error();
  const std::size_t bends = cad->model.segmentation.bends.size();
  const auto springback =
      options.springback_given ? options.springback_deg : production_springback(bends);
  auto part = make_produced_part(cad->model, cad->shape, springback);
  if (!part) return part.error();
  auto scan = scan_passes(*part, settings, options.tilt_deg);
  if (!scan) return scan.error();
  return ProducedScan{std::move(*part), std::move(*scan), settings};
}

int write_truth_file(const std::string& path, const DemoOptions& options, const ProducedScan& p) {
  std::ofstream truth(path);
  write_truth(truth, options.production_cad, p.part, p.scan, p.settings, options.tilt_deg);
  if (truth) return 0;
  std::cerr << "springscan-demo-part: cannot write " << path << '\n';
  return 1;
}

void print_written(const std::string& what, const ProducedScan& p, const std::string& truth) {
  std::cout << "wrote " << what << " (" << p.scan.cloud.size() << " points) and " << truth << " ("
            << p.part.bends.size() << " bends";
  for (const auto& warning : p.part.report.warnings) std::cout << "; " << warning;
  std::cout << ")\n";
}

// The CAD part as produced, scanned from above: OUT/<name>-scan.ply and OUT/<name>-truth.json.
int write_production_part(const DemoOptions& options) {
  LaserScanSettings settings;
  settings.point_count = options.points > 0 ? options.points : 200000;
  settings.noise_sigma_mm = options.noise_mm;
  settings.outlier_fraction = 0.005;
  settings.T_scan_part = demo_hat_pose();
  auto produced = produce_and_scan(options, settings);
  if (!produced) {
    std::cerr << "springscan-demo-part: " << produced.message() << '\n';
    return 1;
  }
  const std::string name = std::filesystem::path(options.production_cad).stem().string();
  const std::string scan_path = options.out_dir + "/" + name + "-scan.ply";
  const std::string truth_path = options.out_dir + "/" + name + "-truth.json";
  PointCloud cloud;
  cloud.points = produced->scan.cloud.points;
  for (int f : produced->scan.cloud.face_ids) cloud.scalars.push_back(f);
  PointWriteOptions write_options;
  write_options.single_precision = true;
  write_options.scalar_name = "face_id";
  if (auto written = write_point_cloud(scan_path, cloud, write_options); !written) {
    std::cerr << "springscan-demo-part: " << written.message() << '\n';
    return 1;
  }
  if (int status = write_truth_file(truth_path, options, *produced)) return status;
  print_written(scan_path, *produced, truth_path);
  return 0;
}

// The CAD part as produced, as the surface the simulated scanner measures (springscan-scanner-sim
// --part FILE): what the passes see of it, dense, noise-free, in the part frame; its truth
// beside it (FILE's stem + "-truth.json").
int write_production_surface(const DemoOptions& options) {
  LaserScanSettings settings;
  settings.point_count = options.points > 0 ? options.points : 600000;
  settings.noise_sigma_mm = 0.0;  // the scanner simulator adds its own noise along its rays
  auto produced = produce_and_scan(options, settings);
  if (!produced) {
    std::cerr << "springscan-demo-part: " << produced.message() << '\n';
    return 1;
  }
  PointCloud cloud;
  cloud.points = produced->scan.cloud.points;
  PointWriteOptions write_options;
  write_options.single_precision = true;
  if (auto written = write_point_cloud(options.surface_path, cloud, write_options); !written) {
    std::cerr << "springscan-demo-part: " << written.message() << '\n';
    return 1;
  }
  const std::filesystem::path surface(options.surface_path);
  const std::string truth_path =
      (surface.parent_path() / (surface.stem().string() + "-truth.json")).string();
  if (int status = write_truth_file(truth_path, options, *produced)) return status;
  print_written(options.surface_path, *produced, truth_path);
  return 0;
}

int run(const DemoOptions& options) {
  if (!options.production_cad.empty())
    return options.surface_path.empty() ? write_production_part(options)
                                        : write_production_surface(options);
  if (!options.surface_path.empty()) return write_surface(options);
  const ProfileSpec spec = demo_hat_profile();
  const std::string cad_path = options.out_dir + "/hat-profile.step";
  if (auto written = write_profile_cad(spec, cad_path); !written) {
    std::cerr << "springscan-demo-part: " << written.message() << '\n';
    return 1;
  }
  ScanSimulationSettings scan_settings;
  scan_settings.point_count = options.points > 0 ? options.points : 60000;
  scan_settings.noise_sigma_mm = options.noise_mm;
  scan_settings.outlier_fraction = 0.005;
  scan_settings.T_scan_part = demo_hat_pose();
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
    } else if (arg == "--production" && has_value) {
      options.production_cad = argv[++i];
    } else if (arg == "--tilt" && has_value) {
      options.tilt_deg = std::atof(argv[++i]);
    } else if (arg == "--out" && has_value) {
      options.out_dir = argv[++i];
    } else if (arg == "--springback" && has_value) {
      options.springback_deg = parse_list(argv[++i]);
      options.springback_given = true;
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
                   "[--production CAD.step [--tilt DEG]] [--springback S1,S2,...] [--points N]\n";
      return 2;
    }
  }
  return run(options);
}
