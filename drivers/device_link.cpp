#include "drivers/device_link.hpp"

#include <algorithm>
#include <chrono>

namespace springscan::drivers {
namespace {

namespace p = protocol;
using analysis::ErrorCode;
using analysis::fail;

// DecodeStatus of a frame the decoder threw away: a CRC failure is kBadCrc (§2.2); a header
// with an impossible length or version is a protocol error.
ErrorCode decode_error_code(DecodeStatus status) {
  return status == DecodeStatus::kBadCrc ? ErrorCode::kBadCrc : ErrorCode::kProtocolError;
}

}  // namespace

DeviceLink::DeviceLink(const LinkSettings& settings) : settings_(settings) {
  auto transport = UsbTransport::create(settings.usb);
  if (transport) {
    transport_ = std::move(transport.value());
  } else {
    create_error_ = transport.error();
  }
}

DeviceLink::~DeviceLink() = default;

std::string DeviceLink::who() const {
  std::string s = "scanner";
  if (identity_) {
    s += " " + identity_->serial + " (" + to_string(identity_->kind) + ")";
  } else if (!settings_.usb.serial.empty()) {
    s += " " + settings_.usb.serial;
  }
  return s;
}

bool DeviceLink::online() const { return transport_ && transport_->online(); }

UsbStats DeviceLink::usb_stats() const { return transport_ ? transport_->stats() : UsbStats{}; }

analysis::Expected<Identity> DeviceLink::connect() {
  if (!transport_) return create_error_;
  // libusb delivers hotplug events and transfer completions only while its events are handled,
  // and between scans nobody handles them: without this a scanner that left while the station
  // was idle (or left and came back) still looked online, and the next scan failed on the stale
  // handle with "device gone" although the device was there (found by station_soak --faults).
  transport_->pump(0);
  if (online() && identity_) return *identity_;
  // An unplugged device leaves a stale handle: close it before enumerating again (notes §3).
  transport_->close();
  identity_.reset();
  if (const UsbError e = transport_->open(); e != UsbError::kOk)
    return fail(to_error_code(e), who() + ": " + to_string(e) + " (" + transport_->detail() + ")");
  decoder_.reset();
  sequence_.reset();
  consecutive_timeouts_ = 0;
  auto reply = request(p::MessageType::kIdentify, {}, p::MessageType::kIdentity);
  if (!reply && reply.code() == ErrorCode::kTimeout) {
    // A host that died mid-scan (springscand killed and restarted) leaves the device in that
    // scan: stop it and drain, as after any aborted scan, then ask again (station_soak --faults).
    resync();
    reply = request(p::MessageType::kIdentify, {}, p::MessageType::kIdentity);
  }
  if (!reply) return reply.error();
  auto id = decode_identity(reply->payload);
  if (!id) return id.error().prepend(who() + ": ");
  identity_ = *id;
  return id;
}

std::optional<analysis::Error> DeviceLink::send(p::MessageType command, ByteSpan payload) {
  const auto frame = encode_frame(command, host_sequence_++, payload);
  if (const UsbError e = transport_->write(frame); e != UsbError::kOk)
    return transport_error(e, "sending " + to_string(command));
  return std::nullopt;
}

analysis::Error DeviceLink::transport_error(UsbError error, const std::string& during) {
  last_usb_error_ = error;
  std::string message = who() + ": " + to_string(error) + " while " + during;
  if (error == UsbError::kNoDevice) {
    // Free the transfers and the handle now; connect() reopens when the device is back.
    transport_->close();
    identity_.reset();
  }
  return fail(to_error_code(error), message + " (" + transport_->detail() + ")");
}

analysis::Expected<FrameView> DeviceLink::next_frame(int timeout_ms, bool count_timeout) {
  FrameView frame;
  last_usb_error_ = UsbError::kOk;
  for (;;) {
    const DecodeStatus status = decoder_.next(frame);
    if (status == DecodeStatus::kFrame) {
      const auto seq = sequence_.check(frame.header.sequence);
      if (seq == SequenceChecker::Result::kRepeat) continue;  // a duplicate (§2.5)
      if (seq == SequenceChecker::Result::kGap)
        return fail(ErrorCode::kSequenceGap,
                    who() + ": sequence gap before frame " + std::to_string(frame.header.sequence) +
                        ", " + std::to_string(sequence_.last_gap()) + " frame(s) lost");
      consecutive_timeouts_ = 0;
      return frame;
    }
    if (status != DecodeStatus::kNeedMore)
      return fail(decode_error_code(status),
                  who() + ": corrupt frame on bulk IN (" + to_string(status) + ")");
    rx_.clear();
    const UsbError e = transport_->read(rx_, timeout_ms);
    if (e == UsbError::kOk) {
      decoder_.feed(rx_);
      continue;
    }
    if (e == UsbError::kTimeout && !count_timeout) {
      last_usb_error_ = e;
      return fail(ErrorCode::kTimeout,
                  who() + ": no frame within " + std::to_string(timeout_ms) + " ms");
    }
    if (e == UsbError::kTimeout && ++consecutive_timeouts_ >= settings_.max_consecutive_timeouts) {
      consecutive_timeouts_ = 0;
      transport_->reset();
    }
    return transport_error(e, "waiting " + std::to_string(timeout_ms) + " ms for a frame");
  }
}

analysis::Expected<FrameView> DeviceLink::request(p::MessageType command, ByteSpan payload,
                                                  p::MessageType reply) {
  const std::uint32_t sequence = host_sequence_;
  if (auto error = send(command, payload)) return *error;
  for (;;) {
    auto frame = next_frame(settings_.command_timeout_ms);
    if (!frame) return frame.error();
    if (frame->header.type == reply) return frame;
    if (frame->header.type == p::MessageType::kError) {
      auto e = decode_error(frame->payload);
      if (!e) return e.error().prepend(who() + ": ");
      if (e->command_sequence != sequence) continue;  // an error about an older command
      return fail(ErrorCode::kDeviceFault, who() + ": device error " + std::to_string(e->code) +
                                               " (" +
                                               to_string(static_cast<p::DeviceErrorCode>(e->code)) +
                                               ") to " + to_string(command) + ": " + e->message);
    }
    // Data left over from an aborted scan: skip it until the reply arrives.
  }
}

analysis::Expected<DeviceConfig> DeviceLink::get_config() {
  auto reply = request(p::MessageType::kGetConfig, {}, p::MessageType::kConfig);
  if (!reply) return reply.error();
  return decode_config(reply->payload);
}

analysis::Expected<DeviceConfig> DeviceLink::set_config(const DeviceConfig& config) {
  const Bytes payload = encode(config);
  auto reply = request(p::MessageType::kSetConfig, payload, p::MessageType::kConfig);
  if (!reply) return reply.error();
  return decode_config(reply->payload);
}

analysis::Expected<DeviceStatus> DeviceLink::status() {
  auto reply = request(p::MessageType::kGetStatus, {}, p::MessageType::kStatus);
  if (!reply) return reply.error();
  return decode_status(reply->payload);
}

analysis::Expected<FrameView> DeviceLink::next_scan_frame(const ScanProgress& progress,
                                                          double done) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::milliseconds(settings_.data_timeout_ms);
  const long slice_ms = std::max(1, settings_.cancel_poll_ms);
  for (;;) {
    const long left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) {
      // The whole silence counts once towards a device reset, as an unsliced wait would.
      last_usb_error_ = UsbError::kTimeout;
      if (++consecutive_timeouts_ >= settings_.max_consecutive_timeouts) {
        consecutive_timeouts_ = 0;
        transport_->reset();
      }
      return fail(ErrorCode::kTimeout, who() + ": timeout while waiting " +
                                           std::to_string(settings_.data_timeout_ms) +
                                           " ms for a frame");
    }
    auto frame = next_frame(static_cast<int>(std::min(left, slice_ms)), false);
    if (frame || last_usb_error_ != UsbError::kTimeout) return frame;
    if (progress && !progress(done))
      return fail(ErrorCode::kCancelled, who() + ": scan cancelled while waiting for data");
  }
}

void DeviceLink::resync() {
  // §7: tell the device to stop, then drain whatever is still coming until it is quiet.
  if (!online()) return;
  if (send(p::MessageType::kStopScan, {})) return;
  for (;;) {
    auto frame = next_frame(settings_.resync_quiet_ms);
    if (!frame) {
      if (!online()) return;
      // Quiet (timeout), or a transport failure that draining cannot fix (a stuck halt).
      if (last_usb_error_ != UsbError::kOk) break;
      continue;  // corrupt or out-of-sequence leftovers: keep draining
    }
    // The stop's reply, or its error when the scan had already ended.
    const auto type = frame->header.type;
    if (type == p::MessageType::kScanStopped || type == p::MessageType::kError) break;
  }
  decoder_.reset();
  sequence_.reset();
  consecutive_timeouts_ = 0;
}

// Some 65 lines on purpose: one loop over the frame types of a running scan
// (docs/device-protocol.md), each branch a few lines; it reads as the protocol's table of what may
// arrive during a scan.
analysis::Expected<ScanOutcome> DeviceLink::scan(p::MessageType data_type,
                                                 const FrameHandler& handler,
                                                 const ScanProgress& progress) {
  if (auto id = connect(); !id) return id.error();
  auto reply = request(p::MessageType::kStartScan, {}, p::MessageType::kScanStarted);
  if (!reply) {
    resync();
    return reply.error();
  }
  auto started = decode_scan_started(reply->payload);
  if (!started) return started.error().prepend(who() + ": ");
  ScanOutcome outcome;
  outcome.started = *started;
  last_started_ = *started;
  const auto abort = [&](const analysis::Error& error) -> analysis::Error {
    resync();
    return error;
  };
  for (;;) {
    const double so_far = outcome.started.expected_frames == 0
                              ? 0.0
                              : double(outcome.frames_received) / outcome.started.expected_frames;
    auto frame = next_scan_frame(progress, std::min(so_far, 1.0));
    const std::string at = " at frame " + std::to_string(outcome.frames_received) + " of " +
                           std::to_string(outcome.started.expected_frames);
    if (!frame)
      return abort(fail(frame.code(), frame.message() + at + "; scan aborted, no partial result"));
    const p::MessageType type = frame->header.type;
    if (type == data_type) {
      if (++outcome.frames_received > outcome.started.expected_frames)
        return abort(fail(ErrorCode::kProtocolError,
                          who() + ": more data frames than the " +
                              std::to_string(outcome.started.expected_frames) + " announced"));
      // The handler's code says what was wrong with the frame (kSequenceGap for a profile out
      // of order, kProtocolError for a bad payload).
      if (auto error = handler(*frame)) {
        auto wrapped = error->prepend(who() + ": ");
        wrapped.message += at + "; scan aborted, no partial result";
        return abort(wrapped);
      }
      const double done = outcome.started.expected_frames == 0
                              ? 1.0
                              : double(outcome.frames_received) / outcome.started.expected_frames;
      if (progress && !progress(std::min(done, 1.0)))
        return abort(fail(ErrorCode::kCancelled, who() + ": scan cancelled" + at));
    } else if (type == p::MessageType::kEndOfScan) {
      auto summary = decode_end_of_scan(frame->payload);
      if (!summary) return abort(summary.error().prepend(who() + ": "));
      outcome.summary = *summary;
      if (summary->dropped_frames != 0 || summary->data_frames != outcome.frames_received)
        return fail(ErrorCode::kSequenceGap,
                    who() + ": scan incomplete: device sent " +
                        std::to_string(summary->data_frames) + " frames and dropped " +
                        std::to_string(summary->dropped_frames) + ", host received " +
                        std::to_string(outcome.frames_received));
      return outcome;
    } else if (type == p::MessageType::kError) {
      auto e = decode_error(frame->payload);
      return abort(fail(ErrorCode::kDeviceFault,
                        who() + ": device error " +
                            (e ? std::to_string(e->code) + " (" + e->message + ")" : e.message()) +
                            at));
    } else {
      return abort(fail(ErrorCode::kProtocolError,
                        who() + ": unexpected " + to_string(type) + " frame" + at));
    }
  }
}

}  // namespace springscan::drivers
