#include "simulators/sim_options.hpp"

#include <cstdlib>
#include <map>
#include <sstream>

#include "analysis/io/point_io.hpp"
#include "simulators/parts/sheet_part.hpp"

namespace springscan::simulators {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

using analysis::fail;
namespace p = drivers::protocol;

bool to_number(const std::string& text, double& out) {
  char* end = nullptr;
  out = std::strtod(text.c_str(), &end);
  return !text.empty() && *end == '\0';
}

analysis::Expected<std::vector<double>> number_list(const std::string& name,
                                                    const std::string& text) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    double v = 0.0;
    if (!to_number(item, v)) return fail("--" + name + " " + text + ": not a number list");
    values.push_back(v);
  }
  return values;
}

// Every option that takes a number, and where it goes.
std::map<std::string, double*> number_options(SimOptions& o) {
  auto& d = o.device;
  return {{"noise", &d.noise.sigma_mm},
          {"outliers", &d.noise.outlier_fraction},
          {"missing", &d.noise.missing_fraction},
          {"duration", &d.scan_duration_s},
          {"step", &d.laser.step_mm},
          {"head-tilt", &d.laser.head_tilt_deg},
          {"grid", &d.probe.grid_step_mm},
          {"unplug-at", &d.faults.unplug_at_fraction},
          {"stall-at", &d.faults.stall_at_fraction},
          {"halt-at", &d.faults.halt_at_fraction},
          {"corrupt-at", &d.faults.corrupt_crc_at_fraction},
          {"wrong-seq-at", &d.faults.wrong_sequence_at_fraction},
          {"skip-frame-at", &d.faults.skip_frame_at_fraction},
          {"replug-after", &o.replug_after_s},
          {"replace-mm", &d.replace_mm},
          {"replace-deg", &d.replace_deg}};
}

}  // namespace

std::string sim_usage() {
  return "usage: springscan-scanner-sim [options] [-- COMMAND [ARGS...]]\n"
         "Presents a simulated scanner as a USB device (umockdev) to COMMAND, which runs with\n"
         "LD_PRELOAD and UMOCKDEV_DIR set; exits with COMMAND's status. Without COMMAND it\n"
         "prints the environment for another process and serves until interrupted.\n\n"
         "  --kind laser|tactile    scanner kind (default laser)\n"
         "  --serial TEXT           USB serial number (default SIM0001)\n"
         "  --part FILE             part surface as a dense point file (PLY, XYZ, STL), mm\n"
         "  --profile hat|l|u|z     analytic sheet part when no --part (default hat)\n"
         "  --springback D[,D...]   springback per bend of the analytic part, degrees\n"
         "  --noise MM              Gaussian noise sigma (default 0.02)\n"
         "  --outliers F, --missing F   shares of outliers and missing points\n"
         "  --duration S            scan duration (default 0: as fast as read)\n"
         "  --step MM, --points N   laser: profile spacing, points per profile\n"
         "  --head-tilt DEG         laser: two heads tilted by +-DEG about the motion axis\n"
         "                          (default 0: one head looking straight down)\n"
         "  --grid MM, --stylus MM  tactile: grid spacing, stylus radius\n"
         "  --unplug-at F, --stall-at F, --halt-at F, --corrupt-at F, --wrong-seq-at F,\n"
         "  --skip-frame-at F\n"
         "                          faults at a share of the scan's data frames\n"
         "  --replug-after S        plug back S seconds after an unplug (default 1, <0 never)\n"
         "  --replace-mm MM, --replace-deg DEG\n"
         "                          each scan finds the part placed anew: moved by up to MM\n"
         "                          and turned by up to DEG (gauge studies; default 0)\n"
         "  --seed N                noise seed (default 1)\n";
}

analysis::Expected<SimOptions> parse_sim_options(int argc, char** argv) {
  SimOptions o;
  auto numbers = number_options(o);
  std::string kind = "laser";
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--") {
      for (int k = i + 1; k < argc; ++k) o.command.emplace_back(argv[k]);
      break;
    }
    if (arg == "--help" || arg == "-h") {
      o.help = true;
      return o;
    }
    if (arg.rfind("--", 0) != 0 || i + 1 >= argc) return fail("unexpected argument " + arg);
    const std::string name = arg.substr(2), value = argv[++i];
    double v = 0.0;
    if (auto it = numbers.find(name); it != numbers.end()) {
      if (!to_number(value, *it->second)) return fail("--" + name + " " + value + ": not a number");
    } else if (name == "kind") {
      kind = value;
    } else if (name == "serial") {
      o.device.identity.serial = value;
    } else if (name == "part") {
      o.part_path = value;
    } else if (name == "profile") {
      o.profile = value;
    } else if (name == "springback") {
      auto list = number_list(name, value);
      if (!list) return list.error();
      o.springback_deg = *list;
    } else if (name == "points" || name == "seed" || name == "stylus") {
      if (!to_number(value, v) || v < 0)
        return fail("--" + name + " " + value + ": not a number >= 0");
      if (name == "points") o.device.laser.points_per_profile = static_cast<int>(v);
      if (name == "seed") o.device.seed = static_cast<std::uint32_t>(v);
      if (name == "stylus") o.device.probe.stylus_radius_mm = static_cast<float>(v);
    } else {
      return fail("unknown option " + arg + " (--help lists them)");
    }
  }
  if (kind != "laser" && kind != "tactile") return fail("--kind " + kind + ": laser or tactile");
  auto& id = o.device.identity;
  id.kind = kind == "laser" ? p::ScannerKind::kLaserLine : p::ScannerKind::kTactileProbe;
  id.model = kind == "laser" ? "SL-200 simulated" : "TP-20 simulated";
  if (o.device.laser.points_per_profile < 1 || o.device.laser.points_per_profile > 4096)
    return fail("--points " + std::to_string(o.device.laser.points_per_profile) + ": 1..4096");
  o.device.config.points_per_profile =
      static_cast<std::uint16_t>(o.device.laser.points_per_profile);
  if (!(o.device.laser.step_mm > 0.0) || !(o.device.probe.grid_step_mm > 0.0))
    return fail("--step and --grid must be positive");
  if (!(o.device.laser.head_tilt_deg >= 0.0 && o.device.laser.head_tilt_deg <= 60.0))
    return fail("--head-tilt " + std::to_string(o.device.laser.head_tilt_deg) + ": 0 to 60");
  return o;
}

analysis::Expected<analysis::PointCloud> load_part_surface(const SimOptions& o) {
  if (!o.part_path.empty()) return analysis::read_point_cloud(o.part_path);
  parts::ProfileSpec nominal;
  if (o.profile == "hat") {
    nominal = parts::hat_profile(15, 20, 30, 45, 3);
  } else if (o.profile == "l") {
    nominal = parts::l_profile(40, 30, 90, 3);
  } else if (o.profile == "u") {
    nominal = parts::u_profile(20, 40, 90, 3);
  } else if (o.profile == "z") {
    nominal = parts::z_profile(25, 30, 90, 3);
  } else {
    return fail("--profile " + o.profile + ": hat, l, u or z");
  }
  std::vector<double> springback = o.springback_deg;
  if (springback.empty()) springback.assign(nominal.bend_angles_deg.size(), 0.0);
  if (springback.size() == 1) springback.assign(nominal.bend_angles_deg.size(), springback[0]);
  parts::ScanSimulationSettings dense;
  dense.point_count = o.surface_points;
  dense.noise_sigma_mm = 0.0;  // the device adds its own noise along its measuring direction
  return parts::simulate_scan(nominal, springback, dense);
}

}  // namespace springscan::simulators
