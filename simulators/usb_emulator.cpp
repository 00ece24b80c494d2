#include "simulators/usb_emulator.hpp"

#include <cstdio>

#include "simulators/usb_emulator_internal.hpp"

namespace springscan::simulators {
namespace {

namespace p = drivers::protocol;

void put16(std::vector<std::uint8_t>& v, std::uint16_t x) {
  v.push_back(static_cast<std::uint8_t>(x & 0xFF));
  v.push_back(static_cast<std::uint8_t>(x >> 8));
}

std::string hex(const std::vector<std::uint8_t>& bytes) {
  std::string s;
  char b[3];
  for (const auto x : bytes) {
    std::snprintf(b, sizeof b, "%02x", x);
    s += b;
  }
  return s;
}

std::vector<std::uint8_t> string_descriptor(const std::string& text) {
  std::vector<std::uint8_t> d{static_cast<std::uint8_t>(2 + 2 * text.size()), 3};
  for (const char c : text) put16(d, static_cast<std::uint8_t>(c));  // UTF-16LE of ASCII
  return d;
}

gboolean on_handle_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self) {
  static_cast<EmulatedUsbScanner::Impl*>(self)->handle_ioctl(client);
  return TRUE;
}

// Clients are tracked from "client-connected" (with a reference) until their stream is seen
// closed: see Impl::sweep_closed_clients_locked.
void on_client_connected(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self) {
  auto* impl = static_cast<EmulatedUsbScanner::Impl*>(self);
  g_object_ref(client);  // released when the client is forgotten
  std::lock_guard lock(impl->mutex);
  impl->open_clients.insert(client);
}

}  // namespace

std::vector<std::uint8_t> EmulatedUsbScanner::Impl::descriptors() const {
  // §1: device descriptor, then configuration 1 with the vendor interface and its two bulk
  // endpoints (USB 2.0 spec, 9.6).
  std::vector<std::uint8_t> d{18, 1, 0x00, 0x02, 0xFF, 0x00, 0x00, 64};
  put16(d, p::kVendorId);
  put16(d, product_id);
  put16(d, 0x0100);  // bcdDevice
  d.insert(d.end(), {p::kStringManufacturer, p::kStringProduct, p::kStringSerial, 1});
  d.insert(d.end(), {9, 2, 32, 0, 1, 1, 0, 0x80, 50});  // configuration, 32 bytes total
  d.insert(d.end(), {9, 4, p::kInterfaceNumber, 0, 2, 0xFF, 0, 0, 0});  // interface 0
  for (const std::uint8_t ep : {p::kEndpointIn, p::kEndpointOut}) {
    d.insert(d.end(), {7, 5, ep, 2});  // bulk
    put16(d, p::kMaxPacketSize);
    d.push_back(0);
  }
  return d;
}

std::vector<std::uint8_t> EmulatedUsbScanner::Impl::control_reply(
    const std::uint8_t setup[8]) const {
  const std::uint8_t request_type = setup[0], request = setup[1];
  const std::uint8_t index = setup[2], type = setup[3];
  if (request_type != 0x80 || request != 6) return {};  // only standard GET_DESCRIPTOR
  const auto all = descriptors();
  if (type == 1) return {all.begin(), all.begin() + 18};
  if (type == 2) return {all.begin() + 18, all.end()};
  if (type != 3) return {};
  if (index == 0) return {4, 3, 0x09, 0x04};  // language: US English
  if (index == p::kStringManufacturer) return string_descriptor("springscan simulator");
  if (index == p::kStringProduct) return string_descriptor(device_settings.identity.model);
  if (index == p::kStringSerial) return string_descriptor(device_settings.identity.serial);
  return {};
}

analysis::Expected<std::unique_ptr<EmulatedUsbScanner>> EmulatedUsbScanner::create(
    const ScannerDeviceSettings& device, analysis::PointCloud surface,
    const EmulatorSettings& settings) {
  if (settings.bus_number < 1 || settings.bus_number > 999 || settings.device_number < 1 ||
      settings.device_number > 127)
    return analysis::fail("usb emulator: bus " + std::to_string(settings.bus_number) +
                          " / device " + std::to_string(settings.device_number) + " out of range");
  auto impl = std::make_unique<Impl>();
  char bus[4], dev[4];
  std::snprintf(bus, sizeof bus, "%03d", settings.bus_number);
  std::snprintf(dev, sizeof dev, "%03d", settings.device_number);
  impl->product_id = settings.product_id != 0                             ? settings.product_id
                     : device.identity.kind == p::ScannerKind::kLaserLine ? p::kProductIdLaser
                                                                          : p::kProductIdTactile;
  impl->device_settings = device;
  impl->surface = std::move(surface);
  const std::string port = std::to_string(settings.bus_number) + "-1";
  impl->sysfs_path =
      "/devices/pci0000:00/0000:00:14.0/usb" + std::to_string(settings.bus_number) + "/" + port;
  impl->dev_node = std::string("/dev/bus/usb/") + bus + "/" + dev;
  impl->description =
      "P: " + impl->sysfs_path + "\nN: bus/usb/" + bus + "/" + dev +
      "\nE: SUBSYSTEM=usb\nE: DRIVER=usb\nE: DEVTYPE=usb_device\nE: BUSNUM=" + bus +
      "\nE: DEVNUM=" + dev + "\nE: DEVNAME=" + impl->dev_node +
      "\nA: busnum=" + std::to_string(settings.bus_number) +
      "\\n\nA: devnum=" + std::to_string(settings.device_number) +
      "\\n\nA: bConfigurationValue=1\\n\nA: speed=480\\n\nA: serial=" + device.identity.serial +
      "\\n\nH: descriptors=" + hex(impl->descriptors()) + "\n";
  impl->testbed = umockdev_testbed_new();  // sets UMOCKDEV_DIR for this process
  impl->handler = umockdev_ioctl_base_new();
  g_signal_connect(impl->handler, "handle-ioctl", G_CALLBACK(on_handle_ioctl), impl.get());
  g_signal_connect(impl->handler, "client-connected", G_CALLBACK(on_client_connected), impl.get());
  GError* error = nullptr;
  // The handler goes on first, so the node answers as soon as the device appears.
  if (!umockdev_testbed_attach_ioctl(impl->testbed, impl->dev_node.c_str(), impl->handler,
                                     &error)) {
    std::string message = "umockdev_testbed_attach_ioctl " + impl->dev_node + ": " +
                          (error ? error->message : "failed");
    g_clear_error(&error);
    return analysis::fail(message);
  }
  auto emulator = std::unique_ptr<EmulatedUsbScanner>(new EmulatedUsbScanner(std::move(impl)));
  emulator->plug();
  if (!emulator->plugged())
    return analysis::fail("umockdev: could not add " + emulator->impl_->dev_node);
  return emulator;
}

EmulatedUsbScanner::EmulatedUsbScanner(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

EmulatedUsbScanner::~EmulatedUsbScanner() {
  for (auto& t : impl_->hotplug_threads) t.join();
  umockdev_testbed_detach_ioctl(impl_->testbed, impl_->dev_node.c_str(), nullptr);
  g_signal_handlers_disconnect_by_data(impl_->handler, impl_.get());
  std::set<UMockdevIoctlClient*> open;
  {
    std::lock_guard lock(impl_->mutex);
    open.swap(impl_->open_clients);
  }
  for (UMockdevIoctlClient* client : open) g_object_unref(client);
  g_object_unref(impl_->handler);
  g_object_unref(impl_->testbed);
}

void EmulatedUsbScanner::unplug() {
  {
    std::lock_guard lock(impl_->mutex);
    if (!impl_->plugged || impl_->unplugging) return;
    impl_->unplugging = true;
  }
  impl_->disconnect();  // on the caller's thread: unplugged when this returns
}

void EmulatedUsbScanner::plug() {
  std::vector<std::thread> threads;
  {
    std::lock_guard lock(impl_->mutex);
    threads.swap(impl_->hotplug_threads);
  }
  for (auto& t : threads) t.join();  // a removal under way must be finished first
  {
    std::lock_guard lock(impl_->mutex);
    if (impl_->plugged) return;
    impl_->device = std::make_unique<ScannerDevice>(impl_->device_settings, impl_->surface);
    impl_->in_halted = false;
    ++impl_->generation;
    ++impl_->stats.plugs;
    impl_->plugged = true;
  }
  GError* error = nullptr;
  if (!umockdev_testbed_add_from_string(impl_->testbed, impl_->description.c_str(), &error)) {
    g_clear_error(&error);
    std::lock_guard lock(impl_->mutex);
    impl_->plugged = false;
    return;
  }
  umockdev_testbed_uevent(impl_->testbed, ("/sys" + impl_->sysfs_path).c_str(), "add");
}

void EmulatedUsbScanner::set_faults(const DeviceFaults& faults) {
  std::lock_guard lock(impl_->mutex);
  impl_->device_settings.faults = faults;
}

void EmulatedUsbScanner::arm_faults(const DeviceFaults& faults) {
  std::lock_guard lock(impl_->mutex);
  if (impl_->device && impl_->plugged) impl_->device->arm_faults(faults);
}

void EmulatedUsbScanner::set_laser_pattern(const LaserPatternSettings& laser) {
  std::lock_guard lock(impl_->mutex);
  impl_->device_settings.laser = laser;
  if (impl_->device && impl_->plugged) impl_->device->set_laser_pattern(laser);
}

bool EmulatedUsbScanner::plugged() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->plugged;
}

std::string EmulatedUsbScanner::root_dir() const {
  gchar* dir = umockdev_testbed_get_root_dir(impl_->testbed);
  std::string s = dir != nullptr ? dir : "";
  g_free(dir);
  return s;
}

EmulatorStats EmulatedUsbScanner::stats() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->stats;
}

std::uint32_t EmulatedUsbScanner::scans_started() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->device ? impl_->device->scans_started() : 0;
}

std::string umockdev_preload_library() { return "libumockdev-preload.so.0"; }

}  // namespace springscan::simulators
