#pragma once
// The hardware-in-the-loop rig: springscand as a real child process (daemon_process.hpp) under
// the scanner simulator presented as a USB device by umockdev in this test process, with the
// bundled demo hat (demo/README.md): the nominal CAD is demo/hat-profile.step, the simulated
// scanner measures the same hat profile as produced with a springback per bend that each test
// chooses (the ground truth), over its whole surface.
//
// This test executable links libumockdev-preload (like the driver tests), so the emulator's
// uevents (unplug, replug) resolve their /sys paths and reach the daemon's libusb hotplug.

#include <gtest/gtest.h>
#if defined(SPRINGSCAN_TSAN)
#include <dlfcn.h>
#include <sanitizer/tsan_interface.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "daemon/register_map.hpp"
#include "daemon_process.hpp"
#include "proto/springscan.pb.h"
#include "simulators/parts/demo_hat.hpp"
#include "simulators/parts/sheet_part.hpp"
#include "simulators/plc_client.hpp"
#include "simulators/usb_emulator.hpp"
#include "test_rig.hpp"
#include "tests/support/test_paths.hpp"

namespace springscan::daemon::testing {
using namespace springscan::parts;  // test and demo parts (simulators/parts)

/// Within the demo's angle tolerance of 1 degree at every bend.
inline const std::vector<double> kGoodSpringback{0.5, 0.3, 0.6, 0.2};

/// What a test changes in the daemon's config.
struct HilConfig {
  double scan_timeout_s = 10.0;  ///< scanner.timeout_s: silence before a scan fails
  std::string allowed_client = "127.0.0.1";
  double angle_tolerance_deg = 1.0;
};

/// The emulated scanner: a paced scan (so that there is a "mid-scan"), modest point counts.
struct HilDevice {
  double scan_duration_s = 0.4;
  simulators::DeviceFaults faults;
  double step_mm = 1.0;          ///< between laser profiles along the 80 mm width
  int points_per_profile = 200;  ///< across the ~120 mm line
};

class HilTest : public ::testing::Test {
 protected:
  HilTest() : dir_("springscan-hil") { write_config({}); }

  void write_config(const HilConfig& c) const {
    std::ofstream(config_path())
        << "modbus { bind_address: \"127.0.0.1\" port: 0 allowed_clients: \"" << c.allowed_client
        << "\" }\nscanner { kind: LASER_LINE timeout_s: " << c.scan_timeout_s << " }\n"
        << "parts { part_id: 1 name: \"demo hat profile\" cad_file: \""
        << springscan::test_paths::source("demo/hat-profile.step")
        << "\"\n  settings { verdict { tolerance_mm: 0.5 "
           "angle_tolerance_deg: "
        << c.angle_tolerance_deg << " } } }\n"
        << "report_dir: \"" << reports() << "\"\nmodel_cache_dir: \"" << dir_.str()
        << "/model-cache\"\nlog_level: \"warning\"\n";
  }
  std::string config_path() const { return dir_.str() + "/station.textproto"; }
  std::string reports() const { return dir_.str() + "/reports"; }

  /// Plugs in the emulated scanner measuring the hat as produced with `springback_deg`.
  void emulate(const std::vector<double>& springback_deg, const HilDevice& d = {}) {
    simulators::ScannerDeviceSettings s;
    s.noise.sigma_mm = 0.02;
    s.laser.step_mm = d.step_mm;                        // default: 81 profiles over the 80 mm width
    s.laser.points_per_profile = d.points_per_profile;  // default: 0.6 mm bins across the line
    s.config.points_per_profile = d.points_per_profile;
    s.scan_duration_s = d.scan_duration_s;
    s.faults = d.faults;
    parts::ScanSimulationSettings dense;  // the part's surface, densely and noise-free
    dense.point_count = 150000;
    dense.noise_sigma_mm = 0.0;
    auto surface = parts::simulate_scan(demo_hat_profile(), springback_deg, dense);
    ASSERT_TRUE(surface.ok()) << surface.message();
    auto emulator = simulators::EmulatedUsbScanner::create(s, std::move(*surface));
    ASSERT_TRUE(emulator.ok()) << emulator.message();
    emulator_ = std::move(*emulator);
  }

  std::unique_ptr<DaemonProcess> start_daemon() const {
    // A sanitizer-built daemon refuses a preload ahead of its runtime; the preload only wraps
    // libc, so the order check is safely off (as in springscan-scanner-sim).
    std::string asan = "verify_asan_link_order=0";
    if (const char* old = std::getenv("ASAN_OPTIONS"); old != nullptr && *old != '\0')
      asan = std::string(old) + ":" + asan;
    return std::make_unique<DaemonProcess>(
        springscan::test_paths::kSpringscand, config_path(), dir_.str(),
        std::vector<std::string>{"LD_PRELOAD=" + daemon_preload(),
                                 "UMOCKDEV_DIR=" + emulator_->root_dir(), "ASAN_OPTIONS=" + asan});
  }

  // The preload's wrappers (open, close, opendir, read, socket, ...) call libc directly, not
  // the next definition. Ahead of ThreadSanitizer's runtime they hide those calls from it: it
  // misses a descriptor being closed and reports the next file that reuses the number as a race
  // between threads (seen: the runner's closedir against the main thread's old sd_notify
  // socket). So under TSan its runtime comes first, as in this executable's own link order.
  static std::string daemon_preload() {
    std::string preload = simulators::umockdev_preload_library();
#if defined(SPRINGSCAN_TSAN)
    Dl_info runtime{};
    if (dladdr(reinterpret_cast<void*>(&__tsan_acquire), &runtime) != 0 &&
        runtime.dli_fname != nullptr)
      preload = std::string(runtime.dli_fname) + " " + preload;
#endif
    return preload;
  }

  static std::unique_ptr<simulators::PlcClient> plc(int port) {
    simulators::PlcClientSettings settings;
    settings.port = port;
    settings.step_timeout_s = 180.0;  // generous: a loaded 2-core machine, the sanitizer build
    auto client = simulators::PlcClient::connect(settings);
    if (!client) throw std::runtime_error(client.message());
    modbus_set_response_timeout((*client)->context(), 10, 0);  // not 2 s: a loaded machine
    return std::move(*client);
  }
  static void wait_online(simulators::PlcClient& plc, bool online = true) {
    ASSERT_TRUE(
        plc.wait_for([online](const auto& s) { return s.bit(regs::kDiScannerOnline) == online; },
                     online ? "SCANNER_ONLINE = 1" : "SCANNER_ONLINE = 0")
            .ok());
  }

  /// The stored report of record `record` (RESULT_SEQ == record here).
  v1::InspectionReport report(int record) const {
    char name[32];
    std::snprintf(name, sizeof name, "/r%012d/report.pb", record);
    std::ifstream in(reports() + name, std::ios::binary);
    v1::InspectionReport r;
    if (!in || !r.ParseFromIstream(&in)) ADD_FAILURE() << "cannot read record " << record;
    return r;
  }
  /// The names in the report directory (records, boot_id, leftovers).
  std::vector<std::string> report_dir_entries() const {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(reports()))
      names.push_back(e.path().filename().string());
    return names;
  }
  int record_count() const {
    int n = 0;
    for (const auto& name : report_dir_entries()) n += name.rfind("r0", 0) == 0 ? 1 : 0;
    return n;
  }

  /// The path-order index (0 = next to the first brim, as the ground truth is given) of a
  /// report's bend. The report numbers bends as the CAD segmentation found them, so the bend
  /// is matched by its axis to the nearest bend axis of the exact nominal model.
  static int path_index(const v1::Bend& bend) {
    static const auto nominal = parts::profile_part_model(demo_hat_profile(), {2000});
    if (!nominal.ok()) return -1;
    const analysis::Vec3 p(bend.axis_point().x(), bend.axis_point().y(), bend.axis_point().z());
    int best = -1;
    double best_distance = 5.0;  // mm: bends of the hat are 30 mm and more apart
    for (std::size_t i = 0; i < nominal->segmentation.bends.size(); ++i) {
      const auto& b = nominal->segmentation.bends[i];
      const analysis::Vec3 d = p - b.axis_point;
      const double distance = (d - d.dot(b.axis_direction) * b.axis_direction).norm();
      if (distance < best_distance) best = static_cast<int>(i), best_distance = distance;
    }
    return best;
  }
  /// Checks every bend of `r` against the ground truth and returns, per report bend, the index
  /// of the part's bend it was matched to. The hat is mirror-symmetric: turned end for end it
  /// fits its CAD model equally well, so a fit may put the scan's bend 0 on the model's bend 3.
  /// Both labelings are the same physical answer; the one closer to the truth is taken, and
  /// then every bend must be within `tolerance_deg`.
  static std::vector<int> expect_springback(const v1::InspectionReport& r,
                                            const std::vector<double>& truth,
                                            double tolerance_deg) {
    const int n = static_cast<int>(truth.size());
    std::vector<int> index;
    double error[2] = {0.0, 0.0};  // largest error: as labelled, mirrored
    for (const auto& bend : r.bends()) {
      const int i = path_index(bend);
      if (i < 0) {
        ADD_FAILURE() << "report bend " << bend.id() << " is at no bend of the part";
        return {};
      }
      index.push_back(i);
      error[0] = std::max(error[0], std::abs(bend.springback_deg() - truth[i]));
      error[1] = std::max(error[1], std::abs(bend.springback_deg() - truth[n - 1 - i]));
    }
    EXPECT_EQ(r.bends_size(), n);
    EXPECT_EQ(std::set<int>(index.begin(), index.end()).size(), index.size())
        << "two report bends on the same bend of the part";
    if (error[1] < error[0]) {
      for (int& i : index) i = n - 1 - i;
    }
    for (int k = 0; k < r.bends_size(); ++k) {
      const auto& bend = r.bends(k);
      EXPECT_TRUE(bend.measured()) << "bend " << index[k];
      EXPECT_NEAR(bend.springback_deg(), truth[index[k]], tolerance_deg)
          << "bend " << index[k] << " (report bend id " << bend.id() << ")";
    }
    return index;
  }
  /// The bend table in the registers says what the report says (millidegrees, rounded).
  static void expect_registers_match(const simulators::ResultRead& read,
                                     const v1::InspectionReport& r) {
    ASSERT_EQ(read.springback_mdeg.size(), static_cast<std::size_t>(r.bends_size()));
    for (int j = 0; j < r.bends_size(); ++j) {
      EXPECT_NEAR(read.springback_mdeg[static_cast<std::size_t>(j)],
                  r.bends(j).springback_deg() * 1000.0, 1.0)
          << "bend record " << j;
      EXPECT_EQ((read.bend_flags[static_cast<std::size_t>(j)] & regs::kBendPass) != 0,
                r.bends(j).pass())
          << "bend record " << j;
    }
  }

  TempDir dir_;
  std::unique_ptr<simulators::EmulatedUsbScanner> emulator_;
};

/// Runs `command`, returns its exit status and output (stdout and stderr).
inline std::pair<int, std::string> run_command(const std::string& command) {
  std::FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return {-1, "popen failed"};
  std::string output;
  char line[512];
  while (std::fgets(line, sizeof line, pipe) != nullptr) output += line;
  return {::pclose(pipe), output};
}

/// "[100]: \t0x0001" lines of mbpoll's output (-t N:hex) as address -> value.
inline std::map<int, unsigned> mbpoll_values(const std::string& output) {
  std::map<int, unsigned> values;
  std::size_t at = 0;
  while ((at = output.find('[', at)) != std::string::npos) {
    int address = 0;
    unsigned value = 0;
    if (std::sscanf(output.c_str() + at, "[%d]: %x", &address, &value) == 2)
      values[address] = value;
    ++at;
  }
  return values;
}

}  // namespace springscan::daemon::testing
