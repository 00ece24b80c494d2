// libFuzzer target: the scanner device protocol as the driver meets it on the wire: a byte
// stream, fed in chunks (the first byte of each chunk's length), decoded into frames, and every
// frame's payload decoded by the message decoder for its type. Garbage, bad CRCs, oversized
// lengths and truncated payloads must be rejected with a status or an error.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>

#include "drivers/codec.hpp"
#include "drivers/messages.hpp"

namespace {

void decode_payload(const springscan::drivers::FrameView& frame) {
  using namespace springscan::drivers;
  using protocol::MessageType;
  switch (frame.header.type) {
    case MessageType::kIdentity:
      (void)decode_identity(frame.payload);
      break;
    case MessageType::kConfig:
      (void)decode_config(frame.payload);
      break;
    case MessageType::kScanStarted:
      (void)decode_scan_started(frame.payload);
      break;
    case MessageType::kStatus:
      (void)decode_status(frame.payload);
      break;
    case MessageType::kEndOfScan:
      (void)decode_end_of_scan(frame.payload);
      break;
    case MessageType::kError:
      (void)decode_error(frame.payload);
      break;
    case MessageType::kLaserProfile:
      (void)decode_laser_profile(frame.payload);
      break;
    case MessageType::kProbePoints:
      (void)decode_probe_batch(frame.payload);
      break;
    default:
      break;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace springscan::drivers;
  FrameDecoder decoder;
  std::size_t at = 0;
  while (at < size) {
    const std::size_t chunk = std::min<std::size_t>(size - at, 1 + data[at] % 64);
    decoder.feed(std::span<const std::uint8_t>(data + at, chunk));
    at += chunk;
    FrameView frame;
    for (int frames = 0; frames < 1000; ++frames) {
      const DecodeStatus status = decoder.next(frame);
      if (status == DecodeStatus::kNeedMore) break;
      if (status == DecodeStatus::kFrame) decode_payload(frame);
    }
  }
  return 0;
}
