// The simulated GenICam profiler: Aravis's fake GigE Vision camera with our description and
// fill. The only simulator file that sees Aravis.
#include "simulators/genicam_camera.hpp"

#include <arv.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <limits>

#include "simulators/parts/produced_part.hpp"

namespace springscan::simulators {
namespace {

// Our registers (genicam_camera.xml): the Scan3d block, indexed by Scan3dCoordinateSelector.
constexpr std::uint32_t kScale = 0x410, kOffset = 0x430, kInvalidFlag = 0x450,
                        kInvalidValue = 0x460, kDeviceModelName = 0x68;
constexpr std::uint32_t kCoordinate[3] = {0, 1, 2};  // A, B, C

void write_double(ArvFakeCamera* camera, std::uint32_t address, double value) {
  std::uint64_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  bits = GUINT64_TO_BE(bits);  // FloatReg BigEndian in the XML
  arv_fake_camera_write_memory(camera, address, sizeof bits, &bits);
}

void put_u16(std::uint8_t* p, std::uint16_t v) {  // PFNC pixels are little-endian
  p[0] = static_cast<std::uint8_t>(v & 0xFF);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}

void fill_pattern(ArvBuffer* buffer, void* self, guint32, guint32, ArvPixelFormat format) {
  auto* data = static_cast<std::uint8_t*>(const_cast<void*>(arv_buffer_get_data(buffer, nullptr)));
  const std::int64_t lost_before = static_cast<GenicamCamera*>(self)->fill(
      data, static_cast<std::uint32_t>(arv_buffer_get_image_width(buffer)),
      static_cast<std::uint32_t>(arv_buffer_get_image_height(buffer)), format);
  // The fake camera numbers its frames itself, before the fill: a frame that was "lost" took
  // an id that never went out, so every later frame goes out that many ids on (GVSP block ids
  // are 16-bit and never 0).
  if (lost_before > 0) {
    const std::uint64_t id = arv_buffer_get_frame_id(buffer) + std::uint64_t(lost_before);
    arv_buffer_set_frame_id(buffer, (id - 1) % 0xFFFF + 1);
  }
}

}  // namespace

std::string default_genicam_xml() { return SPRINGSCAN_GENICAM_XML; }

analysis::Expected<RangeImage> range_image(const parts::LaserScan& scan, double head_z_mm) {
  const auto& points = scan.cloud.points;
  if (points.empty()) return analysis::fail("range_image: the scan has no points");
  if (!(scan.point_spacing_mm > 0.0) || !(scan.line_spacing_mm > 0.0))
    return analysis::fail("range_image: spacings must be positive");
  RangeImage image;
  image.dx_mm = scan.point_spacing_mm;
  image.dy_mm = scan.line_spacing_mm;
  // The rays lie on a regular grid across the view and noise moves points along the ray only,
  // so every point's (x, y) is a grid node: bin relative to the first point.
  const analysis::Vec3 anchor = points.front();
  const auto node = [&](const analysis::Vec3& p) {
    return std::pair{std::lround((p.x() - anchor.x()) / image.dx_mm),
                     std::lround((p.y() - anchor.y()) / image.dy_mm)};
  };
  long c0 = 0, c1 = 0, r0 = 0, r1 = 0;
  for (const auto& p : points) {
    const auto [c, r] = node(p);
    c0 = std::min(c0, c), c1 = std::max(c1, c), r0 = std::min(r0, r), r1 = std::max(r1, r);
  }
  image.width = static_cast<int>(c1 - c0 + 1);
  image.lines = static_cast<int>(r1 - r0 + 1);
  image.x0_mm = anchor.x() + double(c0) * image.dx_mm;
  image.y0_mm = anchor.y() + double(r0) * image.dy_mm;
  image.range_mm.assign(std::size_t(image.width) * std::size_t(image.lines),
                        std::numeric_limits<float>::quiet_NaN());
  for (const auto& p : points) {
    const auto [c, r] = node(p);
    float& cell =
        image.range_mm[std::size_t(r - r0) * std::size_t(image.width) + std::size_t(c - c0)];
    const auto range = static_cast<float>(head_z_mm - p.z());
    if (std::isnan(cell) || range < cell) cell = range;  // the nearest return wins
  }
  return image;
}

analysis::Expected<RangeImage> part_range_image(const std::string& cad_file,
                                                const std::vector<double>& springback_deg,
                                                const parts::LaserScanSettings& settings,
                                                double head_z_mm) {
  auto cad = parts::load_cad_part(cad_file);
  if (!cad) return cad.error();
  auto part = parts::make_produced_part(cad->model, cad->shape, springback_deg);
  if (!part) return part.error();
  auto scan = parts::laser_scan(*part, settings);
  if (!scan) return scan.error();
  return range_image(*scan, head_z_mm);
}

GenicamCamera::GenicamCamera(GenicamCameraSettings settings, RangeImage image)
    : settings_(std::move(settings)),
      image_(std::move(image)),
      lose_every_(settings_.lose_every_nth_frame) {}

analysis::Expected<std::unique_ptr<GenicamCamera>> GenicamCamera::start(
    GenicamCameraSettings settings, RangeImage image) {
  std::unique_ptr<GenicamCamera> camera(new GenicamCamera(std::move(settings), std::move(image)));
  if (auto opened = camera->open_camera(); !opened) return opened.error();
  camera->watcher_ = std::thread([c = camera.get()] { c->watch(); });
  return camera;
}

GenicamCamera::~GenicamCamera() {
  stop_ = true;
  if (watcher_.joinable()) watcher_.join();
  if (camera_ != nullptr) g_object_unref(camera_);
}

analysis::Expected<bool> GenicamCamera::open_camera() {
  const auto& s = settings_;
  ArvGvFakeCamera* gv = arv_gv_fake_camera_new_full(s.interface_address.c_str(), s.serial.c_str(),
                                                    s.genicam_xml.c_str());
  if (gv == nullptr || !arv_gv_fake_camera_is_running(gv)) {
    if (gv != nullptr) g_object_unref(gv);
    return analysis::fail(analysis::ErrorCode::kOsError,
                          "GenICam camera simulator: cannot serve on " + s.interface_address +
                              " (GVCP port 3956 taken by another camera, or no such address)");
  }
  ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(gv);
  char model[32] = "springscan profiler sim";
  arv_fake_camera_write_memory(fake, kDeviceModelName, sizeof model, model);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_WIDTH,
                                 static_cast<guint32>(image_.width));
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_HEIGHT,
                                 static_cast<guint32>(s.lines_per_frame));
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_PIXEL_FORMAT, 0x011000B8);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_ACQUISITION_FRAME_PERIOD_US,
                                 static_cast<guint32>(s.frame_period_us));
  const double scale[3] = {image_.dx_mm, 1.0, s.scale_c_mm};
  const double offset[3] = {image_.x0_mm, 0.0, s.offset_c_mm};
  for (std::uint32_t k : kCoordinate) {
    write_double(fake, kScale + 8 * k, scale[k]);
    write_double(fake, kOffset + 8 * k, offset[k]);
    arv_fake_camera_write_register(fake, kInvalidFlag + 4 * k, k == 2 ? 1 : 0);
    write_double(fake, kInvalidValue + 8 * k, 0.0);  // C16: raw 0 is "no return"
  }
  fake_ = fake;
  stream_port_ = -1;
  arv_fake_camera_set_fill_pattern(fake, fill_pattern, this);
  std::lock_guard lock(mutex_);
  camera_ = gv;
  restart_ = true;
  present_ = true;
  return true;
}

std::int64_t GenicamCamera::fill(std::uint8_t* data, std::uint32_t width, std::uint32_t height,
                                 std::uint32_t format) {
  // Each scan opens a new stream (a new UDP port): a new destination is a new pass of the part
  // too, should watch() have missed the stop between two scans on a loaded machine.
  int port = 0;
  if (GSocketAddress* to = arv_fake_camera_get_stream_address(static_cast<ArvFakeCamera*>(fake_))) {
    port = g_inet_socket_address_get_port(G_INET_SOCKET_ADDRESS(to));
    g_object_unref(to);
  }
  const bool new_stream = port != stream_port_;
  stream_port_ = port;
  if (restart_.exchange(false) || new_stream) {
    cursor_ = 0;
    frame_in_pass_ = 0;
    ++scans_;
  }
  // A lost frame: its lines pass under the head, its id is used, nothing of it arrives. Only
  // frames of the part's lines are lost, so the count does not depend on how soon after the
  // part the receiver stops the acquisition.
  if (const int every = lose_every_.load();
      every > 0 && (frame_in_pass_ + 1) % every == 0 && cursor_ < image_.lines) {
    cursor_ += height;
    ++frame_in_pass_;
    ++lost_;
  }
  ++frame_in_pass_;
  const auto& s = settings_;
  const bool abc = format == 0x026000C0;  // Coord3D_ABC32f; else C16 or Mono16
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::uint32_t row = 0; row < height; ++row) {
    const std::int64_t line = cursor_ + row;
    for (std::uint32_t i = 0; i < width; ++i) {
      const bool inside = line < image_.lines && i < std::uint32_t(image_.width);
      const float r =
          inside ? image_.range_mm[std::size_t(line) * std::size_t(image_.width) + i] : nan;
      const double raw = (double(r) - s.offset_c_mm) / s.scale_c_mm;
      if (abc) {
        const float abc_raw[3] = {float(i), 0.0f, std::isnan(r) ? nan : float(raw)};
        std::memcpy(data, abc_raw, sizeof abc_raw);
        data += sizeof abc_raw;
      } else {
        put_u16(data, std::isnan(r)
                          ? 0
                          : static_cast<std::uint16_t>(std::clamp(std::lround(raw), 1L, 65535L)));
        data += 2;
      }
    }
  }
  cursor_ += height;
  if (s.vanish_after_lines >= 0 && cursor_ >= s.vanish_after_lines && !vanished_once_) {
    vanished_once_ = true;
    vanish_ = true;
    // No frame after this one: hold Aravis's camera thread here until watch() tears the camera
    // down (which waits for this thread, then closes the sockets).
    while (!closing_.load() && !stop_.load())
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return lost_.load();
}

void GenicamCamera::watch() {
  using Clock = std::chrono::steady_clock;
  Clock::time_point vanished_at;
  while (!stop_.load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    std::unique_lock lock(mutex_);
    auto* gv = static_cast<ArvGvFakeCamera*>(camera_);
    if (gv != nullptr && vanish_.exchange(false)) {
      closing_ = true;
      g_object_unref(gv);
      closing_ = false;  // closes its sockets: no answer on GVCP, no more frames
      camera_ = nullptr;
      present_ = false;
      vanished_at = Clock::now();
      continue;
    }
    if (gv == nullptr) {
      const double waited = std::chrono::duration<double>(Clock::now() - vanished_at).count();
      if (bring_back_.exchange(false) ||
          (settings_.return_after_s >= 0.0 && waited >= settings_.return_after_s)) {
        lock.unlock();
        (void)open_camera();  // a port still held is retried on the next round
      }
      continue;
    }
    // Between scans the driver stops the acquisition: the next frame is a new pass of the part.
    if (arv_fake_camera_get_acquisition_status(arv_gv_fake_camera_get_fake_camera(gv)) == 0)
      restart_ = true;
  }
}

}  // namespace springscan::simulators
