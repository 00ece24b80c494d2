#include "drivers/codec.hpp"

#include <gtest/gtest.h>

#include <random>
#include <string>

#include "drivers/wire.hpp"

namespace springscan::drivers {
namespace {

namespace p = protocol;
using Bytes = std::vector<std::uint8_t>;

Bytes payload_of(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  Bytes b(n);
  for (auto& x : b) x = static_cast<std::uint8_t>(rng());
  return b;
}

// Decodes everything buffered; returns the frames' sequence numbers and counts rejections.
struct Drained {
  std::vector<std::uint32_t> sequences;
  std::vector<Bytes> payloads;
  int rejected = 0;
};
Drained drain(FrameDecoder& decoder) {
  Drained d;
  FrameView f;
  for (;;) {
    const DecodeStatus s = decoder.next(f);
    if (s == DecodeStatus::kNeedMore) return d;
    if (s == DecodeStatus::kFrame) {
      d.sequences.push_back(f.header.sequence);
      d.payloads.emplace_back(f.payload.begin(), f.payload.end());
    } else {
      ++d.rejected;
    }
  }
}

TEST(Crc32, MatchesTheStandardCheckValue) {
  // The CRC-32/ISO-HDLC check value: crc("123456789") = 0xCBF43926.
  const std::string s = "123456789";
  const Bytes b(s.begin(), s.end());
  EXPECT_EQ(crc32(b), 0xCBF43926u);
  // Incremental use gives the same answer, also across the 8-byte block boundary.
  EXPECT_EQ(crc32(std::span(b).subspan(3), crc32(std::span(b).first(3))), 0xCBF43926u);
  EXPECT_EQ(crc32({}), 0u);
}

TEST(Crc32, SlicingAgreesWithBitwiseOracle) {
  const Bytes b = payload_of(1000, 7);
  for (std::size_t n : {0u, 1u, 7u, 8u, 9u, 63u, 1000u}) {
    std::uint32_t c = 0xFFFFFFFFu;
    for (std::size_t i = 0; i < n; ++i) {
      c ^= b[i];
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? (0xEDB88320u ^ (c >> 1)) : (c >> 1);
    }
    EXPECT_EQ(crc32(std::span(b).first(n)), ~c) << n;
  }
}

TEST(FrameCodec, RoundTripsInAnyChunking) {
  Bytes stream;
  std::vector<Bytes> payloads;
  for (std::uint32_t i = 0; i < 20; ++i) {
    payloads.push_back(payload_of(i * 37, i));
    append_frame(stream, p::MessageType::kLaserProfile, 100 + i, payloads.back());
  }
  for (std::size_t chunk : {1u, 3u, 16u, 512u, 100000u}) {
    FrameDecoder decoder;
    Drained all;
    for (std::size_t at = 0; at < stream.size(); at += chunk) {
      const std::size_t n = std::min(chunk, stream.size() - at);
      decoder.feed(std::span(stream).subspan(at, n));
      Drained d = drain(decoder);
      all.sequences.insert(all.sequences.end(), d.sequences.begin(), d.sequences.end());
      all.payloads.insert(all.payloads.end(), d.payloads.begin(), d.payloads.end());
      all.rejected += d.rejected;
    }
    ASSERT_EQ(all.payloads.size(), payloads.size()) << "chunk " << chunk;
    EXPECT_EQ(all.payloads, payloads);
    EXPECT_EQ(all.sequences.front(), 100u);
    EXPECT_EQ(all.rejected, 0);
    EXPECT_EQ(decoder.buffered_bytes(), 0u);
  }
}

TEST(FrameCodec, EmptyInputAndTruncatedFrameNeedMore) {
  FrameDecoder decoder;
  FrameView f;
  EXPECT_EQ(decoder.next(f), DecodeStatus::kNeedMore);
  const Bytes frame = encode_frame(p::MessageType::kStatus, 5, payload_of(16, 1));
  for (std::size_t cut = 0; cut < frame.size(); ++cut) {
    FrameDecoder d;
    d.feed(std::span(frame).first(cut));
    EXPECT_EQ(d.next(f), DecodeStatus::kNeedMore) << cut;
    d.feed(std::span(frame).subspan(cut));
    ASSERT_EQ(d.next(f), DecodeStatus::kFrame) << cut;
    EXPECT_EQ(f.header.sequence, 5u);
    EXPECT_EQ(f.header.type, p::MessageType::kStatus);
  }
}

TEST(FrameCodec, ResynchronisesAfterRandomGarbage) {
  std::mt19937 rng(42);
  Bytes stream;
  std::uint32_t frames = 0;
  for (int i = 0; i < 50; ++i) {
    const Bytes junk = payload_of(rng() % 300, static_cast<std::uint32_t>(i + 1000));
    stream.insert(stream.end(), junk.begin(), junk.end());
    append_frame(stream, p::MessageType::kProbePoints, frames++, payload_of(rng() % 200, i));
  }
  FrameDecoder decoder;
  decoder.feed(stream);
  const Drained d = drain(decoder);
  // Every real frame is found; random junk passing a CRC-32 has odds ~2^-32 per candidate.
  ASSERT_EQ(d.sequences.size(), frames);
  for (std::uint32_t i = 0; i < frames; ++i) EXPECT_EQ(d.sequences[i], i);
  EXPECT_GT(decoder.stats().skipped_bytes, 0u);
}

TEST(FrameCodec, PureRandomBytesYieldNoFrames) {
  FrameDecoder decoder;
  for (std::uint32_t seed = 0; seed < 20; ++seed) {
    decoder.feed(payload_of(5000, seed));
    EXPECT_TRUE(drain(decoder).sequences.empty());
  }
  EXPECT_LT(decoder.buffered_bytes(), 4u);
}

TEST(FrameCodec, RejectsBadCrcAndKeepsTheNextFrame) {
  Bytes stream = encode_frame(p::MessageType::kLaserProfile, 1, payload_of(64, 1));
  stream[p::kHeaderBytes + 10] ^= 0x40;  // one flipped payload bit
  append_frame(stream, p::MessageType::kLaserProfile, 2, payload_of(64, 2));
  FrameDecoder decoder;
  decoder.feed(stream);
  FrameView f;
  EXPECT_EQ(decoder.next(f), DecodeStatus::kBadCrc);
  ASSERT_EQ(decoder.next(f), DecodeStatus::kFrame);
  EXPECT_EQ(f.header.sequence, 2u);
  EXPECT_EQ(decoder.stats().bad_crc, 1u);
  // A flipped bit in the sequence, the length or the CRC itself is caught as well. A length
  // that grew makes the decoder wait for more bytes; the CRC then fails and the frame that
  // follows is still found.
  for (std::size_t at : {std::size_t{9}, std::size_t{13}, p::kHeaderBytes + 64 + 2}) {
    Bytes one = encode_frame(p::MessageType::kLaserProfile, 1, payload_of(64, 1));
    one[at] ^= 0x01;
    append_frame(one, p::MessageType::kLaserProfile, 2, payload_of(400, 2));
    FrameDecoder d;
    d.feed(one);
    const Drained r = drain(d);
    EXPECT_EQ(r.sequences, std::vector<std::uint32_t>{2}) << at;
    EXPECT_GE(r.rejected, 1) << at;
  }
}

TEST(FrameCodec, RejectsOversizedLengthWithoutWaitingForIt) {
  Bytes stream = encode_frame(p::MessageType::kLaserProfile, 1, payload_of(8, 1));
  wire::store_u32(stream.data() + p::kOffsetLength, 0xFFFFFFF0u);
  append_frame(stream, p::MessageType::kEndOfScan, 2, payload_of(24, 2));
  FrameDecoder decoder;
  decoder.feed(stream);
  FrameView f;
  // The bad length is rejected at once, not treated as "need 4 GB more".
  EXPECT_EQ(decoder.next(f), DecodeStatus::kOversized);
  ASSERT_EQ(decoder.next(f), DecodeStatus::kFrame);
  EXPECT_EQ(f.header.type, p::MessageType::kEndOfScan);
  // The largest legal frame passes; one more byte of length does not.
  const Bytes max =
      encode_frame(p::MessageType::kLaserProfile, 3, payload_of(p::kMaxPayloadBytes, 3));
  EXPECT_EQ(max.size(), p::kMaxFrameBytes);
  FrameDecoder d2;
  d2.feed(max);
  EXPECT_EQ(d2.next(f), DecodeStatus::kFrame);
  Bytes over = max;
  wire::store_u32(over.data() + p::kOffsetLength, p::kMaxPayloadBytes + 1);
  FrameDecoder d3;
  d3.feed(over);
  EXPECT_EQ(d3.next(f), DecodeStatus::kOversized);
}

TEST(FrameCodec, RejectsUnknownVersion) {
  Bytes stream = encode_frame(p::MessageType::kStatus, 1, payload_of(16, 1));
  stream[p::kOffsetVersion] = 2;
  FrameDecoder decoder;
  decoder.feed(stream);
  FrameView f;
  EXPECT_EQ(decoder.next(f), DecodeStatus::kBadVersion);
  EXPECT_EQ(decoder.next(f), DecodeStatus::kNeedMore);
}

TEST(SequenceChecker, DetectsGapsRepeatsAndWraps) {
  SequenceChecker c;
  EXPECT_EQ(c.check(0xFFFFFFFEu), SequenceChecker::Result::kOk);  // the first sets the start
  EXPECT_EQ(c.check(0xFFFFFFFFu), SequenceChecker::Result::kOk);
  EXPECT_EQ(c.check(0u), SequenceChecker::Result::kOk);  // wraps modulo 2^32
  EXPECT_EQ(c.check(3u), SequenceChecker::Result::kGap);
  EXPECT_EQ(c.last_gap(), 2u);
  EXPECT_EQ(c.check(4u), SequenceChecker::Result::kOk);
  EXPECT_EQ(c.check(4u), SequenceChecker::Result::kRepeat);
  EXPECT_EQ(c.check(2u), SequenceChecker::Result::kRepeat);
  EXPECT_EQ(c.expected(), 5u);
  c.reset();
  EXPECT_EQ(c.check(77u), SequenceChecker::Result::kOk);
}

}  // namespace
}  // namespace springscan::drivers
