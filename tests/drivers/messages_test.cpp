#include "drivers/messages.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "drivers/wire.hpp"

namespace springscan::drivers {
namespace {

namespace p = protocol;

TEST(Messages, IdentityRoundTripsAndTruncatesLongText) {
  Identity id{p::ScannerKind::kTactileProbe, "TP-20 probe", "SN-0042", "1.2.3"};
  const auto back = decode_identity(encode(id));
  ASSERT_TRUE(back.ok()) << back.message();
  EXPECT_EQ(back->kind, p::ScannerKind::kTactileProbe);
  EXPECT_EQ(back->model, "TP-20 probe");
  EXPECT_EQ(back->serial, "SN-0042");
  EXPECT_EQ(back->firmware, "1.2.3");
  id.firmware = std::string(40, 'f');
  EXPECT_EQ(decode_identity(encode(id))->firmware.size(), p::kFirmwareBytes - 1);
  Bytes bad = encode(id);
  bad[0] = 9;
  EXPECT_FALSE(decode_identity(bad).ok());
  bad.pop_back();
  EXPECT_FALSE(decode_identity(bad).ok());
}

TEST(Messages, ConfigRoundTripsAndRangesAreChecked) {
  DeviceConfig c;
  c.rate_hz = 750.0f;
  c.points_per_profile = 640;
  const auto back = decode_config(encode(c));
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->rate_hz, 750.0f);
  EXPECT_EQ(back->points_per_profile, 640);
  c.points_per_profile = 5000;
  const auto bad = decode_config(encode(c));
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("points_per_profile 5000"), std::string::npos);
  c.points_per_profile = 10;
  c.rate_hz = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(decode_config(encode(c)).ok());
}

TEST(Messages, SummaryStatusStartedAndErrorRoundTrip) {
  const EndOfScan e{120, 3, 98765, 1'500'000};
  const auto eb = decode_end_of_scan(encode(e));
  ASSERT_TRUE(eb.ok());
  EXPECT_EQ(eb->data_frames, 120u);
  EXPECT_EQ(eb->dropped_frames, 3u);
  EXPECT_EQ(eb->points, 98765u);
  const auto sb = decode_status(encode(DeviceStatus{p::DeviceState::kScanning, 0, 5, 10, 7}));
  ASSERT_TRUE(sb.ok());
  EXPECT_EQ(sb->state, p::DeviceState::kScanning);
  EXPECT_EQ(sb->frames_expected, 10u);
  const auto st = decode_scan_started(encode(ScanStarted{10, 1000, 4}));
  ASSERT_TRUE(st.ok());
  EXPECT_EQ(st->expected_points, 1000u);
  EXPECT_FALSE(decode_scan_started(encode(ScanStarted{p::kMaxScanFrames + 1, 1, 1})).ok());
  const auto er = decode_error(encode(DeviceError{3, 17, "busy"}));
  ASSERT_TRUE(er.ok());
  EXPECT_EQ(er->code, 3);
  EXPECT_EQ(er->command_sequence, 17u);
  EXPECT_EQ(er->message, "busy");
  EXPECT_FALSE(decode_error(Bytes(4, 0)).ok());
}

TEST(Messages, LaserProfileRoundTripKeepsNaNAndChecksCount) {
  const std::vector<SensorPoint> pts = {
      {-10.5f, 100.25f}, {0.0f, std::numeric_limits<float>::quiet_NaN()}, {10.5f, 99.0f}};
  const Bytes payload = encode_laser_profile(12, 34.5, 999, pts);
  EXPECT_EQ(payload.size(), p::kProfileHeaderBytes + 3 * p::kProfilePointBytes);
  const auto v = decode_laser_profile(payload);
  ASSERT_TRUE(v.ok()) << v.message();
  EXPECT_EQ(v->index, 12u);
  EXPECT_EQ(v->count, 3);
  EXPECT_EQ(v->encoder_mm, 34.5);
  EXPECT_EQ(v->timestamp_us, 999u);
  EXPECT_EQ(wire::load_f32(v->points.data() + 16), 10.5f);
  EXPECT_TRUE(std::isnan(wire::load_f32(v->points.data() + 12)));
  // A count that disagrees with the payload size is refused, in both directions.
  Bytes lying = payload;
  wire::store_u16(lying.data() + 4, 60000);
  const auto bad = decode_laser_profile(lying);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("60000 points"), std::string::npos);
  lying.resize(10);
  EXPECT_FALSE(decode_laser_profile(lying).ok());
  // An empty profile is legal.
  const auto empty = decode_laser_profile(encode_laser_profile(0, 0.0, 0, {}));
  ASSERT_TRUE(empty.ok());
  EXPECT_EQ(empty->count, 0);
}

TEST(Messages, ProbeBatchRoundTrips) {
  std::vector<ProbeRecord> recs(2);
  recs[0] = {{1.5, -2.25, 30.125}, {0.0f, 0.0f, -1.0f}, 1.5f};
  recs[1] = {{4.0, 5.0, 6.0}, {0.6f, 0.0f, -0.8f}, 0.5f};
  const Bytes payload = encode_probe_batch(40, 123, recs);  // the view points into it
  const auto v = decode_probe_batch(payload);
  ASSERT_TRUE(v.ok()) << v.message();
  EXPECT_EQ(v->first_index, 40u);
  ASSERT_EQ(v->count, 2);
  const ProbeRecord r = probe_record(*v, 1);
  EXPECT_EQ(r.center_mm[2], 6.0);
  EXPECT_EQ(r.direction[0], 0.6f);
  EXPECT_EQ(r.stylus_radius_mm, 0.5f);
  Bytes truncated = encode_probe_batch(40, 123, recs);
  truncated.pop_back();
  EXPECT_FALSE(decode_probe_batch(truncated).ok());
}

}  // namespace
}  // namespace springscan::drivers
