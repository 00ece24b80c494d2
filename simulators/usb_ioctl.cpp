// The usbfs ioctl handler of the emulated scanner: what the Linux kernel would answer libusb on
// /dev/bus/usb/BBB/DDD (linux/usbdevice_fs.h), with the ScannerDevice behind the endpoints.
#include <linux/usbdevice_fs.h>
#include <sys/ioctl.h>

#include <cerrno>
#include <cstring>

#include "simulators/usb_emulator_internal.hpp"

namespace springscan::simulators {
namespace {

namespace p = drivers::protocol;

usbdevfs_urb& urb_of(const Urb& u) { return *reinterpret_cast<usbdevfs_urb*>(u.urb->data); }

void complete(UMockdevIoctlClient* client, long result, int error) {
  umockdev_ioctl_client_complete(client, result, error);
}

}  // namespace

bool EmulatedUsbScanner::Impl::live_locked(UMockdevIoctlClient* client) {
  const auto it = clients.find(client);
  if (it == clients.end()) {
    clients[client] = generation;  // first ioctl of a newly opened fd
    return plugged;
  }
  return plugged && it->second == generation;
}

std::vector<UMockdevIoctlClient*> EmulatedUsbScanner::Impl::sweep_closed_clients_locked() {
  std::vector<UMockdevIoctlClient*> closed;
  for (UMockdevIoctlClient* client : open_clients) {
    if (!umockdev_ioctl_client_get_connected(client)) closed.push_back(client);
  }
  for (UMockdevIoctlClient* client : closed) {
    open_clients.erase(client);
    clients.erase(client);
    std::erase_if(pending_in, [client](const Urb& u) { return u.client == client; });
    std::erase_if(done, [client](const Urb& u) { return u.client == client; });
  }
  return closed;
}

void EmulatedUsbScanner::Impl::fill_locked() {
  if (!device || !plugged || unplugging) return;
  std::vector<std::uint8_t> bytes;
  while (!pending_in.empty() && !in_halted) {
    Urb& u = pending_in.front();
    usbdevfs_urb& urb = urb_of(u);
    bytes.clear();
    const std::size_t n = device->send(bytes, static_cast<std::size_t>(urb.buffer_length));
    const DeviceEvent event = device->take_event();
    if (event == DeviceEvent::kUnplug) return start_disconnect_locked();
    if (n > 0) {
      std::memcpy(u.buffer->data, bytes.data(), n);
      urb.actual_length = static_cast<int>(n);
      urb.status = 0;
      done.push_back(std::move(u));
      pending_in.pop_front();
    }
    if (event == DeviceEvent::kHaltIn) {
      // The endpoint halts: the next queued URB ends with -EPIPE (LIBUSB_TRANSFER_STALL); the
      // device keeps its data until the host clears the halt.
      in_halted = true;
      if (!pending_in.empty()) {
        urb_of(pending_in.front()).status = -EPIPE;
        urb_of(pending_in.front()).actual_length = 0;
        done.push_back(std::move(pending_in.front()));
        pending_in.pop_front();
      }
      return;
    }
    if (n == 0) return;
  }
}

void EmulatedUsbScanner::Impl::start_disconnect_locked() {
  if (!plugged || unplugging) return;
  unplugging = true;
  hotplug_threads.emplace_back([this] { disconnect(); });
}

void EmulatedUsbScanner::Impl::disconnect() {
  const std::string sys = "/sys" + sysfs_path;
  umockdev_testbed_uevent(testbed, sys.c_str(), "remove");  // needs the device still in sysfs
  {
    std::lock_guard lock(mutex);
    plugged = false;
    unplugging = false;
    ++stats.unplugs;
    // The kernel kills queued URBs of a vanished device with -ESHUTDOWN
    // (LIBUSB_TRANSFER_NO_DEVICE).
    for (Urb& u : pending_in) {
      urb_of(u).status = -ESHUTDOWN;
      urb_of(u).actual_length = 0;
      done.push_back(std::move(u));
    }
    pending_in.clear();
    device.reset();
  }
  umockdev_testbed_remove_device(testbed, sys.c_str());
}

void EmulatedUsbScanner::Impl::handle_ioctl(UMockdevIoctlClient* client) {
  std::vector<UMockdevIoctlClient*> closed;
  {
    std::lock_guard lock(mutex);
    closed = sweep_closed_clients_locked();
    handle_ioctl_locked(client);
  }
  for (UMockdevIoctlClient* c : closed) g_object_unref(c);  // outside the lock: may finalize
}

void EmulatedUsbScanner::Impl::handle_ioctl_locked(UMockdevIoctlClient* client) {
  const gulong request = umockdev_ioctl_client_get_request(client);
  UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
  const bool live = live_locked(client);
  switch (request) {
    case USBDEVFS_SUBMITURB: {
      if (!live) return complete(client, -1, ENODEV);
      Urb u;
      u.client = client;
      std::memcpy(&u.client_address, arg->data, sizeof u.client_address);
      u.urb.reset(umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_urb), nullptr));
      if (!u.urb) return complete(client, -1, EFAULT);
      usbdevfs_urb& urb = urb_of(u);
      u.buffer.reset(umockdev_ioctl_data_resolve(u.urb.get(), offsetof(usbdevfs_urb, buffer),
                                                 static_cast<gsize>(urb.buffer_length), nullptr));
      if (!u.buffer || urb.buffer_length < 0) return complete(client, -1, EFAULT);
      ++stats.urbs_submitted;
      if (urb.type == USBDEVFS_URB_TYPE_CONTROL) {
        const auto reply =
            urb.buffer_length >= 8 ? control_reply(u.buffer->data) : std::vector<std::uint8_t>{};
        const std::size_t room = static_cast<std::size_t>(urb.buffer_length) - 8;
        const std::size_t n = std::min(reply.size(), urb.buffer_length >= 8 ? room : 0);
        if (n > 0) std::memcpy(u.buffer->data + 8, reply.data(), n);
        urb.status = reply.empty() ? -EPIPE : 0;  // unsupported requests stall endpoint 0
        urb.actual_length = static_cast<int>(n);
        done.push_back(std::move(u));
      } else if (urb.type != USBDEVFS_URB_TYPE_BULK ||
                 (urb.endpoint != p::kEndpointIn && urb.endpoint != p::kEndpointOut)) {
        return complete(client, -1, EINVAL);
      } else if (urb.endpoint == p::kEndpointOut) {
        device->receive({u.buffer->data, static_cast<std::size_t>(urb.buffer_length)});
        urb.status = 0;
        urb.actual_length = urb.buffer_length;
        done.push_back(std::move(u));
      } else {
        pending_in.push_back(std::move(u));
      }
      fill_locked();
      return complete(client, 0, 0);
    }
    case USBDEVFS_REAPURB:
    case USBDEVFS_REAPURBNDELAY: {
      fill_locked();  // libusb polls: the device makes progress on every reap
      const auto it = std::find_if(done.begin(), done.end(),
                                   [client](const Urb& u) { return u.client == client; });
      if (it == done.end()) return complete(client, -1, live ? EAGAIN : ENODEV);
      DataPtr slot(umockdev_ioctl_data_resolve(arg, 0, sizeof(void*), nullptr));
      if (!slot) return complete(client, -1, EFAULT);
      // Hands the client its own URB pointer back, with status and data synced on completion.
      umockdev_ioctl_data_set_ptr(slot.get(), 0, it->urb.get());
      done.erase(it);
      return complete(client, 0, 0);
    }
    case USBDEVFS_DISCARDURB: {
      std::uintptr_t address = 0;
      std::memcpy(&address, arg->data, sizeof address);
      const auto it = std::find_if(pending_in.begin(), pending_in.end(), [&](const Urb& u) {
        return u.client == client && u.client_address == address;
      });
      if (it == pending_in.end()) return complete(client, -1, EINVAL);  // already completed
      urb_of(*it).status = -ENOENT;  // killed: libusb reports LIBUSB_TRANSFER_CANCELLED
      urb_of(*it).actual_length = 0;
      done.push_back(std::move(*it));
      pending_in.erase(it);
      ++stats.urbs_discarded;
      return complete(client, 0, 0);
    }
    case USBDEVFS_GET_CAPABILITIES: {
      DataPtr caps(umockdev_ioctl_data_resolve(arg, 0, sizeof(std::uint32_t), nullptr));
      if (!caps) return complete(client, -1, EFAULT);
      const std::uint32_t value = USBDEVFS_CAP_BULK_CONTINUATION | USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
                                  USBDEVFS_CAP_REAP_AFTER_DISCONNECT;
      std::memcpy(caps->data, &value, sizeof value);
      return complete(client, 0, 0);
    }
    case USBDEVFS_CLEAR_HALT:
      if (!live) return complete(client, -1, ENODEV);
      if (in_halted && device && device->halt_sticks()) return complete(client, -1, EPIPE);
      if (in_halted) ++stats.halts_cleared;
      in_halted = false;
      fill_locked();
      return complete(client, 0, 0);
    case USBDEVFS_RESET:
      if (!live) return complete(client, -1, ENODEV);
      ++stats.resets;
      in_halted = false;
      return complete(client, 0, 0);
    case USBDEVFS_GETDRIVER:
      return complete(client, -1, ENODATA);  // no kernel driver bound to the vendor interface
    case USBDEVFS_CLAIMINTERFACE:
    case USBDEVFS_RELEASEINTERFACE:
    case USBDEVFS_SETINTERFACE:
    case USBDEVFS_SETCONFIGURATION:
    case USBDEVFS_DISCONNECT_CLAIM:
      return complete(client, live ? 0 : -1, live ? 0 : ENODEV);
    default:
      return complete(client, -1, ENOTTY);
  }
}

}  // namespace springscan::simulators
