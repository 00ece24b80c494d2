#pragma once
// A simulated GenICam 3D line profiler: Aravis's fake GigE Vision camera on a loopback address,
// described by simulators/genicam_camera.xml (the SFNC Scan3d features), its frames filled with
// range lines of a simulated laser scan (simulators/parts/laser_scan.hpp) as the part passes
// under it. The driver talks to it over real GVCP/GVSP (UDP), as to a profiler on the plant
// network. Faults: the camera vanishes after a number of lines (and may come back), and frames
// are lost on the way (as a congested switch or a full socket buffer drops them).
//
// One camera per address: GigE Vision's control port (3956) is fixed, so tests that start one
// on 127.0.0.1 take the CTest resource lock "genicam_gvcp".

#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "analysis/core/expected.hpp"
#include "simulators/parts/laser_scan.hpp"

namespace springscan::simulators {

/// A scan as range lines: line k (along the motion) at y0_mm + k * dy_mm, column i (along the
/// laser line) at x0_mm + i * dx_mm; range is measured down from the head (head z - point z).
struct RangeImage {
  int width = 0;  ///< columns
  int lines = 0;  ///< rows
  double x0_mm = 0.0;
  double dx_mm = 1.0;
  double y0_mm = 0.0;
  double dy_mm = 1.0;
  std::vector<float> range_mm;  ///< lines * width; NaN: no return there
};

/// The scan of `scan` (view -z, lines along x, T_scan_part as scanned) seen by a head at height
/// `head_z_mm`. Errors: an empty scan, spacings of zero.
analysis::Expected<RangeImage> range_image(const parts::LaserScan& scan, double head_z_mm);

/// The CAD part `cad_file` produced with `springback_deg` per bend (Bend::id), scanned with
/// `scan` and seen from `head_z_mm`: what the simulated profiler sends.
analysis::Expected<RangeImage> part_range_image(const std::string& cad_file,
                                                const std::vector<double>& springback_deg,
                                                const parts::LaserScanSettings& scan,
                                                double head_z_mm);

/// simulators/genicam_camera.xml in the checkout this was built from.
std::string default_genicam_xml();

struct GenicamCameraSettings {
  std::string interface_address = "127.0.0.1";      ///< where the camera listens (GVCP port 3956)
  std::string genicam_xml = default_genicam_xml();  ///< the description
  std::string serial = "SIM-GENICAM-1";
  int frame_period_us = 2000;  ///< time between frames
  int lines_per_frame = 16;    ///< Height at start (the driver sets its own)
  double scale_c_mm = 0.004;   ///< Scan3dCoordinateScale of C (range): 16 bits cover 262 mm
  double offset_c_mm = 60.0;   ///< Scan3dCoordinateOffset of C
  /// >= 0: the camera vanishes (stops answering, as on a power loss) once this many lines of a
  /// scan were sent.
  std::int64_t vanish_after_lines = -1;
  double return_after_s = -1.0;  ///< >= 0: a vanished camera is back after this long (healthy)
  /// > 0: every this many frames of a pass, one is lost (of the frames that hold the part's
  /// lines): its lines are skipped and its block id never reaches the wire, so the receiver
  /// sees the gap in the ids a lost frame leaves.
  int lose_every_nth_frame = 0;
};

/// The running camera. Thread safety: all members may be called from any thread.
class GenicamCamera {
 public:
  static analysis::Expected<std::unique_ptr<GenicamCamera>> start(GenicamCameraSettings settings,
                                                                  RangeImage image);
  ~GenicamCamera();
  GenicamCamera(const GenicamCamera&) = delete;
  GenicamCamera& operator=(const GenicamCamera&) = delete;

  bool present() const { return present_.load(); }
  /// A vanished camera is back (healthy) at once, as when its power returns.
  void bring_back() { bring_back_ = true; }
  std::int64_t scans_started() const { return scans_.load(); }
  /// Frames lost so far (lose_every_nth_frame), over every pass.
  std::int64_t frames_lost() const { return lost_.load(); }
  /// Changes lose_every_nth_frame from the next frame on (0: no more loss).
  void set_frame_loss(int every_nth_frame) { lose_every_.store(every_nth_frame); }
  const RangeImage& image() const { return image_; }
  const GenicamCameraSettings& settings() const { return settings_; }

  /// The fill of one frame (called by Aravis's camera thread); public for the C callback.
  /// Returns the frames lost before it, over the camera's life: the offset its block id takes.
  std::int64_t fill(std::uint8_t* data, std::uint32_t width, std::uint32_t height,
                    std::uint32_t format);

 private:
  GenicamCamera(GenicamCameraSettings settings, RangeImage image);
  analysis::Expected<bool> open_camera();
  void watch();

  GenicamCameraSettings settings_;
  RangeImage image_;
  std::mutex mutex_;        // the Aravis camera object, opened and closed by watch()
  void* camera_ = nullptr;  // ArvGvFakeCamera (GObject, kept out of this header)
  std::atomic<bool> present_{false};
  std::atomic<bool> vanish_{false};
  std::atomic<bool> restart_{true};  // the next frame starts a new pass of the part
  std::atomic<bool> stop_{false};
  std::atomic<bool> bring_back_{false};
  std::atomic<bool> closing_{false};  // watch() is tearing the vanished camera down
  std::atomic<std::int64_t> scans_{0};
  std::atomic<int> lose_every_{0};
  std::atomic<std::int64_t> lost_{0};
  std::int64_t cursor_ = 0;         // the next line of the image (camera thread only)
  std::int64_t frame_in_pass_ = 0;  // frames of this pass so far, lost ones included (ditto)
  void* fake_ = nullptr;            // ArvFakeCamera of camera_
  int stream_port_ = -1;            // where the frames went last (camera thread only)
  bool vanished_once_ = false;
  std::thread watcher_;
};

}  // namespace springscan::simulators
