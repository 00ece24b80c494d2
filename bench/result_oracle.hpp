#pragma once
// The fault campaign's oracle for stale results: the registers a RESULT_VALID must show for the
// report the station stored on disk, worked out from report.pb and the register map
// (docs/modbus-register-map.md, "Input registers, frozen result"), not by the daemon's own
// result_block.cpp, so that a wrong block cannot agree with itself.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "daemon/register_map.hpp"
#include "proto/springscan.pb.h"
#include "simulators/plc_client.hpp"

namespace springscan::bench {

namespace regs = daemon::regs;

/// Input registers kIrResultSeq .. kResultBlockEnd, as FC04 reads return them.
using BlockWords = std::vector<std::uint16_t>;
inline constexpr int kBlockWords = regs::kResultBlockEnd - regs::kIrResultSeq;

/// The block `report` must show in `order`.
BlockWords expected_block(const v1::InspectionReport& report, regs::WordOrder order);
/// The compensation vectors (int32 um) `report` must show.
std::vector<std::array<std::int32_t, 3>> expected_vectors(const v1::InspectionReport& report);

/// <report_dir>/r<record>/report.pb, or nullopt when it is missing or unreadable.
std::optional<v1::InspectionReport> load_record(const std::string& report_dir,
                                                std::uint64_t record);
/// The newest record number in `report_dir` (0: none).
std::uint64_t newest_record(const std::string& report_dir);

/// Empty when the registers (`block` read raw, `read` as the PLC decoded it, vectors included)
/// show `report`; else the first difference, with the register address, for the log.
std::string difference(const BlockWords& block, const simulators::ResultRead& read,
                       const v1::InspectionReport& report, regs::WordOrder order);

}  // namespace springscan::bench
