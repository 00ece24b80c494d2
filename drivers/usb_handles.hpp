#pragma once
// RAII owners for every libusb handle the transport creates (STYLE.md §6): context, device
// list, device handle with its claimed interface, transfers, hotplug registration. Internal to
// drivers/usb_transport.cpp; not part of the drivers' public interface.

#include <libusb.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "drivers/usb_transport.hpp"

namespace springscan::drivers::usb {

struct ContextDeleter {
  void operator()(libusb_context* c) const { libusb_exit(c); }
};
using ContextPtr = std::unique_ptr<libusb_context, ContextDeleter>;

struct HandleDeleter {
  void operator()(libusb_device_handle* h) const { libusb_close(h); }
};
using HandlePtr = std::unique_ptr<libusb_device_handle, HandleDeleter>;

struct TransferDeleter {
  void operator()(libusb_transfer* t) const { libusb_free_transfer(t); }
};
using TransferPtr = std::unique_ptr<libusb_transfer, TransferDeleter>;

struct DeviceListDeleter {
  void operator()(libusb_device** list) const { libusb_free_device_list(list, 1); }
};
using DeviceListPtr = std::unique_ptr<libusb_device*, DeviceListDeleter>;

/// A hotplug callback registration; deregistered on destruction. The callback runs inside
/// libusb_handle_events and must only do bookkeeping.
class HotplugRegistration {
 public:
  using Callback = std::function<void(libusb_device*, bool arrived)>;
  HotplugRegistration() = default;
  ~HotplugRegistration();
  HotplugRegistration(const HotplugRegistration&) = delete;
  HotplugRegistration& operator=(const HotplugRegistration&) = delete;
  /// Returns a libusb error code; on failure the transport simply works without hotplug.
  int register_for(libusb_context* context, std::uint16_t vendor_id, std::uint16_t product_id,
                   Callback callback);

 private:
  libusb_context* context_ = nullptr;
  libusb_hotplug_callback_handle handle_ = 0;
  std::unique_ptr<Callback> callback_;
};

/// An opened device: the handle, the claimed interface, and the bulk IN transfers with the
/// bytes they delivered. Movable; the state the callbacks see lives at a fixed address.
class OpenDevice {
 public:
  OpenDevice();
  OpenDevice(HandlePtr handle, int interface_number);
  ~OpenDevice();
  OpenDevice(OpenDevice&&) noexcept;
  OpenDevice& operator=(OpenDevice&&) noexcept;

  bool is_open() const { return state_ != nullptr; }
  libusb_device_handle* handle() const;
  /// True when `device` is the one this handle was opened on.
  bool is(libusb_device* device) const;
  bool gone() const;
  void mark_gone();
  bool halted() const;

  /// Allocates and submits the bulk IN transfers. Returns a libusb error code.
  int start_reading(const UsbSettings& settings, UsbStats* stats);
  /// Submits every transfer that is not in flight (after a cleared stall).
  int resubmit_idle();
  /// Cancels the transfers and handles events until all have come back (or the timeout).
  void stop_reading(libusb_context* context, int timeout_ms);
  /// Moves the bytes received so far to the end of `out`; false when there were none.
  bool take_received(std::vector<std::uint8_t>& out);
  bool take_overflow();
  bool take_io_error();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// Finds the first device matching the settings' VID, PID and serial, opens it and claims the
/// interface. On failure the result is not open, `code` holds the libusb error (0: none
/// matched) and `step` says what failed.
OpenDevice open_matching(libusb_context* context, const UsbSettings& settings, int& code,
                         std::string& step);

}  // namespace springscan::drivers::usb
