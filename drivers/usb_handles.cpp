#include "drivers/usb_handles.hpp"

#include <chrono>
#include <utility>

namespace springscan::drivers::usb {

HotplugRegistration::~HotplugRegistration() {
  if (context_ != nullptr) libusb_hotplug_deregister_callback(context_, handle_);
}

int HotplugRegistration::register_for(libusb_context* context, std::uint16_t vendor_id,
                                      std::uint16_t product_id, Callback callback) {
  callback_ = std::make_unique<Callback>(std::move(callback));
  const auto trampoline = [](libusb_context*, libusb_device* device, libusb_hotplug_event event,
                             void* user) -> int {
    (*static_cast<Callback*>(user))(device, event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED);
    return 0;  // stay registered
  };
  const int rc = libusb_hotplug_register_callback(
      context,
      static_cast<libusb_hotplug_event>(LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED |
                                        LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT),
      static_cast<libusb_hotplug_flag>(0), vendor_id, product_id, LIBUSB_HOTPLUG_MATCH_ANY,
      trampoline, callback_.get(), &handle_);
  if (rc == LIBUSB_SUCCESS) context_ = context;
  return rc;
}

// One bulk IN transfer and its buffer.
struct Slot {
  void* owner = nullptr;  // the OpenDevice::State
  TransferPtr transfer;
  std::vector<std::uint8_t> buffer;
  bool in_flight = false;
};

struct OpenDevice::State {
  HandlePtr handle;
  int interface_number = 0;
  std::vector<std::unique_ptr<Slot>> slots;
  std::vector<std::uint8_t> received;
  UsbStats* stats = nullptr;
  bool stopping = false;
  bool gone = false;
  bool halted = false;
  bool overflow = false;
  bool io_error = false;

  int submit(Slot& slot) {
    const int rc = libusb_submit_transfer(slot.transfer.get());
    slot.in_flight = rc == LIBUSB_SUCCESS;
    if (rc == LIBUSB_ERROR_NO_DEVICE) gone = true;
    return rc;
  }

  // Runs inside libusb_handle_events: bookkeeping and resubmission only (notes §3).
  static void LIBUSB_CALL on_complete(libusb_transfer* transfer) {
    auto& slot = *static_cast<Slot*>(transfer->user_data);
    auto& s = *static_cast<State*>(slot.owner);
    slot.in_flight = false;
    switch (transfer->status) {
      case LIBUSB_TRANSFER_COMPLETED:
      case LIBUSB_TRANSFER_TIMED_OUT:
        s.received.insert(s.received.end(), slot.buffer.data(),
                          slot.buffer.data() + transfer->actual_length);
        if (s.stats != nullptr)
          s.stats->bytes_in += static_cast<std::uint64_t>(transfer->actual_length);
        if (!s.stopping && s.submit(slot) != LIBUSB_SUCCESS && !s.gone) s.io_error = true;
        break;
      case LIBUSB_TRANSFER_STALL:
        s.halted = true;
        break;
      case LIBUSB_TRANSFER_NO_DEVICE:
        s.gone = true;
        break;
      case LIBUSB_TRANSFER_OVERFLOW:
        s.overflow = true;
        if (s.stats != nullptr) ++s.stats->overflows;
        if (!s.stopping) s.submit(slot);
        break;
      case LIBUSB_TRANSFER_CANCELLED:
        break;
      default:
        s.io_error = true;
        break;
    }
  }

  bool any_in_flight() const {
    for (const auto& slot : slots)
      if (slot->in_flight) return true;
    return false;
  }
};

OpenDevice::OpenDevice(HandlePtr handle, int interface_number) : state_(std::make_unique<State>()) {
  state_->handle = std::move(handle);
  state_->interface_number = interface_number;
}

OpenDevice::~OpenDevice() {
  if (!state_) return;
  if (state_->any_in_flight()) {
    // libusb still owns these transfers; freeing them would be a use-after-free. They can only
    // be in flight here if stop_reading() timed out, so leaking them is the safe choice.
    for (auto& slot : state_->slots)
      if (slot->in_flight) static_cast<void>(slot.release());
  }
  state_->slots.clear();
  if (!state_->gone) libusb_release_interface(state_->handle.get(), state_->interface_number);
}

OpenDevice::OpenDevice() = default;
OpenDevice::OpenDevice(OpenDevice&&) noexcept = default;
OpenDevice& OpenDevice::operator=(OpenDevice&& other) noexcept {
  if (this != &other) {
    OpenDevice old(std::move(*this));  // releases the previous device, if any
    state_ = std::move(other.state_);
  }
  return *this;
}

libusb_device_handle* OpenDevice::handle() const { return state_ ? state_->handle.get() : nullptr; }
bool OpenDevice::is(libusb_device* device) const {
  return state_ && libusb_get_device(state_->handle.get()) == device;
}
bool OpenDevice::gone() const { return state_ && state_->gone; }
void OpenDevice::mark_gone() {
  if (state_) state_->gone = true;
}
bool OpenDevice::halted() const { return state_ && state_->halted; }

int OpenDevice::start_reading(const UsbSettings& settings, UsbStats* stats) {
  state_->stats = stats;
  for (int i = 0; i < settings.transfers_in_flight; ++i) {
    auto slot = std::make_unique<Slot>();
    slot->owner = state_.get();
    slot->buffer.resize(static_cast<std::size_t>(settings.transfer_bytes));
    slot->transfer.reset(libusb_alloc_transfer(0));
    if (!slot->transfer) return LIBUSB_ERROR_NO_MEM;
    // No transfer timeout: the reader applies its own deadline and the transfers stay queued.
    libusb_fill_bulk_transfer(slot->transfer.get(), state_->handle.get(), settings.endpoint_in,
                              slot->buffer.data(), settings.transfer_bytes, &State::on_complete,
                              slot.get(), 0);
    state_->slots.push_back(std::move(slot));
  }
  return resubmit_idle();
}

int OpenDevice::resubmit_idle() {
  state_->halted = false;
  for (auto& slot : state_->slots) {
    if (slot->in_flight) continue;
    if (const int rc = state_->submit(*slot); rc != LIBUSB_SUCCESS) return rc;
  }
  return LIBUSB_SUCCESS;
}

void OpenDevice::stop_reading(libusb_context* context, int timeout_ms) {
  if (!state_) return;
  state_->stopping = true;
  for (auto& slot : state_->slots)
    if (slot->in_flight) libusb_cancel_transfer(slot->transfer.get());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (state_->any_in_flight() && std::chrono::steady_clock::now() < deadline) {
    timeval tv{0, 20000};
    libusb_handle_events_timeout_completed(context, &tv, nullptr);
  }
}

bool OpenDevice::take_received(std::vector<std::uint8_t>& out) {
  if (!state_ || state_->received.empty()) return false;
  out.insert(out.end(), state_->received.begin(), state_->received.end());
  state_->received.clear();
  return true;
}

bool OpenDevice::take_overflow() { return state_ && std::exchange(state_->overflow, false); }
bool OpenDevice::take_io_error() { return state_ && std::exchange(state_->io_error, false); }

OpenDevice open_matching(libusb_context* context, const UsbSettings& settings, int& code,
                         std::string& step) {
  code = 0;
  step = "no device matches";
  libusb_device** raw = nullptr;
  const ssize_t n = libusb_get_device_list(context, &raw);
  if (n < 0) {
    code = static_cast<int>(n);
    step = "libusb_get_device_list";
    return {};
  }
  DeviceListPtr list(raw);
  for (ssize_t i = 0; i < n; ++i) {
    libusb_device_descriptor desc{};
    if (libusb_get_device_descriptor(raw[i], &desc) != LIBUSB_SUCCESS) continue;
    if (desc.idVendor != settings.vendor_id || desc.idProduct != settings.product_id) continue;
    libusb_device_handle* h = nullptr;
    if (const int rc = libusb_open(raw[i], &h); rc != LIBUSB_SUCCESS) {
      code = rc;
      step = "libusb_open";
      continue;
    }
    HandlePtr handle(h);
    if (!settings.serial.empty()) {
      unsigned char text[128] = {};
      const int len = libusb_get_string_descriptor_ascii(h, desc.iSerialNumber, text, sizeof text);
      const std::string seen = len > 0 ? std::string(reinterpret_cast<char*>(text), len) : "";
      if (seen != settings.serial) {
        step = "no device with this serial (saw '" + seen + "')";
        continue;
      }
    }
    if (const int rc = libusb_claim_interface(h, settings.interface_number); rc != LIBUSB_SUCCESS) {
      code = rc;
      step = "libusb_claim_interface " + std::to_string(settings.interface_number);
      continue;
    }
    code = 0;
    return OpenDevice(std::move(handle), settings.interface_number);
  }
  return {};
}

}  // namespace springscan::drivers::usb
