#include "report/png.hpp"

#include <gtest/gtest.h>

#include <random>

#include "tests/report/png_decode.hpp"

namespace springscan::report {
namespace {

RgbImage random_image(int w, int h, std::uint32_t seed) {
  RgbImage image = RgbImage::filled(w, h, {0, 0, 0});
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> byte(0, 255);
  // Half noise, half flat bands, so both filters' paths and long runs are exercised.
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      image.set(x, y,
                x < w / 2 ? Rgb{static_cast<std::uint8_t>(byte(rng)),
                                static_cast<std::uint8_t>(byte(rng)),
                                static_cast<std::uint8_t>(byte(rng))}
                          : Rgb{static_cast<std::uint8_t>(y * 7), 200, 13});
  return image;
}

class PngRoundTrip : public ::testing::TestWithParam<std::pair<int, int>> {};

TEST_P(PngRoundTrip, DecodesToTheSamePixels) {
  const auto [w, h] = GetParam();
  const RgbImage image = random_image(w, h, 11);
  for (int level : {0, 6, 9}) {
    auto png = encode_png(image, {level});
    ASSERT_TRUE(png.ok()) << png.message();
    std::string why;
    auto decoded = testing::decode_png(*png, &why);
    ASSERT_TRUE(decoded) << why;
    EXPECT_EQ(decoded->width, w);
    EXPECT_EQ(decoded->height, h);
    EXPECT_EQ(decoded->channels, 3);
    EXPECT_EQ(decoded->pixels, image.rgb) << "level " << level;
  }
}

INSTANTIATE_TEST_SUITE_P(Sizes, PngRoundTrip,
                         ::testing::Values(std::pair{1, 1}, std::pair{7, 5}, std::pair{64, 33},
                                           std::pair{560, 400}));

TEST(Png, StartsWithSignatureAndIhdr) {
  auto png = encode_png(RgbImage::filled(3, 2, {1, 2, 3}));
  ASSERT_TRUE(png.ok());
  EXPECT_EQ(png->substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(png->substr(12, 4), "IHDR");
  EXPECT_EQ(png->substr(png->size() - 8, 4), "IEND");
}

TEST(Png, CorruptionIsDetectedByTheCrc) {
  auto png = encode_png(random_image(16, 16, 3));
  ASSERT_TRUE(png.ok());
  std::string broken = *png;
  broken[broken.size() / 2] ^= 0x5a;
  EXPECT_FALSE(testing::decode_png(broken));
}

TEST(Png, RejectsEmptyAndInconsistentImages) {
  EXPECT_FALSE(encode_png(RgbImage{}).ok());
  RgbImage bad = RgbImage::filled(4, 4, {0, 0, 0});
  bad.rgb.pop_back();
  auto result = encode_png(bad);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.message().find("47 bytes"), std::string::npos) << result.message();
}

}  // namespace
}  // namespace springscan::report
