#pragma once
// Test pieces injected into the job runner and the station: a scanner that "scans" a flat
// sheet lifted by a known offset (or fails as told), and an analysis that measures that offset
// against the plane z = 0. The tests know the ground truth (the offset) and check the numbers
// that come out of the registers and the reports.

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <optional>
#include <random>
#include <string>

#include "analysis/inspection/pipeline.hpp"
#include "drivers/scanner.hpp"

namespace springscan::daemon::testing {

class PlaneScanner : public drivers::Scanner {
 public:
  analysis::Expected<drivers::DeviceInfo> identify() override {
    if (!present) return analysis::fail(analysis::ErrorCode::kNotFound, "device not found");
    return drivers::DeviceInfo{"test plane", "SN-1", "1.0", "laser_line"};
  }
  analysis::Expected<analysis::PointCloud> scan(const drivers::ScanProgress& progress) override {
    ++scans;
    {
      // A gate the test can close to keep the scan "running" (busy tests).
      std::unique_lock lock(mutex_);
      gate_.wait(lock, [this] { return open_; });
    }
    if (unplug_next_scan.exchange(false)) {
      present = false;
      return analysis::fail(analysis::ErrorCode::kDeviceGone,
                            "scanner unplugged during the scan (LIBUSB_ERROR_NO_DEVICE)");
    }
    if (fail_next_scan) {
      const analysis::Error error = *fail_next_scan;
      fail_next_scan.reset();
      return error;
    }
    analysis::PointCloud cloud;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> xy(-50.0, 50.0);
    for (int i = 0; i < points; ++i) {
      cloud.points.emplace_back(xy(rng), xy(rng), offset_mm.load());
      if (i % 100 == 0 && progress && !progress(double(i) / points)) {
        return analysis::fail(analysis::ErrorCode::kCancelled, "scan cancelled");
      }
    }
    return cloud;
  }
  bool online() const override { return present.load(); }

  void close_gate() {
    std::lock_guard lock(mutex_);
    open_ = false;
  }
  void open_gate() {
    {
      std::lock_guard lock(mutex_);
      open_ = true;
    }
    gate_.notify_all();
  }

  std::atomic<bool> present{true};
  std::atomic<bool> unplug_next_scan{false};
  /// The next scan fails with this error (set before the job starts; the runner's start()
  /// orders the write before the scan).
  std::optional<analysis::Error> fail_next_scan;
  std::atomic<double> offset_mm{0.05};
  std::atomic<int> scans{0};
  int points = 2000;

 private:
  std::mutex mutex_;
  std::condition_variable gate_;
  bool open_ = true;
};

/// Deviation of every point from the plane z = 0; pass when max |z| <= tolerance_mm. One
/// "bend" whose springback is the tilt-free offset in degrees, for the bend table; one
/// compensation vector per 100 points, opposite to the deviation.
inline analysis::Expected<analysis::InspectionOutcome> plane_analysis(
    const analysis::PointCloud& scan, double tolerance_mm, double uncertainty_mm = 0.0) {
  if (scan.empty()) return analysis::fail("empty scan");
  analysis::InspectionOutcome outcome;
  v1::InspectionReport& r = outcome.report;
  double max_abs = 0.0, sum_sq = 0.0, lo = 1e300, hi = -1e300;
  for (const auto& p : scan.points) {
    max_abs = std::max(max_abs, std::abs(p.z()));
    sum_sq += p.z() * p.z();
    lo = std::min(lo, p.z());
    hi = std::max(hi, p.z());
  }
  r.mutable_deviation()->set_min(lo);
  r.mutable_deviation()->set_max(hi);
  r.mutable_deviation()->set_rms(std::sqrt(sum_sq / double(scan.size())));
  r.mutable_deviation()->set_p95(max_abs);
  r.mutable_deviation()->set_color_scale_mm(tolerance_mm);
  r.mutable_input()->set_scan_points(static_cast<std::int64_t>(scan.size()));
  auto* bend = r.add_bends();
  bend->set_id(1);
  bend->set_measured(true);
  bend->set_springback_deg(hi * 10.0);
  bend->set_pass(std::abs(hi * 10.0) <= 1.0);
  for (std::size_t i = 0; i < scan.size(); i += 100) {
    auto* c = r.add_compensation();
    c->mutable_point()->set_x(scan.points[i].x());
    c->mutable_vector()->set_z(-scan.points[i].z());
  }
  // The guard band (analysis/inspection/conformity.hpp) on max |d| with U = uncertainty_mm.
  const bool pass = max_abs <= tolerance_mm - uncertainty_mm;
  const bool fail = max_abs > tolerance_mm + uncertainty_mm;
  r.mutable_verdict()->set_pass(pass);
  r.mutable_verdict()->set_decision(pass   ? v1::Verdict::PASS
                                    : fail ? v1::Verdict::FAIL
                                           : v1::Verdict::UNDECIDED);
  r.mutable_deviation()->set_uncertainty_mm(uncertainty_mm);
  if (!pass) {
    r.mutable_verdict()->add_reasons("max deviation " + std::to_string(max_abs) + " mm " +
                                     (fail ? "exceeds" : "undecided, within U of") + " tolerance " +
                                     std::to_string(tolerance_mm));
  }
  outcome.deviation_cloud = scan;
  outcome.deviation_cloud.scalars.assign(scan.size(), hi);
  return outcome;
}

/// A fresh empty directory under the system temp dir, removed by the destructor.
class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(std::filesystem::temp_directory_path() / (name + "-" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string str() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

}  // namespace springscan::daemon::testing
