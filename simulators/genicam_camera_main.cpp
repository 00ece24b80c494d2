// springscan-genicam-camera: a simulated GenICam 3D line profiler on a loopback address
// (simulators/genicam_camera.hpp) scanning a CAD part as produced with a chosen springback.
//   springscan-genicam-camera --cad PART.step --springback 0.5,0.3,0.6,0.2 [--xml FILE]
//       [--address 127.0.0.1] [--spacing MM] [--noise MM] [--frame-period-us N]
//       [--vanish-after-lines N] [--return-after-s S] [--lose-every-nth-frame N] [--seed N]
// Prints "READY width=W lines=L x0_mm=X y0_mm=Y dy_mm=D" when it serves, then runs until
// SIGTERM or SIGINT.
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>

#include "simulators/genicam_camera.hpp"

namespace {

using namespace springscan;

int usage(const std::string& message) {
  std::fprintf(stderr,
               "springscan-genicam-camera: %s\nusage: springscan-genicam-camera --cad FILE "
               "--springback A,B,... [--xml FILE] [--address IP] [--spacing MM] [--noise MM] "
               "[--frame-period-us N] [--vanish-after-lines N] [--return-after-s S] "
               "[--lose-every-nth-frame N] [--seed N]\n",
               message.c_str());
  return 2;
}

bool number(const char* text, double& out) {
  char* end = nullptr;
  out = std::strtod(text, &end);
  return end != text && *end == '\0';
}

}  // namespace

int main(int argc, char** argv) {
  simulators::GenicamCameraSettings camera;
  parts::LaserScanSettings scan;
  scan.line_spacing_mm = 1.0;
  scan.noise_sigma_mm = 0.02;
  std::string cad;
  std::vector<double> springback;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) return usage(arg + ": needs a value");
    const char* value = argv[++i];
    double v = 0.0;
    if (arg == "--cad") {
      cad = value;
    } else if (arg == "--xml") {
      camera.genicam_xml = value;
    } else if (arg == "--address") {
      camera.interface_address = value;
    } else if (arg == "--springback") {
      std::stringstream list(value);
      std::string item;
      while (std::getline(list, item, ',')) {
        if (!number(item.c_str(), v)) return usage("--springback " + std::string(value));
        springback.push_back(v);
      }
    } else if (!number(value, v)) {
      return usage(arg + " " + value + ": not a number");
    } else if (arg == "--spacing" && v > 0.0) {
      scan.line_spacing_mm = v;
    } else if (arg == "--noise" && v >= 0.0) {
      scan.noise_sigma_mm = v;
    } else if (arg == "--frame-period-us" && v >= 100.0) {
      camera.frame_period_us = static_cast<int>(v);
    } else if (arg == "--vanish-after-lines") {
      camera.vanish_after_lines = static_cast<std::int64_t>(v);
    } else if (arg == "--return-after-s") {
      camera.return_after_s = v;
    } else if (arg == "--lose-every-nth-frame" && v >= 0.0) {
      camera.lose_every_nth_frame = static_cast<int>(v);
    } else if (arg == "--seed" && v >= 0.0) {
      scan.seed = static_cast<std::uint64_t>(v);
    } else {
      return usage("unknown option or bad value: " + arg + " " + value);
    }
  }
  if (cad.empty() || springback.empty()) return usage("--cad and --springback are required");
  // Block the stop signals before any thread starts, so that only sigwait below takes them.
  sigset_t stop;
  sigemptyset(&stop);
  sigaddset(&stop, SIGTERM);
  sigaddset(&stop, SIGINT);
  pthread_sigmask(SIG_BLOCK, &stop, nullptr);
  constexpr double kHeadZ = 200.0;  // the default laser head (drivers/conversion.hpp)
  auto image = simulators::part_range_image(cad, springback, scan, kHeadZ);
  if (!image) return usage(image.message());
  auto running = simulators::GenicamCamera::start(camera, std::move(*image));
  if (!running) return usage(running.message());
  const auto& im = (*running)->image();
  std::printf("READY width=%d lines=%d x0_mm=%.6f y0_mm=%.6f dy_mm=%.6f\n", im.width, im.lines,
              im.x0_mm, im.y0_mm, im.dy_mm);
  std::fflush(stdout);
  int signal = 0;
  sigwait(&stop, &signal);
  return 0;
}
