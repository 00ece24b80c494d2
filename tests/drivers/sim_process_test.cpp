// Cross-process emulation: springscan-scanner-sim owns the umockdev testbed and runs
// `springscan scan` under the preload, so the CLI's production libusb driver talks to the
// simulated device. The way the daemon's hardware-in-the-loop tests run.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "analysis/io/point_io.hpp"
#include "simulators/parts/sheet_part.hpp"
#include "tests/support/test_paths.hpp"

namespace springscan {
namespace {

int run(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string sim_and_scan(const std::string& sim_flags, const std::string& scan_flags,
                         const std::string& out) {
  return std::string(springscan::test_paths::kScannerSim) + " --serial SN-HIL " + sim_flags +
         " -- " + springscan::test_paths::kSpringscan + " scan --quiet --serial SN-HIL --out " +
         out + " " + scan_flags;
}

TEST(ScannerSimProcess, CliLaserScanThroughTheEmulatedDeviceMatchesThePart) {
  const std::string out = ::testing::TempDir() + "sim_process_laser.ply";
  ASSERT_EQ(run(sim_and_scan("--kind laser --profile hat --springback 2 --step 3 --noise 0.02",
                             "--kind laser", out)),
            0);
  const auto cloud = analysis::read_point_cloud(out);
  ASSERT_TRUE(cloud.ok()) << cloud.message();
  EXPECT_GT(cloud->size(), 3000u);
  // The simulator's part: the hat profile with 2 degrees of springback at every bend.
  const auto produced =
      parts::produced_profile(parts::hat_profile(15, 20, 30, 45, 3), {2, 2, 2, 2});
  ASSERT_TRUE(produced.ok());
  const auto distance = parts::profile_surface_distance(*produced);
  double sum = 0.0;
  for (const auto& q : cloud->points) sum += std::pow(distance->closest(q).signed_distance_mm, 2);
  EXPECT_LT(std::sqrt(sum / double(cloud->size())), 0.03);
}

TEST(ScannerSimProcess, UnplugReachesTheCliAsAFailureAndTheDeviceComesBack) {
  const std::string out = ::testing::TempDir() + "sim_process_tactile.ply";
  const std::string cli = std::string(springscan::test_paths::kSpringscan) +
                          " scan --quiet --kind tactile --serial SN-HIL --out " + out;
  // First scan: unplugged half way (exit 1); the simulator plugs the device back 0.5 s later,
  // once the first process has surely ended (a process that closes its udev monitor while a
  // uevent is in flight makes Debian 12's umockdev abort the simulator: usb_emulator_internal.hpp);
  // the second scan, a new process, finds it again.
  const std::string script = "sh -c '" + cli + "; test $? -eq 1 || exit 9; sleep 1; " + cli + "'";
  EXPECT_EQ(run(std::string(springscan::test_paths::kScannerSim) +
                " --serial SN-HIL --kind tactile --duration 0.4 --unplug-at 0.5 "
                "--replug-after 0.5 -- " +
                script),
            0);
  EXPECT_TRUE(analysis::read_point_cloud(out).ok());
}

TEST(ScannerSimProcess, BadOptionsAreRefusedWithAReason) {
  EXPECT_EQ(run(std::string(springscan::test_paths::kScannerSim) + " --kind sonar 2>/dev/null"), 2);
  EXPECT_EQ(run(std::string(springscan::test_paths::kScannerSim) + " --noise abc 2>/dev/null"), 2);
}

}  // namespace
}  // namespace springscan
