// The Aravis edge of the GenICam driver: the only file that sees Aravis or GLib.
#include "drivers/genicam/genicam_scanner.hpp"

#include <arv.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>

namespace springscan::drivers::genicam {
namespace {

using analysis::ErrorCode;
using analysis::fail;

// GLib reports failures through a GError the caller frees; this takes its message.
std::string take(GError*& error) {
  if (error == nullptr) return "unknown Aravis error";
  std::string message = error->message;
  g_clear_error(&error);
  return message;
}

struct ObjectUnref {
  void operator()(gpointer object) const { g_object_unref(object); }
};
using StreamPtr = std::unique_ptr<ArvStream, ObjectUnref>;

// Scan3dDistanceUnit entries (SFNC) in millimetres, or 0 for one we do not know.
double unit_mm(const std::string& unit) {
  if (unit == "Millimeter") return 1.0;
  if (unit == "Micrometer") return 1e-3;
  if (unit == "Meter") return 1e3;
  if (unit == "Inch") return 25.4;
  return 0.0;
}

}  // namespace

/// An open camera and the flag Aravis raises from its heartbeat thread when the control
/// connection is lost (GigE Vision "control-lost").
class GenicamScanner::Camera {
 public:
  static analysis::Expected<std::unique_ptr<Camera>> open(const std::string& id) {
    GError* error = nullptr;
    ArvCamera* camera = arv_camera_new(id.empty() ? nullptr : id.c_str(), &error);
    if (camera == nullptr)
      return fail(ErrorCode::kNotFound,
                  "genicam camera " + (id.empty() ? std::string("(first found)") : "'" + id + "'") +
                      ": not found (" + take(error) + ")");
    return std::unique_ptr<Camera>(new Camera(camera, id));
  }
  ~Camera() {
    if (handler_ != 0) g_signal_handler_disconnect(device_, handler_);
    g_object_unref(camera_);
  }
  Camera(const Camera&) = delete;
  Camera& operator=(const Camera&) = delete;

  ArvCamera* camera() const { return camera_; }
  ArvDevice* device() const { return device_; }
  bool lost() const { return lost_.load(); }
  std::string who() const { return "genicam camera " + name_; }

  bool has(const std::string& feature) const {
    GError* error = nullptr;
    const bool yes = arv_device_is_feature_available(device_, feature.c_str(), &error);
    g_clear_error(&error);
    return yes;
  }
  /// Any feature from its text form (enumeration entry, number, boolean, command "execute").
  analysis::Expected<bool> set(const std::string& feature, const std::string& value) {
    ArvGcNode* node = arv_device_get_feature(device_, feature.c_str());
    if (node == nullptr || !ARV_IS_GC_FEATURE_NODE(node))
      return fail(ErrorCode::kInvalidSettings, who() + ": has no feature " + feature);
    GError* error = nullptr;
    if (ARV_IS_GC_COMMAND(node)) {
      arv_gc_command_execute(ARV_GC_COMMAND(node), &error);
    } else {
      arv_gc_feature_node_set_value_from_string(ARV_GC_FEATURE_NODE(node), value.c_str(), &error);
    }
    if (error != nullptr)
      return fail(ErrorCode::kInvalidSettings,
                  who() + ": " + feature + " = '" + value + "' refused (" + take(error) + ")");
    return true;
  }
  analysis::Expected<double> get_float(const std::string& feature) {
    GError* error = nullptr;
    const double v = arv_device_get_float_feature_value(device_, feature.c_str(), &error);
    if (error != nullptr)
      return fail(ErrorCode::kProtocolError, who() + ": " + feature + ": " + take(error));
    return v;
  }
  analysis::Expected<std::string> get_string(const std::string& feature) {
    GError* error = nullptr;
    const char* v = arv_device_get_string_feature_value(device_, feature.c_str(), &error);
    if (error != nullptr)
      return fail(ErrorCode::kProtocolError, who() + ": " + feature + ": " + take(error));
    return std::string(v != nullptr ? v : "");
  }
  /// A register round trip: false when the camera no longer answers.
  bool responds() {
    if (lost()) return false;
    // Address 0 is a bootstrap register of both transports (GigE Vision's version, USB3
    // Vision's GenCP version); read raw, since Aravis may answer a feature from its cache.
    GError* error = nullptr;
    guint32 value = 0;
    arv_device_read_register(device_, 0x0, &value, &error);
    const bool ok = error == nullptr;
    g_clear_error(&error);
    return ok;
  }

 private:
  Camera(ArvCamera* camera, const std::string& id)
      : camera_(camera), device_(arv_camera_get_device(camera)), name_(id) {
    if (name_.empty()) {
      GError* error = nullptr;
      const char* device_id = arv_camera_get_device_id(camera_, &error);
      name_ = device_id != nullptr ? device_id : "(first found)";
      g_clear_error(&error);
    }
    handler_ = g_signal_connect(device_, "control-lost", G_CALLBACK(+[](ArvDevice*, gpointer flag) {
                                  static_cast<std::atomic<bool>*>(flag)->store(true);
                                }),
                                &lost_);
  }

  ArvCamera* camera_;
  ArvDevice* device_;  // owned by camera_
  std::string name_;
  std::atomic<bool> lost_{false};
  gulong handler_ = 0;
};

GenicamScanner::GenicamScanner(GenicamSettings settings) : settings_(std::move(settings)) {}
GenicamScanner::~GenicamScanner() = default;

std::string GenicamScanner::last_scan_note() const {
  const GenicamOutcome& o = outcome_;
  if (o.lost_frames == 0) return {};
  return std::to_string(o.lost_frames) + " of " + std::to_string(o.frames + o.lost_frames) +
         " frames lost on the network (their " + std::to_string(settings_.lines_per_frame) +
         " lines each have no points; max_lost_frames " +
         std::to_string(settings_.max_lost_frames) + "): check the profiler's link and switch";
}

bool GenicamScanner::online() const { return camera_ != nullptr && !camera_->lost(); }

analysis::Expected<DeviceInfo> GenicamScanner::identify() {
  if (camera_ && camera_->lost()) camera_.reset();  // gone while idle: open it afresh
  if (camera_) return info_;
  auto opened = Camera::open(settings_.camera_id);
  if (!opened) return opened.error();
  std::unique_ptr<Camera> camera = std::move(*opened);
  std::string missing;
  for (const std::string& feature : required_features(settings_)) {
    if (!camera->has(feature)) missing += (missing.empty() ? "" : ", ") + feature;
  }
  // Present but unusable stays open (online), as a USB head of the wrong kind does: a trigger
  // then fails with this reason instead of the station sitting offline.
  camera_ = std::move(camera);
  DeviceInfo info;
  info.kind = "laser_line";
  for (auto [field, feature] :
       {std::pair{&info.model, "DeviceModelName"}, std::pair{&info.serial, "DeviceSerialNumber"},
        std::pair{&info.firmware, "DeviceVersion"}}) {
    if (!camera_->has(feature)) continue;
    if (auto v = camera_->get_string(feature)) *field = *v;
  }
  if (info.serial.empty() && camera_->has("DeviceID")) {
    if (auto v = camera_->get_string("DeviceID")) info.serial = *v;
  }
  info_ = info;
  if (!missing.empty())
    return fail(ErrorCode::kInvalidSettings,
                camera_->who() + ": lacks the GenICam feature(s) " + missing +
                    " (docs/device-protocol.md, GenICam: features used)");
  return info_;
}

namespace {

// Puts a popped buffer back in the stream's queue when the loop is done with it.
struct QueuedBack {
  ArvStream* stream;
  ArvBuffer* buffer;
  ~QueuedBack() { arv_stream_push_buffer(stream, buffer); }
};

}  // namespace

analysis::Expected<analysis::PointCloud> GenicamScanner::scan(const ScanProgress& progress) {
  if (const std::string bad = validate(settings_); !bad.empty())
    return fail(ErrorCode::kInvalidSettings, bad);
  auto info = identify();
  if (!info) return info.error();
  Camera& cam = *camera_;
  const std::string who = cam.who();

  // The profile mode: format, frame size, output mode, the range component, then the
  // station's own features, in the config's order.
  std::vector<std::pair<std::string, std::string>> setup{
      {"PixelFormat", to_string(settings_.pixel_format)},
      {"Height", std::to_string(settings_.lines_per_frame)}};
  if (settings_.width > 0) setup.emplace_back("Width", std::to_string(settings_.width));
  if (!settings_.output_mode.empty()) setup.emplace_back("Scan3dOutputMode", settings_.output_mode);
  if (!settings_.component.empty() && cam.has("ComponentSelector")) {
    setup.emplace_back("ComponentSelector", settings_.component);
    if (cam.has("ComponentEnable")) setup.emplace_back("ComponentEnable", "true");
  }
  setup.insert(setup.end(), settings_.features.begin(), settings_.features.end());
  for (const auto& [feature, value] : setup) {
    if (auto set = cam.set(feature, value); !set) return set.error();
  }

  // The camera's scale and offset per coordinate, and its distance unit.
  RangeScaling scaling;
  const bool abc = settings_.pixel_format == RangeFormat::kCoord3dAbc32f;
  for (auto [coordinate, name] :
       {std::pair{&scaling.a, "CoordinateA"}, std::pair{&scaling.b, "CoordinateB"},
        std::pair{&scaling.c, "CoordinateC"}}) {
    if (coordinate == &scaling.b && !abc) continue;
    if (auto set = cam.set("Scan3dCoordinateSelector", name); !set) return set.error();
    auto scale = cam.get_float("Scan3dCoordinateScale");
    if (!scale) return scale.error();
    auto offset = cam.get_float("Scan3dCoordinateOffset");
    if (!offset) return offset.error();
    coordinate->scale = *scale;
    coordinate->offset = *offset;
    if (cam.has("Scan3dInvalidDataFlag") && cam.has("Scan3dInvalidDataValue")) {
      GError* error = nullptr;
      coordinate->invalid_flag =
          arv_device_get_boolean_feature_value(cam.device(), "Scan3dInvalidDataFlag", &error);
      g_clear_error(&error);
      if (auto v = cam.get_float("Scan3dInvalidDataValue")) coordinate->invalid_value = *v;
    }
  }
  if (cam.has("Scan3dDistanceUnit")) {
    auto unit = cam.get_string("Scan3dDistanceUnit");
    if (!unit) return unit.error();
    scaling.unit_mm = unit_mm(*unit);
    if (scaling.unit_mm == 0.0)
      return fail(ErrorCode::kInvalidSettings,
                  who + ": Scan3dDistanceUnit '" + *unit + "' is not a length unit we know");
  }
  double step_mm = settings_.line_step_mm;
  if (step_mm == 0.0) {
    double rate = settings_.line_rate_hz;
    if (rate == 0.0) {
      auto camera_rate = cam.get_float("AcquisitionLineRate");
      if (!camera_rate) return camera_rate.error();
      rate = *camera_rate;
    }
    if (!(rate > 0.0))
      return fail(ErrorCode::kInvalidSettings, who + ": line rate " + std::to_string(rate) + " Hz");
    step_mm = settings_.speed_mm_s / rate;
  }

  bool gone = false;
  auto cloud = acquire(scaling, step_mm, progress, gone);
  if (gone) camera_.reset();  // after the stream is freed: closed until identify() finds it
  return cloud;
}

analysis::Expected<analysis::PointCloud> GenicamScanner::acquire(const RangeScaling& scaling,
                                                                 double step_mm,
                                                                 const ScanProgress& progress,
                                                                 bool& gone) {
  Camera& cam = *camera_;
  const std::string who = cam.who();
  GError* error = nullptr;
  const guint payload = arv_camera_get_payload(cam.camera(), &error);
  if (error != nullptr)
    return fail(ErrorCode::kProtocolError, who + ": PayloadSize: " + take(error));
  StreamPtr stream(arv_camera_create_stream(cam.camera(), nullptr, nullptr, &error));
  if (!stream) return fail(ErrorCode::kOsError, who + ": no stream (" + take(error) + ")");
  for (int i = 0; i < settings_.buffers; ++i)
    arv_stream_push_buffer(stream.get(), arv_buffer_new(payload, nullptr));

  // A camera that stops answering is gone (closed, like an unplugged USB head); one that
  // answers but sends nothing timed out.
  const auto silent = [&](const std::string& what) -> analysis::Error {
    if (!cam.responds()) {
      gone = true;
      return fail(ErrorCode::kDeviceGone,
                  who + ": gone " + what + " (no answer on the control channel)");
    }
    arv_camera_stop_acquisition(cam.camera(), nullptr);
    return fail(
        ErrorCode::kTimeout,
        who + ": no frame for " + std::to_string(settings_.frame_timeout_ms) + " ms " + what);
  };
  arv_camera_start_acquisition(cam.camera(), &error);
  if (error != nullptr) {
    take(error);
    return silent("when starting the acquisition");
  }

  GenicamOutcome outcome;
  outcome.line_step_mm = step_mm;
  analysis::PointCloud cloud;
  // Frame k of the scan (k from the block ids, so that a lost or late frame leaves its lines
  // empty and the others in place) holds lines k * H .. k * H + H - 1.
  const std::int64_t lines = settings_.scan_lines;
  const std::int64_t per_frame = settings_.lines_per_frame;
  const std::int64_t frames_needed = (lines + per_frame - 1) / per_frame;
  std::optional<std::uint64_t> previous_id;
  std::int64_t index = 0, covered = 0;  // this frame's index; frames up to the newest one
  while (covered < frames_needed) {
    ArvBuffer* buffer = arv_stream_timeout_pop_buffer(
        stream.get(), static_cast<guint64>(settings_.frame_timeout_ms) * 1000u);
    if (buffer == nullptr)
      return silent("at line " + std::to_string(covered * per_frame) + " of " +
                    std::to_string(lines));
    QueuedBack back{stream.get(), buffer};
    // A buffer Aravis hands back unwritten (seen on loopback under load as the acquisition
    // starts, block ids 0, 1, ...) carries no frame: it neither counts nor moves the index.
    if (arv_buffer_get_status(buffer) == ARV_BUFFER_STATUS_CLEARED) continue;
    std::uint64_t id = arv_buffer_get_frame_id(buffer);
    // A GigE Vision frame so damaged that its block id is lost comes as id 0 (never valid):
    // it is the one after the previous.
    if (id == 0 && previous_id) id = *previous_id == 0xFFFF ? 1 : *previous_id + 1;
    index = previous_id ? index + block_id_step(*previous_id, id) : 0;
    previous_id = id;
    covered = std::max(covered, index + 1);
    const bool complete = arv_buffer_get_status(buffer) == ARV_BUFFER_STATUS_SUCCESS;
    if (complete && index >= 0 && index < frames_needed) {
      RangeFrameView frame;
      frame.format = static_cast<RangeFormat>(arv_buffer_get_image_pixel_format(buffer));
      frame.data = static_cast<const std::uint8_t*>(arv_buffer_get_data(buffer, &frame.size));
      frame.width = static_cast<std::uint32_t>(arv_buffer_get_image_width(buffer));
      frame.first_line = index * per_frame;
      frame.height = static_cast<std::uint32_t>(
          std::min(std::int64_t(arv_buffer_get_image_height(buffer)), lines - frame.first_line));
      if (const std::string bad = validate(frame); !bad.empty()) {
        arv_camera_stop_acquisition(cam.camera(), nullptr);
        return fail(ErrorCode::kProtocolError, who + ": frame " + std::to_string(id) + ": " + bad);
      }
      outcome.points +=
          append_range_lines(frame, scaling, settings_.calibration, step_mm, cloud.points);
      ++outcome.frames;
    }
    // Frames still missing; a late one may still come, so the limit is final at the end. Far
    // more missing than the stream has buffers cannot all be late.
    outcome.lost_frames = std::min(covered, frames_needed) - outcome.frames;
    if (outcome.lost_frames > settings_.max_lost_frames + settings_.buffers ||
        (covered >= frames_needed && outcome.lost_frames > settings_.max_lost_frames)) {
      arv_camera_stop_acquisition(cam.camera(), nullptr);
      return fail(ErrorCode::kSequenceGap, who + ": " + std::to_string(outcome.lost_frames) +
                                               " frame(s) of " + std::to_string(per_frame) +
                                               " lines lost (max_lost_frames " +
                                               std::to_string(settings_.max_lost_frames) + ")");
    }
    const double done = double(std::min(covered * per_frame, lines)) / double(lines);
    if (progress && !progress(done)) {
      arv_camera_stop_acquisition(cam.camera(), nullptr);
      return fail(ErrorCode::kCancelled,
                  who + ": scan cancelled at " + std::to_string(int(done * 100.0)) + " %");
    }
  }
  arv_camera_stop_acquisition(cam.camera(), &error);
  if (error != nullptr) {
    take(error);
    if (!cam.responds()) {
      gone = true;
      return fail(ErrorCode::kDeviceGone, who + ": gone at the end of the scan");
    }
  }
  outcome.lines = lines;
  outcome_ = outcome;
  return cloud;
}

}  // namespace springscan::drivers::genicam
