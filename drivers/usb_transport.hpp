#pragma once
// The libusb transport of the scanner protocol (docs/device-protocol.md §1, §7): an explicit
// libusb context, open by VID/PID/serial, the claimed vendor interface, several bulk IN
// transfers kept in flight, synchronous bulk OUT for commands, and hotplug. Every libusb handle
// has an RAII owner. The recovery rules follow ../shared/reference/plc-usb-reliability-notes.md
// §3: nothing but bookkeeping in callbacks, clear-halt and close outside them.
//
// Thread safety: none. One thread owns a transport and runs its only event loop (read(),
// write(), pump()); libusb calls the callbacks from inside that loop.

#include <libusb.h>

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "drivers/protocol.hpp"

namespace springscan::drivers {

/// Transport outcomes, with buckets for libusb's own errors (STYLE.md §5). This enum stays
/// inside the driver; to_error_code() maps it onto the shared analysis::ErrorCode, which is what
/// crosses the Scanner interface (the daemon and the CLI see one Error type from every layer).
enum class UsbError {
  kOk,
  kNotFound,  ///< no device with that VID/PID/serial
  kAccess,    ///< permission denied (udev rule missing)
  kBusy,      ///< interface claimed by another program
  kNoDevice,  ///< the device went away
  kTimeout,   ///< nothing arrived in time
  kPipe,      ///< an endpoint stalled and could not be cleared (clear-halt failed)
  kOverflow,  ///< the device sent more than a transfer could hold; data was lost
  kIo,        ///< any other libusb failure
};

std::string to_string(UsbError error);
/// Maps a libusb_error code to the bucket it belongs to.
UsbError usb_error_from_libusb(int code);
/// The shared code of a transport outcome (docs/device-protocol.md §7): kNotFound -> kNotFound,
/// kNoDevice -> kDeviceGone, kTimeout -> kTimeout, kPipe -> kStalledEndpoint, kAccess, kBusy,
/// kOverflow and kIo -> kOsError. kOk is not an error: kInternal.
analysis::ErrorCode to_error_code(UsbError error);

struct UsbSettings {
  std::uint16_t vendor_id = protocol::kVendorId;         ///< idVendor to match
  std::uint16_t product_id = protocol::kProductIdLaser;  ///< idProduct to match
  std::string serial;                                    ///< serial string; empty: any
  int interface_number = protocol::kInterfaceNumber;     ///< the vendor interface
  std::uint8_t endpoint_in = protocol::kEndpointIn;      ///< bulk IN endpoint address
  std::uint8_t endpoint_out = protocol::kEndpointOut;    ///< bulk OUT endpoint address
  int transfers_in_flight = 4;                           ///< bulk IN transfers kept queued, 1..16
  int transfer_bytes = 16384;                            ///< each, a multiple of 512
  int write_timeout_ms = 1000;                           ///< bulk OUT timeout
  int close_timeout_ms = 1000;                           ///< wait for cancelled transfers
};

/// What the transport had to recover from since it was created.
struct UsbStats {
  std::uint64_t bytes_in = 0;
  std::uint64_t stalls_cleared = 0;
  std::uint64_t overflows = 0;
  std::uint64_t opens = 0;
  std::uint64_t device_left = 0;  ///< hotplug or transfer reports of a vanished device
  std::uint64_t resets = 0;
};

class UsbTransport {
 public:
  /// Creates the libusb context and registers for hotplug (when the platform supports it).
  static analysis::Expected<std::unique_ptr<UsbTransport>> create(const UsbSettings& settings);
  ~UsbTransport();
  UsbTransport(const UsbTransport&) = delete;
  UsbTransport& operator=(const UsbTransport&) = delete;

  /// Finds, opens and claims the device and starts the bulk IN transfers. kOk when already open.
  UsbError open();
  /// Cancels the transfers, releases the interface and closes the handle.
  void close();
  bool is_open() const;
  /// Open and not reported gone (by hotplug or by a transfer).
  bool online() const;

  /// Sends bytes on bulk OUT (synchronously; clears a stalled OUT endpoint once).
  UsbError write(std::span<const std::uint8_t> bytes);
  /// Waits up to `timeout_ms` for bulk IN bytes and appends them to `out`.
  UsbError read(std::vector<std::uint8_t>& out, int timeout_ms);
  /// Handles pending libusb events (hotplug, completions) for at most `timeout_ms`.
  void pump(int timeout_ms);
  /// libusb_reset_device (after repeated timeouts); closes the handle when it fails.
  UsbError reset();

  /// Context of the last failure: which call, which device, what libusb said.
  const std::string& detail() const { return detail_; }
  const UsbStats& stats() const { return stats_; }
  const UsbSettings& settings() const { return settings_; }

 private:
  struct Impl;
  explicit UsbTransport(std::unique_ptr<Impl> impl, const UsbSettings& settings);
  UsbError fail(UsbError error, const std::string& what, int code = 0);
  std::unique_ptr<Impl> impl_;
  UsbSettings settings_;
  UsbStats stats_;
  std::string detail_;
};

}  // namespace springscan::drivers
