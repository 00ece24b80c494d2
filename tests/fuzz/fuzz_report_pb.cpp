// libFuzzer target: a report.pb as `springscan report` reads it (a file from another station,
// a truncated copy): the protobuf parse, then the HTML page drawn from whatever parsed, which
// walks every repeated field (bends, segments, vectors, error history).
#include <cstddef>
#include <cstdint>

#include "proto/springscan.pb.h"
#include "report/report_html.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  springscan::v1::InspectionReport report;
  if (!report.ParseFromArray(data, static_cast<int>(size))) return 0;
  (void)springscan::report::render_report_html(report, springscan::analysis::PointCloud{});
  return 0;
}
