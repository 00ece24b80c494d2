#include "bench/result_oracle.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace springscan::bench {

namespace {

// The register map's scalings: mm -> int32 um and deg -> int32 millideg, rounded; a value that
// is not finite reads as kInvalidInt32 ("no value").
std::int32_t um(double mm) { return std::isfinite(mm) ? regs::mm_to_um(mm) : regs::kInvalidInt32; }
std::int32_t mdeg(double deg) {
  return std::isfinite(deg) ? regs::deg_to_mdeg(deg) : regs::kInvalidInt32;
}

std::int32_t clamp_int32(double value) {
  if (!std::isfinite(value)) return 0;
  return static_cast<std::int32_t>(std::clamp<long long>(std::llround(value), 0, INT32_MAX));
}

/// Writes into the block by register address.
struct BlockWriter {
  BlockWords& words;
  regs::WordOrder order;
  std::uint16_t& at(std::uint16_t address) {
    return words[static_cast<std::size_t>(address - regs::kIrResultSeq)];
  }
  void put32(std::uint16_t address, std::int32_t value) {
    regs::encode_int32(value, order, &at(address));
  }
};

// Deviations and bends are only shown for an analysed part (RESULT_CODE 0, 1, 5, 6).
bool analysed(std::uint32_t code) {
  using regs::ResultCode;
  return code == static_cast<std::uint32_t>(ResultCode::kOk) ||
         code == static_cast<std::uint32_t>(ResultCode::kFormNok) ||
         code == static_cast<std::uint32_t>(ResultCode::kAmbiguous) ||
         code == static_cast<std::uint32_t>(ResultCode::kUndecided);
}

void put_bends(const v1::InspectionReport& report, BlockWriter& w) {
  const int bends = std::min(report.bends_size(), static_cast<int>(regs::kMaxBends));
  std::uint16_t failed = 0, undecided = 0;
  w.at(regs::kIrBendCount) = static_cast<std::uint16_t>(bends);
  for (int j = 0; j < bends; ++j) {
    const v1::Bend& b = report.bends(j);
    const auto base = static_cast<std::uint16_t>(regs::kIrBendTable + j * regs::kBendRecordSize);
    w.at(base + regs::kBendId) = static_cast<std::uint16_t>(std::clamp(b.id(), 0, 65535));
    const bool measurable = !b.has_measurable() || b.measurable();
    const bool is_undecided = b.decision() == v1::UNDECIDED;  // map version 6
    w.at(base + regs::kBendFlags) = static_cast<std::uint16_t>(
        (b.measured() ? regs::kBendMeasured : 0) | (b.pass() ? regs::kBendPass : 0) |
        (measurable ? 0 : regs::kBendNotMeasurable) | (is_undecided ? regs::kBendUndecided : 0));
    w.put32(static_cast<std::uint16_t>(base + regs::kBendSpringback), mdeg(b.springback_deg()));
    w.put32(static_cast<std::uint16_t>(base + regs::kBendMeasuredAngle),
            mdeg(b.measured_angle_deg()));
    // The bend shape table: no value where the report has no such figure.
    const double nan = std::nan("");
    const auto shape =
        static_cast<std::uint16_t>(regs::kIrBendShapeTable + j * regs::kBendShapeRecordSize);
    w.put32(static_cast<std::uint16_t>(shape + regs::kBendAngleSpread),
            mdeg(b.measured() && b.angle_along_bend_size() > 0 ? b.angle_spread_deg() : nan));
    w.put32(static_cast<std::uint16_t>(shape + regs::kBendMeasuredRadius),
            um(b.has_measured_radius_mm() ? b.measured_radius_mm() : nan));
    if (b.measured() && !b.pass() && !is_undecided) ++failed;
    if (is_undecided) ++undecided;
  }
  w.at(regs::kIrBendsFailed) = failed;
  w.at(regs::kIrBendsUndecided) = undecided;
}

std::string record_name(std::uint64_t record) {
  char name[32];
  std::snprintf(name, sizeof name, "r%012llu", static_cast<unsigned long long>(record));
  return name;
}

}  // namespace

BlockWords expected_block(const v1::InspectionReport& report, regs::WordOrder order) {
  BlockWords words(kBlockWords, 0);
  BlockWriter w{words, order};
  const bool with_analysis = analysed(report.result_code());
  const auto& dev = report.deviation();
  const double nan = std::nan("");
  w.at(regs::kIrResultSeq) = static_cast<std::uint16_t>(report.result_seq());
  w.at(regs::kIrResultPartId) =
      static_cast<std::uint16_t>(std::strtoul(report.input().part_id().c_str(), nullptr, 10));
  w.at(regs::kIrResultJobId) = static_cast<std::uint16_t>(report.job_id());
  w.at(regs::kIrResultCode) = static_cast<std::uint16_t>(report.result_code());
  w.put32(regs::kIrMaxDeviation,
          um(with_analysis ? std::max(std::abs(dev.min()), std::abs(dev.max())) : nan));
  w.put32(regs::kIrRmsDeviation, um(with_analysis ? dev.rms() : nan));
  w.put32(regs::kIrP95Deviation, um(with_analysis ? dev.p95() : nan));
  w.at(regs::kIrVectorCount) = static_cast<std::uint16_t>(
      with_analysis ? std::min(report.compensation_size(), static_cast<int>(regs::kMaxVectors))
                    : 0);
  w.at(regs::kIrVectorRecordSize) = regs::kVectorRecordSize;
  w.put32(regs::kIrCycleTimeMs, clamp_int32(report.cycle_time_ms()));
  w.at(regs::kIrBendRecordSize) = regs::kBendRecordSize;
  w.put32(regs::kIrScanPoints, clamp_int32(static_cast<double>(report.input().scan_points())));
  if (with_analysis) put_bends(report, w);
  return words;
}

std::vector<std::array<std::int32_t, 3>> expected_vectors(const v1::InspectionReport& report) {
  std::vector<std::array<std::int32_t, 3>> vectors;
  if (!analysed(report.result_code())) return vectors;
  for (const auto& c : report.compensation()) {
    if (vectors.size() >= regs::kMaxVectors) break;
    vectors.push_back({um(c.vector().x()), um(c.vector().y()), um(c.vector().z())});
  }
  return vectors;
}

std::optional<v1::InspectionReport> load_record(const std::string& report_dir,
                                                std::uint64_t record) {
  std::ifstream in(report_dir + "/" + record_name(record) + "/report.pb", std::ios::binary);
  v1::InspectionReport report;
  if (!in || !report.ParseFromIstream(&in)) return std::nullopt;
  return report;
}

std::uint64_t newest_record(const std::string& report_dir) {
  std::uint64_t newest = 0;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(report_dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() == 13 && name[0] == 'r')
      newest = std::max<std::uint64_t>(newest, std::stoull(name.substr(1)));
  }
  return newest;
}

std::string difference(const BlockWords& block, const simulators::ResultRead& read,
                       const v1::InspectionReport& report, regs::WordOrder order) {
  const BlockWords expected = expected_block(report, order);
  for (std::size_t i = 0; i < expected.size() && i < block.size(); ++i) {
    if (block[i] != expected[i])
      return "input register " + std::to_string(regs::kIrResultSeq + i) + " reads " +
             std::to_string(block[i]) + ", the stored report says " + std::to_string(expected[i]);
  }
  const auto vectors = expected_vectors(report);
  if (read.vectors_um.size() != vectors.size())
    return std::to_string(read.vectors_um.size()) + " vectors read, the stored report has " +
           std::to_string(vectors.size());
  for (std::size_t i = 0; i < vectors.size(); ++i) {
    if (read.vectors_um[i] != vectors[i])
      return "vector record " + std::to_string(i) + " differs from the stored report";
  }
  return {};
}

}  // namespace springscan::bench
