// `springscan report REPORT.pb --out FILE` end to end: the built CLI renders a saved report,
// with and without deviation.ply beside it, and names a bad input file.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "analysis/io/point_io.hpp"
#include "tests/report/report_fixture.hpp"
#include "tests/support/test_paths.hpp"

namespace springscan::report {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

class CliReport : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("springscan_cli_report_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    fixture_ = testing::make_fixture(5000);
    std::ofstream(dir_ / "report.pb", std::ios::binary) << fixture_.report.SerializeAsString();
  }
  void TearDown() override { fs::remove_all(dir_); }
  // Runs the CLI with `arguments`; returns its exit code, stderr in err_.
  int run(const std::string& arguments) {
    const std::string command = std::string(springscan::test_paths::kSpringscan) + " report " +
                                arguments + " 2> " + (dir_ / "stderr.txt").string();
    const int status = std::system(command.c_str());
    err_ = slurp(dir_ / "stderr.txt");
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  fs::path dir_;
  testing::Fixture fixture_;
  std::string err_;
};

TEST_F(CliReport, RendersFromReportAndDeviationPly) {
  analysis::PointWriteOptions options;
  options.scalar_name = "signed_deviation_mm";
  ASSERT_TRUE(
      analysis::write_point_cloud((dir_ / "deviation.ply").string(), fixture_.cloud, options).ok());
  ASSERT_EQ(run((dir_ / "report.pb").string() + " --out " + (dir_ / "out.html").string()), 0)
      << err_;
  const std::string html = slurp(dir_ / "out.html");
  for (int id = 1; id <= 4; ++id)
    EXPECT_NE(html.find("id='bend-" + std::to_string(id) + "'"), std::string::npos);
  EXPECT_NE(html.find("class='banner fail'"), std::string::npos);
  EXPECT_EQ(html.find("Picture missing"), std::string::npos);
  EXPECT_NE(html.find("drawn from 5000 points"), std::string::npos);
}

TEST_F(CliReport, RendersWithoutCloudAndSaysSo) {
  ASSERT_EQ(run((dir_ / "report.pb").string() + " --quiet"), 0) << err_;
  const std::string html = slurp(dir_ / "report.html");  // default: beside the report
  EXPECT_NE(html.find("Picture missing: deviation.ply was not found beside report.pb"),
            std::string::npos);
  EXPECT_NE(html.find("id='bend-2'"), std::string::npos);
}

TEST_F(CliReport, NamesAnUnreadableReport) {
  std::ofstream(dir_ / "broken.pb", std::ios::binary) << "\xff\xff\xff garbage";
  EXPECT_EQ(run((dir_ / "broken.pb").string()), 2);
  EXPECT_NE(err_.find("broken.pb"), std::string::npos) << err_;
  EXPECT_EQ(run((dir_ / "missing.pb").string()), 2);
  EXPECT_NE(err_.find("missing.pb"), std::string::npos) << err_;
  EXPECT_EQ(run(""), 2);
}

}  // namespace
}  // namespace springscan::report
