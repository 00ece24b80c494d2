#include "daemon/result_block.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace springscan::daemon {

namespace {

std::uint16_t part_id_number(const std::string& text) {
  // The daemon writes the PLC's numeric part id into input.part_id; anything else shows 0.
  char* end = nullptr;
  const unsigned long value = std::strtoul(text.c_str(), &end, 10);
  if (text.empty() || end == nullptr || *end != '\0' || value > 65535) return 0;
  return static_cast<std::uint16_t>(value);
}

double finite_or_nan(double value) {
  return std::isfinite(value) ? value : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

ResultBlock result_block_from_report(const v1::InspectionReport& report) {
  ResultBlock block;
  block.seq = static_cast<std::uint16_t>(report.result_seq());
  block.job_id = static_cast<std::uint16_t>(report.job_id());
  block.part_id = part_id_number(report.input().part_id());
  const auto code = report.result_code();
  block.code = code <= static_cast<std::uint32_t>(regs::ResultCode::kUndecided)
                   ? static_cast<regs::ResultCode>(code)
                   : regs::ResultCode::kAnalysisFailed;
  block.cycle_time_ms = static_cast<std::int64_t>(
      std::llround(std::isfinite(report.cycle_time_ms()) ? report.cycle_time_ms() : 0.0));
  block.scan_points = report.input().scan_points();
  const bool analysed =
      block.code == regs::ResultCode::kOk || block.code == regs::ResultCode::kFormNok ||
      block.code == regs::ResultCode::kAmbiguous || block.code == regs::ResultCode::kUndecided;
  if (!analysed) {
    // No analysis: the deviation fields say "no value" rather than a plausible zero.
    const double nan = std::numeric_limits<double>::quiet_NaN();
    block.max_deviation_mm = block.rms_deviation_mm = block.p95_deviation_mm = nan;
    return block;
  }
  const auto& dev = report.deviation();
  block.max_deviation_mm = finite_or_nan(std::max(std::abs(dev.min()), std::abs(dev.max())));
  block.rms_deviation_mm = finite_or_nan(dev.rms());
  block.p95_deviation_mm = finite_or_nan(dev.p95());
  for (const auto& bend : report.bends()) {
    BendRow row;
    row.id = static_cast<std::uint16_t>(std::clamp(bend.id(), 0, 65535));
    row.measured = bend.measured();
    row.pass = bend.pass();
    row.undecided = bend.decision() == v1::UNDECIDED;
    row.springback_deg = finite_or_nan(bend.springback_deg());
    row.measured_angle_deg = finite_or_nan(bend.measured_angle_deg());
    row.measurable = !bend.has_measurable() || bend.measurable();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    row.angle_spread_deg = bend.measured() && bend.angle_along_bend_size() > 0
                               ? finite_or_nan(bend.angle_spread_deg())
                               : nan;
    row.measured_radius_mm =
        bend.has_measured_radius_mm() ? finite_or_nan(bend.measured_radius_mm()) : nan;
    block.bends.push_back(row);
  }
  block.vectors.reserve(
      static_cast<std::size_t>(std::min<int>(report.compensation_size(), regs::kMaxVectors)));
  for (const auto& c : report.compensation()) {
    if (block.vectors.size() >= regs::kMaxVectors) break;
    block.vectors.push_back({c.vector().x(), c.vector().y(), c.vector().z()});
  }
  return block;
}

}  // namespace springscan::daemon
