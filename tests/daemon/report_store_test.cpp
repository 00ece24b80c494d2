#include "daemon/report_store.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "analysis/io/point_io.hpp"
#include "report/inspection_files.hpp"
#include "test_rig.hpp"

namespace springscan::daemon {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

v1::InspectionReport report_with_seq(std::uint32_t seq) {
  v1::InspectionReport r;
  r.set_result_seq(seq);
  r.mutable_verdict()->set_pass(true);
  return r;
}

TEST(ReportStore, PersistsAllFilesAndReloadsTheNewest) {
  TempDir dir("springscan-store");
  auto store = ReportStore::open({dir.str(), 10});
  ASSERT_TRUE(store.ok()) << store.message();
  EXPECT_EQ(store->last_record(), 0u);
  EXPECT_FALSE(store->load_latest()->has_value());
  analysis::PointCloud cloud;
  cloud.points = {{1, 2, 3}, {4, 5, 6}};
  cloud.scalars = {0.1, -0.2};
  analysis::InspectionOutcome outcome = report_only(report_with_seq(1));
  outcome.deviation_cloud = cloud;
  analysis::CompensationVector c;
  c.point = analysis::Vec3(1.0, 2.0, 3.0);
  c.vector = analysis::Vec3(0.0, 0.0, -0.25);
  c.supported = true;
  outcome.compensation.vectors.push_back(c);
  auto path = store->persist(1, outcome);
  ASSERT_TRUE(path.ok()) << path.message();
  ASSERT_TRUE(store->persist(2, report_only(report_with_seq(2))).ok());
  EXPECT_TRUE(fs::exists(*path + "/report.pb"));
  EXPECT_TRUE(fs::exists(*path + "/report.json"));
  EXPECT_TRUE(fs::exists(*path + "/report.html"));  // report::write_inspection_files writes all
  // The tool designer's files, as `springscan analyze` writes them (docs/report-format.md).
  EXPECT_TRUE(fs::exists(*path + "/compensation.csv"));
  EXPECT_TRUE(fs::exists(*path + "/compensation.ply"));
  const std::string failed_scan = store->record_path(2);
  for (const char* name : {"report.pb", "report.json", "report.html", "deviation.ply"})
    EXPECT_TRUE(fs::exists(failed_scan + "/" + name)) << name;
  EXPECT_EQ(analysis::read_point_cloud(failed_scan + "/deviation.ply")->size(), 0u);
  // The same deviation.ply as `springscan analyze` writes (docs/report-format.md): the points,
  // the signed deviation as `signed_deviation_mm`, colours from analysis::deviation_color.
  analysis::PointReadOptions by_name;
  by_name.scalar_property = "signed_deviation_mm";
  const auto ply = analysis::read_point_cloud(*path + "/deviation.ply", by_name);
  ASSERT_TRUE(ply.ok()) << ply.message();
  EXPECT_EQ(ply->points, cloud.points);
  EXPECT_EQ(ply->scalars, cloud.scalars);
  ASSERT_EQ(ply->colors.size(), 2u);
  const double scale = report::deviation_color_scale_mm(report_with_seq(1));
  EXPECT_EQ(ply->colors[1], analysis::deviation_color(-0.2, scale));
  std::ifstream json(*path + "/report.json");
  const std::string text((std::istreambuf_iterator<char>(json)), {});
  EXPECT_NE(text.find("\"result_seq\": 1"), std::string::npos);
  auto reopened = ReportStore::open({dir.str(), 10});
  ASSERT_TRUE(reopened.ok());
  EXPECT_EQ(reopened->last_record(), 2u);
  auto latest = reopened->load_latest();
  ASSERT_TRUE(latest.ok());
  ASSERT_TRUE(latest->has_value());
  EXPECT_EQ((*latest)->result_seq(), 2u);
}

TEST(ReportStore, InterruptedWritesAreRemovedAtOpen) {
  TempDir dir("springscan-store-crash");
  {
    auto store = ReportStore::open({dir.str(), 10});
    ASSERT_TRUE(store->persist(1, report_only(report_with_seq(1))).ok());
  }
  // What kill -9 during persist(2) leaves: a temporary directory with a partial file.
  fs::create_directories(dir.str() + "/.tmp-r000000000002");
  std::ofstream(dir.str() + "/.tmp-r000000000002/report.pb.tmp") << "half";
  auto store = ReportStore::open({dir.str(), 10});
  ASSERT_TRUE(store.ok());
  EXPECT_FALSE(fs::exists(dir.str() + "/.tmp-r000000000002"));
  EXPECT_EQ(store->last_record(), 1u);
  EXPECT_EQ((*store->load_latest())->result_seq(), 1u);
}

TEST(ReportStore, RetentionKeepsTheNewest) {
  TempDir dir("springscan-store-retention");
  auto store = ReportStore::open({dir.str(), 3});
  for (std::uint64_t k = 1; k <= 6; ++k) {
    ASSERT_TRUE(
        store->persist(k, report_only(report_with_seq(static_cast<std::uint32_t>(k)))).ok());
  }
  int records = 0;
  for (const auto& entry : fs::directory_iterator(dir.str())) {
    (void)entry;
    ++records;
  }
  EXPECT_EQ(records, 3);
  EXPECT_FALSE(fs::exists(store->record_path(3)));
  EXPECT_TRUE(fs::exists(store->record_path(4)));
  EXPECT_TRUE(fs::exists(store->record_path(6)));
}

TEST(ReportStore, UnwritableDirectoryIsAnError) {
  TempDir dir("springscan-store-file");
  const std::string file = dir.str() + "/plain-file";
  std::ofstream(file) << "x";
  auto store = ReportStore::open({file + "/reports", 3});
  ASSERT_FALSE(store.ok());
  EXPECT_NE(store.message().find("report_dir"), std::string::npos);
}

}  // namespace
}  // namespace springscan::daemon
