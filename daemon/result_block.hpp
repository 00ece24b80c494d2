#pragma once
// The frozen result block (register map "Input registers, frozen result") as plain values, and
// its construction from an InspectionReport. Units: mm and degrees here; the register image
// scales them to int32 um and millidegrees.

#include <cstdint>
#include <limits>
#include <vector>

#include "daemon/register_map.hpp"
#include "proto/springscan.pb.h"

namespace springscan::daemon {

struct BendRow {
  std::uint16_t id = 0;
  bool measured = false;
  bool pass = false;
  double springback_deg = 0.0;  ///< nominal minus measured
  double measured_angle_deg = 0.0;
  bool measurable = true;  ///< false: a closed hem
  /// Along the bend line, max - min over its stations; NaN (no value) when not measured.
  double angle_spread_deg = std::numeric_limits<double>::quiet_NaN();
  /// The bend zone's inner radius; NaN (no value) when not fitted.
  double measured_radius_mm = std::numeric_limits<double>::quiet_NaN();
  bool undecided = false;  ///< decision UNDECIDED: within U of its limit, or not measured
};

struct VectorRow {
  double dx_mm = 0.0;  ///< compensation vector, CAD frame
  double dy_mm = 0.0;
  double dz_mm = 0.0;
};

struct ResultBlock {
  std::uint16_t seq = 0;  ///< RESULT_SEQ; 0 = no result
  std::uint16_t part_id = 0;
  std::uint16_t job_id = 0;
  regs::ResultCode code = regs::ResultCode::kNoData;
  double max_deviation_mm = 0.0;  ///< max |signed deviation|
  double rms_deviation_mm = 0.0;
  double p95_deviation_mm = 0.0;
  std::int64_t scan_points = 0;
  std::int64_t cycle_time_ms = 0;
  std::vector<BendRow> bends;      ///< first regs::kMaxBends are shown
  std::vector<VectorRow> vectors;  ///< first regs::kMaxVectors are shown
};

/// The block for a report. The report's result_seq, job_id, result_code, cycle_time_ms and
/// input.part_id must be filled in. Numbers that are not finite show as kInvalidInt32.
ResultBlock result_block_from_report(const v1::InspectionReport& report);

}  // namespace springscan::daemon
