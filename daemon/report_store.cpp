#include "daemon/report_store.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "report/inspection_files.hpp"

namespace springscan::daemon {

namespace fs = std::filesystem;
using analysis::Expected;
using analysis::fail;

namespace {

constexpr const char* kTempPrefix = ".tmp-";

std::string system_error(const std::string& what, const std::string& path) {
  return what + " " + path + ": " + std::strerror(errno);
}

Expected<bool> fsync_path(const std::string& path, int flags) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0) return fail(system_error("cannot open", path));
  const bool ok = ::fsync(fd) == 0;
  const std::string error = ok ? "" : system_error("fsync failed for", path);
  ::close(fd);
  if (!ok) return fail(error);
  return true;
}

/// "r000000000042" -> 42; anything else -> 0.
std::uint64_t record_number(const std::string& name) {
  if (name.size() != 13 || name[0] != 'r') return 0;
  std::uint64_t value = 0;
  for (std::size_t i = 1; i < name.size(); ++i) {
    if (name[i] < '0' || name[i] > '9') return 0;
    value = value * 10 + static_cast<std::uint64_t>(name[i] - '0');
  }
  return value;
}

std::vector<std::uint64_t> list_records(const std::string& directory) {
  std::vector<std::uint64_t> records;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(directory, ec)) {
    const std::uint64_t n = record_number(entry.path().filename().string());
    if (n != 0 && entry.is_directory(ec)) records.push_back(n);
  }
  std::sort(records.begin(), records.end());
  return records;
}

}  // namespace

ReportStore::ReportStore(ReportStoreSettings settings) : settings_(std::move(settings)) {}

ReportStore::ReportStore(ReportStore&& other) noexcept
    : settings_(std::move(other.settings_)), last_record_(other.last_record_) {}

Expected<ReportStore> ReportStore::open(const ReportStoreSettings& settings) {
  std::error_code ec;
  fs::create_directories(settings.directory, ec);
  if (ec || !fs::is_directory(settings.directory, ec) || ec) {
    return fail("report_dir " + settings.directory + ": cannot create: " + ec.message());
  }
  // Interrupted writes (power loss, kill -9) left only hidden temporaries: drop them.
  for (const auto& entry : fs::directory_iterator(settings.directory, ec)) {
    if (entry.path().filename().string().rfind(kTempPrefix, 0) == 0) {
      fs::remove_all(entry.path(), ec);
    }
  }
  ReportStore store(settings);
  const auto records = list_records(settings.directory);
  store.last_record_ = records.empty() ? 0 : records.back();
  return store;
}

std::uint64_t ReportStore::last_record() const {
  std::lock_guard lock(mutex_);
  return last_record_;
}

std::string ReportStore::record_path(std::uint64_t record) const {
  char name[32];
  std::snprintf(name, sizeof name, "r%012llu", static_cast<unsigned long long>(record));
  return (fs::path(settings_.directory) / name).string();
}

Expected<std::optional<v1::InspectionReport>> ReportStore::load_latest() const {
  const std::uint64_t record = last_record();
  if (record == 0) return std::optional<v1::InspectionReport>{};
  const std::string path = record_path(record) + "/report.pb";
  std::ifstream in(path, std::ios::binary);
  v1::InspectionReport report;
  if (!in || !report.ParseFromIstream(&in)) return fail(path + ": unreadable report");
  return std::optional<v1::InspectionReport>(std::move(report));
}

analysis::InspectionOutcome report_only(v1::InspectionReport report) {
  analysis::InspectionOutcome outcome;
  outcome.report = std::move(report);
  return outcome;
}

Expected<std::string> ReportStore::persist(std::uint64_t record,
                                           const analysis::InspectionOutcome& outcome) {
  const std::string final_path = record_path(record);
  const std::string temp =
      (fs::path(settings_.directory) / (kTempPrefix + fs::path(final_path).filename().string()))
          .string();
  std::error_code ec;
  fs::remove_all(temp, ec);
  if (!fs::create_directory(temp, ec)) return fail("cannot create " + temp + ": " + ec.message());
  // Every file of the record through the one writer `springscan analyze` uses
  // (report/inspection_files.hpp).
  auto written = report::write_inspection_files(temp, outcome);
  if (!written) return written.error().prepend("record " + std::to_string(record) + ": ");
  if (::rename(temp.c_str(), final_path.c_str()) != 0) {
    return fail(system_error("cannot rename report into", final_path));
  }
  auto synced = fsync_path(settings_.directory, O_RDONLY | O_DIRECTORY);
  if (!synced) return synced.error();
  {
    std::lock_guard lock(mutex_);
    last_record_ = std::max(last_record_, record);
  }
  apply_retention();
  return final_path;
}

void ReportStore::apply_retention() {
  const auto records = list_records(settings_.directory);
  const auto keep = static_cast<std::size_t>(std::max(settings_.retention, 1));
  std::error_code ec;
  for (std::size_t i = 0; i + keep < records.size(); ++i) {
    fs::remove_all(record_path(records[i]), ec);
  }
}

}  // namespace springscan::daemon
