#pragma once
// Internals of the USB emulation shared by usb_emulator.cpp (testbed, plug/unplug) and
// usb_ioctl.cpp (the usbfs ioctl handler). Not part of the simulators' interface.

#include <umockdev.h>

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "simulators/usb_emulator.hpp"

namespace springscan::simulators {

/// A GObject reference that is released with its owner.
struct GObjectUnref {
  void operator()(void* object) const {
    if (object != nullptr) g_object_unref(object);
  }
};
using DataPtr = std::unique_ptr<UMockdevIoctlData, GObjectUnref>;

/// One URB the client submitted: its struct and data buffer, resolved into our memory.
struct Urb {
  UMockdevIoctlClient* client = nullptr;
  std::uintptr_t client_address = 0;  // the client's pointer, to match DISCARDURB
  DataPtr urb;                        // struct usbdevfs_urb
  DataPtr buffer;                     // its data
};

struct EmulatedUsbScanner::Impl {
  // Set at creation, immutable afterwards.
  UMockdevTestbed* testbed = nullptr;
  UMockdevIoctlBase* handler = nullptr;
  std::string sysfs_path;   // /devices/...
  std::string dev_node;     // /dev/bus/usb/BBB/DDD
  std::string description;  // umockdev text record of the device
  ScannerDeviceSettings device_settings;
  analysis::PointCloud surface;
  std::uint16_t product_id = 0;

  mutable std::mutex mutex;  // guards everything below
  std::unique_ptr<ScannerDevice> device;
  bool plugged = false;
  bool unplugging = false;  // the cable is out, the "remove" uevent not yet sent: device silent
  bool in_halted = false;
  int generation = 0;                           // increments per plug
  std::map<UMockdevIoctlClient*, int> clients;  // the generation each client opened
  std::set<UMockdevIoctlClient*> open_clients;  // connected, each holding a reference
  std::deque<Urb> pending_in;                   // bulk IN URBs waiting for data
  std::deque<Urb> done;                         // completed, waiting to be reaped
  EmulatorStats stats;
  std::vector<std::thread> hotplug_threads;  // uevents go out off the worker thread

  /// Completes queued IN URBs from the device's output; runs the device's fault events.
  void fill_locked();
  /// A fault pulls the cable during a transfer (on umockdev's worker thread): the device goes
  /// silent at once and disconnect() runs on a hotplug thread.
  void start_disconnect_locked();
  /// Sends the "remove" uevent, then fails the queued URBs with -ESHUTDOWN and marks the device
  /// unplugged, then removes it from the testbed. In that order: umockdev 0.17 (Debian 12)
  /// abort()s the emulating process when a client closes its udev monitor between the uevent
  /// sender's connect() and sendmsg(), and a client that sees its URBs fail may exit (closing
  /// its monitor) at once; this way every client is still waiting on the device while the
  /// uevent goes out. Called with `unplugging` set and the mutex not held.
  void disconnect();
  /// True when `client` opened the device node of the device that is plugged in now.
  bool live_locked(UMockdevIoctlClient* client);
  /// Answers one usbfs ioctl (usb_ioctl.cpp), after forgetting the closed clients.
  void handle_ioctl(UMockdevIoctlClient* client);
  void handle_ioctl_locked(UMockdevIoctlClient* client);
  /// umockdev 0.17 declares "client-vanished" but never emits it (and its "connected"
  /// property is never notified): a client whose process closed the device node or died
  /// (kill -9) only shows as a closed stream. Such clients are dropped here, with their queued
  /// URBs, which would otherwise sit at the head of the queue and swallow the data meant for
  /// the next process that opens the device. Returns them for the caller to unref unlocked.
  std::vector<UMockdevIoctlClient*> sweep_closed_clients_locked();
  /// Standard GET_DESCRIPTOR answers on endpoint 0 (strings carry the identity).
  std::vector<std::uint8_t> control_reply(const std::uint8_t setup[8]) const;
  std::vector<std::uint8_t> descriptors() const;
};

}  // namespace springscan::simulators
