#include "drivers/codec.hpp"

#include <algorithm>
#include <array>
#include <cstring>

#include "drivers/wire.hpp"

namespace springscan::drivers {
namespace {

using protocol::kCrcBytes;
using protocol::kHeaderBytes;
using protocol::kMagic;
using protocol::kMaxPayloadBytes;

// Slicing-by-8 tables (Intel, "A Systematic Approach to Building High Performance
// Software-based CRC Generators", 2005): table[k][b] is the CRC of byte b followed by k zeros.
using CrcTables = std::array<std::array<std::uint32_t, 256>, 8>;

constexpr CrcTables make_crc_tables() {
  CrcTables t{};
  for (std::uint32_t b = 0; b < 256; ++b) {
    std::uint32_t c = b;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? (0xEDB88320u ^ (c >> 1)) : (c >> 1);
    t[0][b] = c;
  }
  for (std::uint32_t b = 0; b < 256; ++b) {
    for (std::size_t k = 1; k < 8; ++k) t[k][b] = (t[k - 1][b] >> 8) ^ t[0][t[k - 1][b] & 0xFFu];
  }
  return t;
}

constexpr CrcTables kCrcTables = make_crc_tables();

}  // namespace

std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc) {
  const auto& t = kCrcTables;
  std::uint32_t c = ~crc;
  const std::uint8_t* p = bytes.data();
  std::size_t n = bytes.size();
  while (n >= 8) {
    const std::uint32_t lo = wire::load_u32(p) ^ c;
    const std::uint32_t hi = wire::load_u32(p + 4);
    c = t[7][lo & 0xFF] ^ t[6][(lo >> 8) & 0xFF] ^ t[5][(lo >> 16) & 0xFF] ^ t[4][lo >> 24] ^
        t[3][hi & 0xFF] ^ t[2][(hi >> 8) & 0xFF] ^ t[1][(hi >> 16) & 0xFF] ^ t[0][hi >> 24];
    p += 8;
    n -= 8;
  }
  while (n-- > 0) c = t[0][(c ^ *p++) & 0xFFu] ^ (c >> 8);
  return ~c;
}

void append_frame(std::vector<std::uint8_t>& out, protocol::MessageType type,
                  std::uint32_t sequence, std::span<const std::uint8_t> payload) {
  if (payload.size() > kMaxPayloadBytes) payload = payload.first(kMaxPayloadBytes);
  const std::size_t start = out.size();
  out.resize(start + kHeaderBytes + payload.size() + kCrcBytes);
  std::uint8_t* h = out.data() + start;
  std::memcpy(h, kMagic, sizeof kMagic);
  h[protocol::kOffsetVersion] = protocol::kProtocolVersion;
  h[protocol::kOffsetType] = static_cast<std::uint8_t>(type);
  wire::store_u16(h + protocol::kOffsetFlags, 0);
  wire::store_u32(h + protocol::kOffsetSequence, sequence);
  wire::store_u32(h + protocol::kOffsetLength, static_cast<std::uint32_t>(payload.size()));
  if (!payload.empty()) std::memcpy(h + kHeaderBytes, payload.data(), payload.size());
  // §2.2: the CRC covers header and payload.
  const std::uint32_t crc = crc32({h, kHeaderBytes + payload.size()});
  wire::store_u32(h + kHeaderBytes + payload.size(), crc);
}

std::vector<std::uint8_t> encode_frame(protocol::MessageType type, std::uint32_t sequence,
                                       std::span<const std::uint8_t> payload) {
  std::vector<std::uint8_t> out;
  out.reserve(kHeaderBytes + payload.size() + kCrcBytes);
  append_frame(out, type, sequence, payload);
  return out;
}

std::string to_string(DecodeStatus status) {
  switch (status) {
    case DecodeStatus::kFrame:
      return "frame";
    case DecodeStatus::kNeedMore:
      return "need more bytes";
    case DecodeStatus::kBadCrc:
      return "bad CRC";
    case DecodeStatus::kOversized:
      return "oversized length";
    case DecodeStatus::kBadVersion:
      return "unknown protocol version";
  }
  return "unknown decode status";
}

FrameDecoder::FrameDecoder() { buffer_.reserve(2 * protocol::kMaxFrameBytes); }

void FrameDecoder::feed(std::span<const std::uint8_t> bytes) {
  compact();
  buffer_.insert(buffer_.end(), bytes.begin(), bytes.end());
}

void FrameDecoder::reset() {
  buffer_.clear();
  read_ = 0;
}

void FrameDecoder::compact() {
  if (read_ == 0) return;
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(read_));
  read_ = 0;
}

DecodeStatus FrameDecoder::next(FrameView& frame) {
  // §2.4: find the magic; everything before it is garbage.
  const std::uint8_t* begin = buffer_.data() + read_;
  const std::uint8_t* end = buffer_.data() + buffer_.size();
  const std::uint8_t* found = std::search(begin, end, std::begin(kMagic), std::end(kMagic));
  if (found == end) {
    // Keep a possible partial magic at the tail (up to 3 bytes).
    const std::size_t keep = std::min<std::size_t>(buffer_.size() - read_, sizeof kMagic - 1);
    stats_.skipped_bytes += (buffer_.size() - read_) - keep;
    read_ = buffer_.size() - keep;
    return DecodeStatus::kNeedMore;
  }
  stats_.skipped_bytes += static_cast<std::uint64_t>(found - begin);
  read_ = static_cast<std::size_t>(found - buffer_.data());
  if (buffer_.size() - read_ < kHeaderBytes) return DecodeStatus::kNeedMore;

  const std::uint8_t* h = found;
  const std::uint32_t length = wire::load_u32(h + protocol::kOffsetLength);
  // A rejected header skips only its first byte, so a real frame hidden inside is still found.
  if (h[protocol::kOffsetVersion] != protocol::kProtocolVersion) {
    ++stats_.bad_version;
    ++read_;
    return DecodeStatus::kBadVersion;
  }
  if (length > kMaxPayloadBytes) {
    ++stats_.oversized;
    ++read_;
    return DecodeStatus::kOversized;
  }
  const std::size_t total = kHeaderBytes + length + kCrcBytes;
  if (buffer_.size() - read_ < total) return DecodeStatus::kNeedMore;
  const std::uint32_t expected = wire::load_u32(h + kHeaderBytes + length);
  if (crc32({h, kHeaderBytes + length}) != expected) {
    ++stats_.bad_crc;
    ++read_;
    return DecodeStatus::kBadCrc;
  }
  frame.header.version = h[protocol::kOffsetVersion];
  frame.header.type = static_cast<protocol::MessageType>(h[protocol::kOffsetType]);
  frame.header.flags = wire::load_u16(h + protocol::kOffsetFlags);
  frame.header.sequence = wire::load_u32(h + protocol::kOffsetSequence);
  frame.header.payload_length = length;
  frame.payload = {h + kHeaderBytes, length};
  read_ += total;
  ++stats_.frames;
  return DecodeStatus::kFrame;
}

SequenceChecker::Result SequenceChecker::check(std::uint32_t sequence) {
  last_gap_ = 0;
  if (!started_) {
    started_ = true;
    next_ = sequence + 1;
    return Result::kOk;
  }
  if (sequence == next_) {
    ++next_;
    return Result::kOk;
  }
  // Unsigned distance modulo 2^32: a small step back is a repeat, anything else a gap.
  const std::uint32_t behind = next_ - sequence;
  if (behind <= 0x8000'0000u) return Result::kRepeat;
  last_gap_ = sequence - next_;
  next_ = sequence + 1;
  return Result::kGap;
}

}  // namespace springscan::drivers
