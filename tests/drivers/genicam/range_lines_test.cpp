// GenICam range lines to part coordinates (drivers/genicam/range_lines.hpp), on byte arrays the
// tests build from known points: scale and offset, invalid pixels, the motion axis, lost frames.
#include "drivers/genicam/range_lines.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

namespace springscan::drivers::genicam {
namespace {

void put_u16(std::vector<std::uint8_t>& b, std::uint16_t v) {
  b.push_back(static_cast<std::uint8_t>(v & 0xFF));
  b.push_back(static_cast<std::uint8_t>(v >> 8));
}
void put_f32(std::vector<std::uint8_t>& b, float v) {
  std::uint8_t raw[4];
  std::memcpy(raw, &v, 4);
  b.insert(b.end(), raw, raw + 4);
}

RangeFrameView view(RangeFormat f, const std::vector<std::uint8_t>& b, std::uint32_t w,
                    std::uint32_t h, std::int64_t first_line = 0) {
  return RangeFrameView{f, b.data(), b.size(), w, h, first_line};
}

// A tilted head: the conversion must use the calibration's axes, not assume the part frame.
LaserCalibration tilted() {
  LaserCalibration c;
  c.origin_mm = {10.0, -5.0, 300.0};
  c.x_axis = analysis::Vec3(1.0, 0.0, 1.0).normalized();
  c.z_axis = analysis::Vec3(1.0, 0.0, -1.0).normalized();
  c.motion_axis = {0.0, 1.0, 0.0};
  return c;
}

TEST(RangeLines, C16AppliesScaleOffsetAndUnitPerCoordinate) {
  RangeScaling s;
  s.a = {0.05, -20.0};
  s.c = {0.002, 100.0};
  s.unit_mm = 25.4;  // Scan3dDistanceUnit Inch
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> raw(1, 65535);
  const std::uint32_t w = 37, h = 3;
  std::vector<std::uint8_t> bytes;
  std::vector<std::uint16_t> values;
  for (std::uint32_t k = 0; k < w * h; ++k) {
    values.push_back(static_cast<std::uint16_t>(raw(rng)));
    put_u16(bytes, values.back());
  }
  const LaserCalibration c = tilted();
  std::vector<analysis::Vec3> out;
  ASSERT_EQ(validate(view(RangeFormat::kCoord3dC16, bytes, w, h, 10)), "");
  EXPECT_EQ(append_range_lines(view(RangeFormat::kCoord3dC16, bytes, w, h, 10), s, c, 0.25, out),
            w * h);
  for (std::uint32_t row = 0; row < h; ++row) {
    for (std::uint32_t i = 0; i < w; ++i) {
      const double x = (i * 0.05 - 20.0) * 25.4;
      const double z = (values[row * w + i] * 0.002 + 100.0) * 25.4;
      const double m = (10.0 + row) * 0.25;
      const analysis::Vec3 truth = c.origin_mm + x * c.x_axis + z * c.z_axis + m * c.motion_axis;
      ASSERT_LT((out[row * w + i] - truth).norm(), 1e-9) << "row " << row << " pixel " << i;
    }
  }
}

TEST(RangeLines, InvalidPixelsAreDroppedOnlyWhenTheFlagIsSet) {
  std::vector<std::uint8_t> bytes;
  for (std::uint16_t v : {0, 500, 0, 700, 0}) put_u16(bytes, v);
  RangeScaling s;
  s.c.invalid_value = 0.0;
  std::vector<analysis::Vec3> out;
  s.c.invalid_flag = false;
  EXPECT_EQ(append_range_lines(view(RangeFormat::kMono16, bytes, 5, 1), s, {}, 1.0, out), 5u);
  out.clear();
  s.c.invalid_flag = true;
  ASSERT_EQ(append_range_lines(view(RangeFormat::kMono16, bytes, 5, 1), s, {}, 1.0, out), 2u);
  // The survivors are pixels 1 and 3 with their own x and range (default head: z = 200 - range).
  EXPECT_DOUBLE_EQ(out[0].x(), 1.0);
  EXPECT_DOUBLE_EQ(out[0].z(), 200.0 - 500.0);
  EXPECT_DOUBLE_EQ(out[1].x(), 3.0);
  EXPECT_DOUBLE_EQ(out[1].z(), 200.0 - 700.0);
}

TEST(RangeLines, Abc32fDropsNanAndInvalidAndAddsBAlongTheMotion) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<std::uint8_t> bytes;
  const float abc[4][3] = {
      {1.5f, 0.0f, 40.0f}, {2.5f, 0.5f, nan}, {3.5f, 0.0f, -1.0f}, {4.5f, 0.25f, 42.0f}};
  for (const auto& p : abc)
    for (float v : p) put_f32(bytes, v);
  RangeScaling s;
  s.c.invalid_flag = true;
  s.c.invalid_value = -1.0;
  LaserCalibration c;  // default head: x along x, range down from z = 200, motion along y
  std::vector<analysis::Vec3> out;
  ASSERT_EQ(validate(view(RangeFormat::kCoord3dAbc32f, bytes, 2, 2)), "");
  ASSERT_EQ(append_range_lines(view(RangeFormat::kCoord3dAbc32f, bytes, 2, 2, 4), s, c, 2.0, out),
            2u);
  EXPECT_LT((out[0] - analysis::Vec3(1.5, 4 * 2.0, 160.0)).norm(), 1e-9);
  EXPECT_LT((out[1] - analysis::Vec3(4.5, 5 * 2.0 + 0.25, 158.0)).norm(), 1e-9);
}

TEST(RangeLines, MotionAxisPlacesLinesByIndex) {
  std::vector<std::uint8_t> bytes;
  for (int k = 0; k < 4; ++k) put_u16(bytes, 100);
  LaserCalibration c;
  c.motion_axis = {0.0, 0.0, 0.0};
  c.motion_axis = analysis::Vec3(0.6, 0.8, 0.0);
  std::vector<analysis::Vec3> out;
  append_range_lines(view(RangeFormat::kCoord3dC16, bytes, 1, 4, 100), {}, c, 0.5, out);
  ASSERT_EQ(out.size(), 4u);
  for (int row = 0; row < 4; ++row) {
    const double m = (100 + row) * 0.5;
    EXPECT_NEAR(out[row].x(), 0.6 * m, 1e-12);
    EXPECT_NEAR(out[row].y(), 0.8 * m, 1e-12);
  }
}

TEST(RangeLines, EmptyAndShortFrames) {
  std::vector<std::uint8_t> bytes(10, 0);
  std::vector<analysis::Vec3> out;
  EXPECT_EQ(validate(view(RangeFormat::kCoord3dC16, bytes, 0, 0)), "");
  EXPECT_EQ(append_range_lines(view(RangeFormat::kCoord3dC16, bytes, 0, 0), {}, {}, 1.0, out), 0u);
  EXPECT_NE(validate(view(RangeFormat::kCoord3dC16, bytes, 6, 1)), "");  // 12 bytes needed
  EXPECT_NE(validate(view(RangeFormat::kCoord3dAbc32f, bytes, 1, 1)), "");
  EXPECT_NE(validate(view(static_cast<RangeFormat>(0x01080001), bytes, 1, 1)), "");  // Mono8
}

TEST(RangeLines, BlockIdSteps) {
  EXPECT_EQ(block_id_step(5, 6), 1);
  EXPECT_EQ(block_id_step(5, 9), 4);       // three lost between
  EXPECT_EQ(block_id_step(65535, 1), 1);   // GigE Vision wraps past 0
  EXPECT_EQ(block_id_step(65534, 2), 3);   // 65535 and 1 lost
  EXPECT_EQ(block_id_step(1, 65535), -1);  // late, across the wrap
  EXPECT_EQ(block_id_step(102, 101), -1);  // late
  EXPECT_EQ(block_id_step(7, 7), 0);
  EXPECT_EQ(block_id_step(70000, 70003), 3);  // USB3 Vision's 64-bit ids
}

}  // namespace
}  // namespace springscan::drivers::genicam
