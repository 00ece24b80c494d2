#pragma once
// The frame codec of the scanner protocol (docs/device-protocol.md §2): pure functions and a
// stream decoder over byte arrays, no I/O. Shared by the host drivers and the simulator.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "drivers/protocol.hpp"

namespace springscan::drivers {

/// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320, init and final xor 0xFFFFFFFF), the
/// frame check of §2.2. `crc` continues a previous call (start with 0). Slicing-by-8.
std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc = 0);

struct FrameHeader {
  std::uint8_t version = protocol::kProtocolVersion;
  protocol::MessageType type = protocol::MessageType::kIdentify;
  std::uint16_t flags = 0;
  std::uint32_t sequence = 0;
  std::uint32_t payload_length = 0;
};

/// A decoded frame. `payload` points into the decoder's buffer and stays valid until the next
/// call to FrameDecoder::feed() or next().
struct FrameView {
  FrameHeader header;
  std::span<const std::uint8_t> payload;
};

/// Appends one complete frame (header, payload, CRC) to `out`. The payload must not exceed
/// protocol::kMaxPayloadBytes (checked by the caller; larger payloads are truncated to it).
void append_frame(std::vector<std::uint8_t>& out, protocol::MessageType type,
                  std::uint32_t sequence, std::span<const std::uint8_t> payload);

/// One frame as a new byte vector.
std::vector<std::uint8_t> encode_frame(protocol::MessageType type, std::uint32_t sequence,
                                       std::span<const std::uint8_t> payload);

enum class DecodeStatus {
  kFrame,       ///< a valid frame is in the output
  kNeedMore,    ///< no complete frame buffered
  kBadCrc,      ///< a frame failed its CRC; it was skipped and the decoder resynchronised
  kOversized,   ///< a header announced more than kMaxPayloadBytes; skipped, resynchronised
  kBadVersion,  ///< a header with an unknown protocol version; skipped, resynchronised
};

std::string to_string(DecodeStatus status);

/// Counters of what the decoder had to throw away.
struct DecoderStats {
  std::uint64_t frames = 0;         ///< valid frames returned
  std::uint64_t skipped_bytes = 0;  ///< bytes discarded while searching for a frame start
  std::uint64_t bad_crc = 0;        ///< frames rejected by their CRC
  std::uint64_t oversized = 0;      ///< headers rejected by their length
  std::uint64_t bad_version = 0;    ///< headers rejected by their version
};

/// A stream decoder: feed it bytes as they arrive (in any chunking), then call next() until it
/// says kNeedMore. After garbage or a rejected frame it searches for the next magic (§2.4).
/// Memory is bounded: the buffer never holds more than one maximal frame plus the bytes of one
/// feed() call, and a length field is never used to size an allocation.
/// Not thread-safe; one decoder per stream.
class FrameDecoder {
 public:
  FrameDecoder();
  /// Appends received bytes.
  void feed(std::span<const std::uint8_t> bytes);
  /// Extracts the next frame or reports why none could be extracted.
  DecodeStatus next(FrameView& frame);
  /// Drops everything buffered (after a reconnect or a resync command).
  void reset();
  std::size_t buffered_bytes() const { return buffer_.size() - read_; }
  const DecoderStats& stats() const { return stats_; }

 private:
  void compact();
  std::vector<std::uint8_t> buffer_;
  std::size_t read_ = 0;
  DecoderStats stats_;
};

/// Checks that frame sequence numbers follow each other (§2.5): each is the previous plus one,
/// modulo 2^32. The first frame after reset() sets the start.
class SequenceChecker {
 public:
  enum class Result { kOk, kGap, kRepeat };
  Result check(std::uint32_t sequence);
  void reset() { started_ = false; }
  /// Frames missing at the last kGap (0 otherwise).
  std::uint32_t last_gap() const { return last_gap_; }
  std::uint32_t expected() const { return next_; }

 private:
  bool started_ = false;
  std::uint32_t next_ = 0;
  std::uint32_t last_gap_ = 0;
};

}  // namespace springscan::drivers
