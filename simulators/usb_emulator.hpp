#pragma once
// The simulated scanner presented to libusb as a USB device, through umockdev's ioctl emulation
// (libumockdev): a testbed with the device's sysfs entry and descriptors, and a handler that
// answers the usbfs ioctls libusb issues on /dev/bus/usb/BBB/DDD (SUBMITURB, REAPURB[NDELAY],
// DISCARDURB, CLAIMINTERFACE, CLEAR_HALT, ...) by feeding bulk OUT to the ScannerDevice and
// filling bulk IN URBs from it. The technique of libusb's tests/umockdev.c; notes in
// ../shared/reference/plc-usb-reliability-notes.md §3.
//
// The process (or a child started with LD_PRELOAD=libumockdev-preload.so.0 and UMOCKDEV_DIR =
// root_dir()) then sees the device in place of real hardware: the production libusb code runs
// unchanged. Creating an emulator sets UMOCKDEV_DIR in this process's environment; at most one
// emulator may exist per process.
//
// Thread safety: plug() and unplug() may be called from any thread; umockdev calls the ioctl
// handler from its own worker thread; all device state is guarded by one mutex.

#include <cstdint>
#include <memory>
#include <string>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"
#include "simulators/scanner_device.hpp"

namespace springscan::simulators {

struct EmulatorSettings {
  int bus_number = 1;     ///< /dev/bus/usb/BBB
  int device_number = 2;  ///< /dev/bus/usb/BBB/DDD
  /// idProduct; 0: from the identity's kind (docs/device-protocol.md §1)
  std::uint16_t product_id = 0;
};

/// What the emulated device saw, for tests and the simulator's log.
struct EmulatorStats {
  std::uint64_t urbs_submitted = 0;
  std::uint64_t urbs_discarded = 0;
  std::uint64_t halts_cleared = 0;
  std::uint64_t unplugs = 0;
  std::uint64_t plugs = 0;
  std::uint64_t resets = 0;
};

class EmulatedUsbScanner {
 public:
  /// Builds the testbed and plugs in a device that scans `surface` (part frame, mm).
  static analysis::Expected<std::unique_ptr<EmulatedUsbScanner>> create(
      const ScannerDeviceSettings& device, analysis::PointCloud surface,
      const EmulatorSettings& settings = {});
  ~EmulatedUsbScanner();
  EmulatedUsbScanner(const EmulatedUsbScanner&) = delete;
  EmulatedUsbScanner& operator=(const EmulatedUsbScanner&) = delete;

  /// As if the cable were pulled: queued URBs complete with -ESHUTDOWN, further ioctls fail
  /// with ENODEV, and a "remove" uevent goes out (libusb hotplug sees DEVICE_LEFT).
  void unplug();
  /// Plugs in a fresh device (power-on state; the faults armed again) with an "add" uevent.
  void plug();
  /// Replaces the fault settings for the next plug().
  void set_faults(const DeviceFaults& faults);
  /// Arms `faults` on the device plugged in now, without a replug (ScannerDevice::arm_faults):
  /// each fires once, in the next scan. No effect while unplugged; plug() arms set_faults().
  void arm_faults(const DeviceFaults& faults);
  /// Replaces the laser pattern (head mounts, ScannerDevice::set_laser_pattern) of the device
  /// plugged in now, from its next scan on, and of every later plug(): a head that moved.
  void set_laser_pattern(const LaserPatternSettings& laser);
  bool plugged() const;
  /// The testbed root: UMOCKDEV_DIR for a child process.
  std::string root_dir() const;
  EmulatorStats stats() const;
  /// Scans the current device has started.
  std::uint32_t scans_started() const;

  struct Impl;

 private:
  explicit EmulatedUsbScanner(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// The libumockdev preload library to put in LD_PRELOAD of a child process.
std::string umockdev_preload_library();

}  // namespace springscan::simulators
