#include "drivers/usb_transport.hpp"

#include <algorithm>
#include <chrono>

#include "drivers/usb_handles.hpp"

namespace springscan::drivers {
namespace {

using Clock = std::chrono::steady_clock;

std::string hex4(unsigned v) {
  static const char* digits = "0123456789abcdef";
  std::string s(4, '0');
  for (int i = 3; i >= 0; --i, v >>= 4) s[static_cast<std::size_t>(i)] = digits[v & 0xF];
  return s;
}

}  // namespace

std::string to_string(UsbError error) {
  switch (error) {
    case UsbError::kOk:
      return "ok";
    case UsbError::kNotFound:
      return "device not found";
    case UsbError::kAccess:
      return "access denied";
    case UsbError::kBusy:
      return "interface busy";
    case UsbError::kNoDevice:
      return "device disconnected";
    case UsbError::kTimeout:
      return "timeout";
    case UsbError::kPipe:
      return "endpoint stalled";
    case UsbError::kOverflow:
      return "transfer overflow";
    case UsbError::kIo:
      return "I/O error";
  }
  return "unknown USB error";
}

UsbError usb_error_from_libusb(int code) {
  switch (code) {
    case LIBUSB_SUCCESS:
      return UsbError::kOk;
    case LIBUSB_ERROR_NOT_FOUND:
      return UsbError::kNotFound;
    case LIBUSB_ERROR_ACCESS:
      return UsbError::kAccess;
    case LIBUSB_ERROR_BUSY:
      return UsbError::kBusy;
    case LIBUSB_ERROR_NO_DEVICE:
      return UsbError::kNoDevice;
    case LIBUSB_ERROR_TIMEOUT:
      return UsbError::kTimeout;
    case LIBUSB_ERROR_PIPE:
      return UsbError::kPipe;
    case LIBUSB_ERROR_OVERFLOW:
      return UsbError::kOverflow;
    default:
      return UsbError::kIo;
  }
}

analysis::ErrorCode to_error_code(UsbError error) {
  using analysis::ErrorCode;
  switch (error) {
    case UsbError::kOk:
      return ErrorCode::kInternal;  // not an error: a caller mixed up its branches
    case UsbError::kNotFound:
      return ErrorCode::kNotFound;
    case UsbError::kNoDevice:
      return ErrorCode::kDeviceGone;
    case UsbError::kTimeout:
      return ErrorCode::kTimeout;
    case UsbError::kPipe:
      return ErrorCode::kStalledEndpoint;
    case UsbError::kAccess:
    case UsbError::kBusy:
    case UsbError::kOverflow:
    case UsbError::kIo:
      return ErrorCode::kOsError;
  }
  return ErrorCode::kInternal;
}

struct UsbTransport::Impl {
  usb::ContextPtr context;
  usb::HotplugRegistration hotplug;
  usb::OpenDevice device;  // declared after the context: destroyed first
  bool hotplug_left = false;
};

analysis::Expected<std::unique_ptr<UsbTransport>> UsbTransport::create(
    const UsbSettings& settings) {
  if (settings.transfers_in_flight < 1 || settings.transfers_in_flight > 16)
    return analysis::fail(analysis::ErrorCode::kInvalidSettings,
                          "usb settings: transfers_in_flight " +
                              std::to_string(settings.transfers_in_flight) + " outside 1..16");
  if (settings.transfer_bytes < protocol::kMaxPacketSize ||
      settings.transfer_bytes % protocol::kMaxPacketSize != 0 || settings.transfer_bytes > 1 << 20)
    return analysis::fail(analysis::ErrorCode::kInvalidSettings,
                          "usb settings: transfer_bytes " +
                              std::to_string(settings.transfer_bytes) +
                              " must be a multiple of 512 up to 1 MiB");
  auto impl = std::make_unique<Impl>();
  libusb_context* raw = nullptr;
  // An explicit context, never the default one (STYLE.md §6).
  if (const int rc = libusb_init(&raw); rc != LIBUSB_SUCCESS)
    return analysis::fail(analysis::ErrorCode::kOsError,
                          std::string("libusb_init: ") + libusb_error_name(rc));
  impl->context.reset(raw);
  auto transport = std::unique_ptr<UsbTransport>(new UsbTransport(std::move(impl), settings));
  if (libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) {
    Impl* state = transport->impl_.get();
    state->hotplug.register_for(state->context.get(), settings.vendor_id, settings.product_id,
                                [state](libusb_device* dev, bool arrived) {
                                  // Bookkeeping only: opening happens in open() (notes §3).
                                  if (!arrived && state->device.is(dev)) state->hotplug_left = true;
                                });
  }
  return transport;
}

UsbTransport::UsbTransport(std::unique_ptr<Impl> impl, const UsbSettings& settings)
    : impl_(std::move(impl)), settings_(settings) {}

UsbTransport::~UsbTransport() { close(); }

UsbError UsbTransport::fail(UsbError error, const std::string& what, int code) {
  detail_ = "usb " + hex4(settings_.vendor_id) + ":" + hex4(settings_.product_id) +
            (settings_.serial.empty() ? "" : " serial " + settings_.serial) + ": " + what;
  if (code != 0) detail_ += std::string(": ") + libusb_error_name(code);
  return error;
}

bool UsbTransport::is_open() const { return impl_->device.is_open(); }

bool UsbTransport::online() const {
  return is_open() && !impl_->hotplug_left && !impl_->device.gone();
}

UsbError UsbTransport::open() {
  if (is_open()) return UsbError::kOk;
  pump(0);  // deliver pending hotplug events first
  impl_->hotplug_left = false;
  int code = 0;
  std::string step;
  usb::OpenDevice dev = usb::open_matching(impl_->context.get(), settings_, code, step);
  if (!dev.is_open()) {
    return fail(code == 0 ? UsbError::kNotFound : usb_error_from_libusb(code), step, code);
  }
  if (const int rc = dev.start_reading(settings_, &stats_); rc != LIBUSB_SUCCESS)
    return fail(usb_error_from_libusb(rc), "submitting bulk IN transfers", rc);
  impl_->device = std::move(dev);
  ++stats_.opens;
  return UsbError::kOk;
}

void UsbTransport::close() {
  if (!is_open()) return;
  impl_->device.stop_reading(impl_->context.get(), settings_.close_timeout_ms);
  impl_->device = usb::OpenDevice{};
}

void UsbTransport::pump(int timeout_ms) {
  timeval tv{timeout_ms / 1000, (timeout_ms % 1000) * 1000};
  libusb_handle_events_timeout_completed(impl_->context.get(), &tv, nullptr);
}

UsbError UsbTransport::write(std::span<const std::uint8_t> bytes) {
  if (!online()) return fail(UsbError::kNoDevice, "write: device not open");
  for (int attempt = 0;; ++attempt) {
    int sent = 0;
    const int rc = libusb_bulk_transfer(
        impl_->device.handle(), settings_.endpoint_out, const_cast<std::uint8_t*>(bytes.data()),
        static_cast<int>(bytes.size()), &sent, static_cast<unsigned>(settings_.write_timeout_ms));
    if (rc == LIBUSB_SUCCESS && static_cast<std::size_t>(sent) == bytes.size())
      return UsbError::kOk;
    if (rc == LIBUSB_ERROR_PIPE && attempt == 0) {
      // A stalled OUT endpoint: clear it and send again, once (notes §3).
      libusb_clear_halt(impl_->device.handle(), settings_.endpoint_out);
      ++stats_.stalls_cleared;
      continue;
    }
    if (rc == LIBUSB_ERROR_NO_DEVICE) impl_->device.mark_gone();
    if (rc == LIBUSB_SUCCESS) return fail(UsbError::kTimeout, "bulk OUT: short write");
    return fail(usb_error_from_libusb(rc), "bulk OUT endpoint 0x02", rc);
  }
}

UsbError UsbTransport::read(std::vector<std::uint8_t>& out, int timeout_ms) {
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
  for (;;) {
    if (!is_open()) return fail(UsbError::kNoDevice, "read: device not open");
    usb::OpenDevice& dev = impl_->device;
    if (dev.take_received(out)) return UsbError::kOk;
    if (dev.gone() || impl_->hotplug_left) {
      ++stats_.device_left;
      return fail(UsbError::kNoDevice, "bulk IN: device disconnected");
    }
    if (dev.halted()) {
      // STALL: clear the halt here, outside the callback, then resubmit (notes §3).
      const int rc = libusb_clear_halt(dev.handle(), settings_.endpoint_in);
      if (rc == LIBUSB_ERROR_NO_DEVICE) dev.mark_gone();
      // A halt that cannot be cleared leaves the endpoint stalled (kPipe), whatever libusb
      // calls the failure (usbfs reports most CLEAR_HALT errors as LIBUSB_ERROR_OTHER).
      if (rc != LIBUSB_SUCCESS)
        return fail(rc == LIBUSB_ERROR_NO_DEVICE ? UsbError::kNoDevice : UsbError::kPipe,
                    "clear halt on 0x81", rc);
      ++stats_.stalls_cleared;
      if (const int rs = dev.resubmit_idle(); rs != LIBUSB_SUCCESS)
        return fail(usb_error_from_libusb(rs), "resubmitting bulk IN after a stall", rs);
      continue;
    }
    if (dev.take_overflow()) return fail(UsbError::kOverflow, "bulk IN transfer overflowed");
    if (dev.take_io_error()) return fail(UsbError::kIo, "bulk IN transfer failed");
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left.count() <= 0)
      return fail(UsbError::kTimeout,
                  "bulk IN: no data within " + std::to_string(timeout_ms) + " ms");
    pump(static_cast<int>(std::min<long>(left.count(), 50)));
  }
}

UsbError UsbTransport::reset() {
  if (!is_open()) return UsbError::kNoDevice;
  ++stats_.resets;
  const int rc = libusb_reset_device(impl_->device.handle());
  if (rc == LIBUSB_SUCCESS) return UsbError::kOk;
  // NOT_FOUND after a reset: the device re-enumerated; the handle is stale (notes §3).
  close();
  return fail(usb_error_from_libusb(rc), "libusb_reset_device", rc);
}

}  // namespace springscan::drivers
