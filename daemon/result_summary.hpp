#pragma once
// The compact JSON summary of one result, published on <prefix>/<station>/result/json
// (docs/plant-integration.md "Payloads"): what a historian, an MES or a dashboard needs without
// decoding the protobuf report: the ids that make the message unique, the verdict, the result
// code, the job and part, the deviation statistics and the bend table.

#include <cstdint>
#include <string>

#include "proto/springscan.pb.h"

namespace springscan::daemon {

/// What makes a published result unique (docs/plant-integration.md "Duplicates").
struct PublishedIds {
  std::string station;           ///< the topic's station name
  std::uint16_t boot_id = 0;     ///< BOOT_ID of the daemon that published it
  std::uint64_t record = 0;      ///< report store record number: unique over the station's life
  std::uint32_t result_seq = 0;  ///< RESULT_SEQ as the PLC saw it (wraps after 65535)
};

/// One line of JSON (no newline), schema "springscan.result.v1".
std::string result_summary_json(const v1::InspectionReport& report, const PublishedIds& ids);

}  // namespace springscan::daemon
