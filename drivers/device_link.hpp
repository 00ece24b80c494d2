#pragma once
// The host side of the scanner protocol over the USB transport (docs/device-protocol.md §3-§5,
// §7): commands and their replies, the scan loop with sequence checking, progress and
// cancellation, resynchronisation after errors, reconnection after an unplug. Shared by the
// laser and the tactile driver, which only convert the data frames.
//
// Thread safety: none; one thread drives a link (the Scanner contract).

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "drivers/codec.hpp"
#include "drivers/messages.hpp"
#include "drivers/scanner.hpp"
#include "drivers/usb_transport.hpp"

namespace springscan::drivers {

struct LinkSettings {
  UsbSettings usb;                   ///< which device and how to talk to it
  int command_timeout_ms = 1000;     ///< wait for a command's reply
  int data_timeout_ms = 2000;        ///< longest silence between two data frames in a scan
  int resync_quiet_ms = 200;         ///< after a failure, drain until the stream is quiet this long
  int max_consecutive_timeouts = 3;  ///< then libusb_reset_device (notes §3)
  /// During a scan the progress callback is asked at least this often, also while no frame
  /// arrives, so a cancel (daemon shutdown) ends a scan stuck on a silent device promptly.
  int cancel_poll_ms = 100;
};

/// What a scan delivered besides the points.
struct ScanOutcome {
  ScanStarted started;
  EndOfScan summary;
  std::uint32_t frames_received = 0;
};

/// Converts one data frame; returns an error to abort the scan.
using FrameHandler = std::function<std::optional<analysis::Error>(const FrameView&)>;

class DeviceLink {
 public:
  explicit DeviceLink(const LinkSettings& settings);
  ~DeviceLink();

  /// Opens the device when it is not open (first use, or again after an unplug) and reads its
  /// identity. Cheap when already online.
  analysis::Expected<Identity> connect();
  bool online() const;
  const std::optional<Identity>& identity() const { return identity_; }
  /// The scan-started reply of the scan in progress (or the last one).
  const ScanStarted& last_started() const { return last_started_; }

  analysis::Expected<DeviceConfig> get_config();
  analysis::Expected<DeviceConfig> set_config(const DeviceConfig& config);
  analysis::Expected<DeviceStatus> status();

  /// Runs one scan whose data frames have type `data_type`, passing each to `handler`.
  /// Progress is frames received over frames announced. On any failure the device is told to
  /// stop, the stream is drained, and the error names the device and the frame.
  analysis::Expected<ScanOutcome> scan(protocol::MessageType data_type, const FrameHandler& handler,
                                       const ScanProgress& progress);

  /// Transport counters (stalls cleared, opens, ...).
  UsbStats usb_stats() const;
  const DecoderStats& decoder_stats() const { return decoder_.stats(); }

 private:
  /// `count_timeout`: a timeout counts towards max_consecutive_timeouts (false for the slices
  /// of a longer wait).
  analysis::Expected<FrameView> next_frame(int timeout_ms, bool count_timeout = true);
  /// The next frame of a running scan: waits up to data_timeout_ms in cancel_poll_ms slices,
  /// asking `progress(done)` between them.
  analysis::Expected<FrameView> next_scan_frame(const ScanProgress& progress, double done);
  analysis::Expected<FrameView> request(protocol::MessageType command, ByteSpan payload,
                                        protocol::MessageType reply);
  std::optional<analysis::Error> send(protocol::MessageType command, ByteSpan payload);
  analysis::Error transport_error(UsbError error, const std::string& during);
  void resync();
  std::string who() const;

  LinkSettings settings_;
  std::unique_ptr<UsbTransport> transport_;
  analysis::Error create_error_;  // why the transport could not be created
  FrameDecoder decoder_;
  SequenceChecker sequence_;
  std::vector<std::uint8_t> rx_;
  std::uint32_t host_sequence_ = 0;
  int consecutive_timeouts_ = 0;
  UsbError last_usb_error_ = UsbError::kOk;  // of the last next_frame()
  std::optional<Identity> identity_;
  ScanStarted last_started_;
};

}  // namespace springscan::drivers
