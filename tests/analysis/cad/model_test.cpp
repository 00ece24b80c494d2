#include "analysis/cad/model.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <set>

#include "analysis/io/sha256.hpp"
#include "analysis/messages/cad_model_proto.hpp"
#include "simulators/parts/cad_profile.hpp"
#include "tests/analysis/cad_test_util.hpp"

namespace springscan::analysis {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

using testing::shared_cad;
using testing::TempDir;

// FIPS 180-4 / NIST CSRC example vectors.
TEST(Sha256, KnownVectors) {
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(sha256_hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

// SOURCES.md lists the first and last hex digits of the bracket's SHA-256.
TEST(Sha256, FileMatchesSourcesMd) {
  const auto hash = sha256_file(shared_cad("nema-17-bracket.step"));
  ASSERT_TRUE(hash) << hash.message();
  EXPECT_EQ(hash->substr(0, 8), "bc7b546d");
  EXPECT_EQ(hash->substr(58), "a84c2d");
  EXPECT_FALSE(sha256_file("/nonexistent/file.step"));
}

// The report names the CAD revision measured against: the model carries its file's SHA-256.
TEST(CadModel, ModelCarriesItsCadFilesSha256) {
  CadModelSettings settings;
  settings.sampling.sample_count = 2000;
  const auto model = load_part_model(shared_cad("nema-17-bracket.step"), settings);
  ASSERT_TRUE(model) << model.message();
  ASSERT_EQ(model->source_sha256.size(), 64u);
  EXPECT_EQ(model->source_sha256.substr(0, 8), "bc7b546d");  // SOURCES.md
}

CadModelSettings small_settings() {
  CadModelSettings settings;
  settings.sampling.sample_count = 3000;
  return settings;
}

TEST(CadModel, LoadPartModelPutsItTogether) {
  TempDir dir;
  const ProfileSpec spec = hat_profile(20, 30, 40, 90, 4);
  ASSERT_TRUE(write_profile_cad(spec, dir.file("hat.step")));
  const auto model = load_part_model(dir.file("hat.step"), small_settings());
  ASSERT_TRUE(model) << model.message();
  EXPECT_EQ(model->face_count, 9);
  EXPECT_EQ(model->samples.size(), 3000u);
  EXPECT_EQ(model->segmentation.flanges.size(), 5u);
  EXPECT_EQ(model->segmentation.bends.size(), 4u);
  ASSERT_NE(model->distance, nullptr);
  // Every sample lies on the surface, on its own face (or a face it shares an edge with).
  for (std::size_t i = 0; i < model->samples.size(); i += 10)
    EXPECT_NEAR(model->distance->closest(model->samples.points[i]).signed_distance_mm, 0.0, 1e-7);
  const auto missing = load_part_model(dir.file("missing.igs"));
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.message().find("missing.igs"), std::string::npos);
}

TEST(CadModel, CacheHitMissAndInvalidation) {
  TempDir dir;
  const std::string part = dir.file("part.step"), cache = dir.file("cache");
  ASSERT_TRUE(write_profile_cad(l_profile(40, 30, 90, 3), part));
  const auto settings = small_settings();

  const auto first = load_part_model_cached(part, cache, settings);
  ASSERT_TRUE(first) << first.message();
  EXPECT_FALSE(first->cache_hit);
  EXPECT_TRUE(first->cache_error.empty()) << first->cache_error;
  EXPECT_TRUE(std::filesystem::exists(first->cache_file));

  const auto second = load_part_model_cached(part, cache, settings);
  ASSERT_TRUE(second) << second.message();
  EXPECT_TRUE(second->cache_hit);
  EXPECT_EQ(first->model.source_sha256, first->source_sha256);
  EXPECT_EQ(second->model.source_sha256, first->source_sha256);
  EXPECT_EQ(second->model.samples.points, first->model.samples.points);
  EXPECT_EQ(second->model.samples.face_ids, first->model.samples.face_ids);
  ASSERT_EQ(second->model.segmentation.bends.size(), 1u);
  EXPECT_NEAR(second->model.segmentation.bends[0].nominal_angle_deg, 90.0, 1e-9);
  // The reloaded shape keeps its face ids: the distance finds each sample on its own face.
  ASSERT_NE(second->model.distance, nullptr);
  int same_face = 0;
  for (std::size_t i = 0; i < 300; ++i) {
    const auto hit = second->model.distance->closest(second->model.samples.points[i]);
    EXPECT_NEAR(hit.signed_distance_mm, 0.0, 1e-7);
    same_face += hit.face_id == second->model.samples.face_ids[i];
  }
  EXPECT_GT(same_face, 290);

  // Other settings: a miss, rebuilt and rewritten.
  auto more = settings;
  more.sampling.sample_count = 4000;
  const auto changed_settings = load_part_model_cached(part, cache, more);
  ASSERT_TRUE(changed_settings);
  EXPECT_FALSE(changed_settings->cache_hit);
  EXPECT_EQ(changed_settings->model.samples.size(), 4000u);

  // A changed file: another hash, a miss, and the new geometry (a 60 degree bend).
  ASSERT_TRUE(write_profile_cad(l_profile(40, 30, 60, 3), part));
  const auto changed_file = load_part_model_cached(part, cache, settings);
  ASSERT_TRUE(changed_file);
  EXPECT_FALSE(changed_file->cache_hit);
  EXPECT_NE(changed_file->source_sha256, first->source_sha256);
  ASSERT_EQ(changed_file->model.segmentation.bends.size(), 1u);
  EXPECT_NEAR(changed_file->model.segmentation.bends[0].nominal_angle_deg, 60.0, 1e-9);

  // A corrupt entry is a miss, never an error.
  std::ofstream(changed_file->cache_file, std::ios::trunc) << "garbage";
  const auto after_corruption = load_part_model_cached(part, cache, settings);
  ASSERT_TRUE(after_corruption) << after_corruption.message();
  EXPECT_FALSE(after_corruption->cache_hit);
  EXPECT_TRUE(load_part_model_cached(part, cache, settings)->cache_hit);
}

}  // namespace
}  // namespace springscan::analysis

namespace springscan::analysis {
namespace {

// The cache key hashes every value that shapes a model: any change gives a new key, the same
// values the same key, and the settings survive the trip through their message.
TEST(CadModel, CacheKeyChangesWithEverySetting) {
  const CadModelSettings base;
  const std::string key = cache_settings_key(base);
  EXPECT_EQ(cache_settings_key(CadModelSettings{}), key);
  const std::vector<std::function<void(CadModelSettings&)>> changes = {
      [](CadModelSettings& s) { s.sampling.sample_count += 1; },
      [](CadModelSettings& s) { s.sampling.seed += 1; },
      [](CadModelSettings& s) { s.import.linear_deflection_mm *= 2; },
      [](CadModelSettings& s) { s.import.angular_deflection_deg += 1; },
      [](CadModelSettings& s) { s.import.sewing_tolerance_mm *= 2; },
      [](CadModelSettings& s) { s.import.sew_loose_faces = !s.import.sew_loose_faces; },
      [](CadModelSettings& s) { s.import.heal = !s.import.heal; },
      [](CadModelSettings& s) { s.import.min_plausible_size_mm += 1; },
      [](CadModelSettings& s) { s.segmentation.coplanar_angle_deg *= 2; },
      [](CadModelSettings& s) { s.segmentation.coplanar_distance_mm *= 2; },
      [](CadModelSettings& s) { s.segmentation.coaxial_distance_mm *= 2; },
      [](CadModelSettings& s) { s.segmentation.same_radius_mm *= 2; },
      [](CadModelSettings& s) { s.segmentation.max_sheet_thickness_mm += 1; },
  };
  std::set<std::string> keys = {key};
  for (std::size_t i = 0; i < changes.size(); ++i) {
    CadModelSettings changed = base;
    changes[i](changed);
    EXPECT_TRUE(keys.insert(cache_settings_key(changed)).second) << "change " << i;
    auto back = from_proto(to_proto(changed));
    ASSERT_TRUE(back.ok()) << back.message();
    EXPECT_EQ(cache_settings_key(*back), cache_settings_key(changed)) << "change " << i;
  }
}

}  // namespace
}  // namespace springscan::analysis
