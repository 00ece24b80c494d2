#pragma once
// Helpers shared by the CAD tests: a per-test temporary folder and the shared CAD data path.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "tests/support/test_paths.hpp"

namespace springscan::analysis::testing {

/// A fresh folder under the system temp dir, named after the running test, removed at exit.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            (std::string("springscan_") + info->test_suite_name() + "_" + info->name());
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

inline std::string shared_cad(const std::string& name) {
  return springscan::test_paths::shared_cad(name);
}

}  // namespace springscan::analysis::testing
