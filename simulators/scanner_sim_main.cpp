// springscan-scanner-sim: the scanner simulator as a USB device for another process.
//
//   springscan-scanner-sim [options] -- COMMAND [ARGS...]
//
// builds the umockdev testbed with the emulated scanner, runs COMMAND with
// LD_PRELOAD=libumockdev-preload.so.0 and UMOCKDEV_DIR set (so its libusb sees the device),
// serves the device until COMMAND exits, and exits with COMMAND's status. Without COMMAND it
// prints the two environment variables and serves until SIGINT or SIGTERM.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "simulators/sim_options.hpp"
#include "simulators/usb_emulator.hpp"

namespace {

std::atomic<int> g_signal{0};

void on_signal(int signal_number) { g_signal = signal_number; }

pid_t start_child(const std::vector<std::string>& command, const std::string& root) {
  const pid_t pid = fork();
  if (pid != 0) return pid;
  std::string preload = springscan::simulators::umockdev_preload_library();
  if (const char* old = std::getenv("LD_PRELOAD"); old != nullptr && *old != '\0')
    preload += std::string(":") + old;
  setenv("LD_PRELOAD", preload.c_str(), 1);
  setenv("UMOCKDEV_DIR", root.c_str(), 1);
  // A sanitizer-built child would refuse a preload ahead of its ASan runtime; the preload only
  // wraps libc calls, so the order check is safely off (harmless for normal builds).
  std::string asan = "verify_asan_link_order=0";
  if (const char* old = std::getenv("ASAN_OPTIONS"); old != nullptr && *old != '\0')
    asan = std::string(old) + ":" + asan;
  setenv("ASAN_OPTIONS", asan.c_str(), 1);
  std::vector<char*> argv;
  for (const auto& a : command) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  execvp(argv[0], argv.data());
  std::fprintf(stderr, "springscan-scanner-sim: cannot run %s\n", argv[0]);
  _exit(127);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace springscan::simulators;
  auto options = parse_sim_options(argc, argv);
  if (!options) {
    std::fprintf(stderr, "springscan-scanner-sim: %s\n", options.message().c_str());
    return 2;
  }
  if (options->help) {
    std::fputs(sim_usage().c_str(), stdout);
    return 0;
  }
  auto surface = load_part_surface(*options);
  if (!surface) {
    std::fprintf(stderr, "springscan-scanner-sim: %s\n", surface.message().c_str());
    return 2;
  }
  auto emulator = EmulatedUsbScanner::create(options->device, std::move(*surface));
  if (!emulator) {
    std::fprintf(stderr, "springscan-scanner-sim: %s\n", emulator.message().c_str());
    return 1;
  }
  auto& device = **emulator;
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  pid_t child = -1;
  if (options->command.empty()) {
    std::printf("UMOCKDEV_DIR=%s\nLD_PRELOAD=%s\n", device.root_dir().c_str(),
                umockdev_preload_library().c_str());
    std::fflush(stdout);
  } else {
    child = start_child(options->command, device.root_dir());
  }
  // Serve until the child ends (or a signal), plugging the device back after an unplug fault.
  using Clock = std::chrono::steady_clock;
  Clock::time_point unplugged_since{};
  int status = 0;
  for (;;) {
    if (child > 0 && waitpid(child, &status, WNOHANG) == child) break;
    if (g_signal != 0) {
      if (child <= 0) break;
      kill(child, g_signal);
      g_signal = 0;
    }
    if (!device.plugged() && options->replug_after_s >= 0.0) {
      if (unplugged_since == Clock::time_point{}) unplugged_since = Clock::now();
      if (Clock::now() - unplugged_since >=
          std::chrono::duration<double>(options->replug_after_s)) {
        device.set_faults({});  // the fault happened; the device comes back healthy
        device.plug();
        unplugged_since = {};
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (child <= 0) return 0;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}
