#include "daemon/page_feed.hpp"

#include <algorithm>
#include <optional>

#include "analysis/io/file_io.hpp"

namespace springscan::daemon {

PageFeed::PageFeed(const PageSettings& settings, const ReportStore& store, std::string station_name,
                   Log& log)
    : settings_(settings), store_(store), station_name_(std::move(station_name)), log_(log) {
  load_history();
  rebuild();
  thread_ = std::thread([this] { watch(); });
}

PageFeed::~PageFeed() {
  stop();
  if (thread_.joinable()) thread_.join();
}

void PageFeed::on_status(const MachineStatus& s, bool calibration_drift) {
  const PageStatus next{s.state,          s.error_code,    s.error_detail,   s.ready,
                        s.scanner_online, s.plc_comm_lost, calibration_drift};
  std::lock_guard lock(mutex_);
  if (next == status_) return;
  status_ = next;
  status_dirty_ = true;
  wake_watcher_.notify_one();
}

PageFeed::Snapshot PageFeed::current() const {
  std::lock_guard lock(mutex_);
  return snapshot_;
}

PageFeed::Snapshot PageFeed::wait_newer(std::uint64_t seen,
                                        std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mutex_);
  changed_.wait_for(lock, timeout, [&] { return stop_ || snapshot_.version > seen; });
  return snapshot_;
}

void PageFeed::stop() {
  std::lock_guard lock(mutex_);
  stop_ = true;
  changed_.notify_all();
  wake_watcher_.notify_all();
}

bool PageFeed::stopped() const {
  std::lock_guard lock(mutex_);
  return stop_;
}

std::string PageFeed::deviation_svg(std::uint64_t record) const {
  {
    std::lock_guard lock(mutex_);
    if (record == svg_record_) return svg_;
  }
  auto html = analysis::read_file_bytes(store_.record_path(record) + "/report.html");
  return html ? deviation_svg_from_report_html(*html) : std::string();
}

void PageFeed::watch() {
  const auto interval = std::chrono::milliseconds(settings_.watch_interval_ms);
  for (;;) {
    bool status_changed = false;
    {
      std::unique_lock lock(mutex_);
      wake_watcher_.wait_for(lock, interval, [this] { return stop_ || status_dirty_; });
      if (stop_) return;
      status_changed = status_dirty_;
      status_dirty_ = false;
    }
    const std::time_t start = shift_start(std::time(nullptr), settings_.shift_starts_min);
    const bool new_shift = start != shift_start_;
    if (new_shift) {
      shift_start_ = start;
      shift_ = {};
      for (const PageResult& r : recent_) {
        if (r.created >= start) shift_.count(r.report, 1);  // already in the new shift
      }
    }
    const bool added = take_new_records();
    if (added || status_changed || new_shift) rebuild();
    // After the snapshot, so that reading report.html never delays a verdict; a page asking
    // for the picture before this reads it itself (deviation_svg).
    if (added) cache_picture(recent_.front().record);
  }
}

void PageFeed::cache_picture(std::uint64_t record) {
  auto html = analysis::read_file_bytes(store_.record_path(record) + "/report.html");
  std::string svg = html ? deviation_svg_from_report_html(*html) : std::string();
  std::lock_guard lock(mutex_);
  svg_record_ = record;
  svg_ = std::move(svg);
}

namespace {

// A record's report for the page; nullopt when it is not (or no longer) in the store.
std::optional<PageResult> read_result(const ReportStore& store, std::uint64_t record) {
  auto bytes = analysis::read_file_bytes(store.record_path(record) + "/report.pb");
  v1::InspectionReport full;
  if (!bytes || !full.ParseFromString(*bytes)) return std::nullopt;
  PageResult result{record, page_fields(full), parse_created_utc(full.created_utc())};
  return result;
}

}  // namespace

void PageFeed::load_history() {
  // Newest first, until the table is full and the records are older than the shift. Bounded
  // by the store's retention; runs once, before the watcher starts.
  last_record_ = store_.last_record();
  shift_start_ = shift_start(std::time(nullptr), settings_.shift_starts_min);
  const auto wanted = static_cast<std::size_t>(std::max(settings_.recent_results, 1));
  for (std::uint64_t record = last_record_; record > 0; --record) {
    auto result = read_result(store_, record);
    if (!result) break;  // removed by retention (or unreadable): nothing older is kept either
    const bool in_shift = result->created >= shift_start_;
    if (in_shift) shift_.count(result->report, 1);
    if (recent_.size() < wanted) {
      recent_.push_back(std::move(*result));
    } else if (!in_shift) {
      break;
    }
  }
  if (!recent_.empty()) cache_picture(recent_.front().record);
}

bool PageFeed::take_new_records() {
  const std::uint64_t newest = store_.last_record();
  bool added = false;
  for (; last_record_ < newest; ++last_record_) {
    auto result = read_result(store_, last_record_ + 1);
    if (!result) {
      log_.warning("operator page: record " + std::to_string(last_record_ + 1) +
                   " cannot be read; it is left out of the page");
      continue;
    }
    add_result(std::move(*result));
    added = true;
  }
  return added;
}

void PageFeed::add_result(PageResult result) {
  if (result.created >= shift_start_) shift_.count(result.report, 1);
  recent_.push_front(std::move(result));
  while (recent_.size() > static_cast<std::size_t>(std::max(settings_.recent_results, 1)))
    recent_.pop_back();
}

void PageFeed::rebuild() {
  PageView view;
  view.station = station_name_;
  view.recent = &recent_;
  view.shift_start = shift_start_;
  view.shift = shift_;
  {
    std::lock_guard lock(mutex_);
    view.status = status_;
  }
  auto json = std::make_shared<const std::string>(page_snapshot_json(view));
  std::lock_guard lock(mutex_);
  snapshot_.json = std::move(json);
  ++snapshot_.version;
  changed_.notify_all();
}

}  // namespace springscan::daemon
