#pragma once
// The text parts of the HTML report: header with the verdict banner, and the tables. Each
// returns an HTML fragment with every text from the report escaped.

#include <string>

#include "proto/springscan.pb.h"

namespace springscan::report {

/// Title, part, time, station, and the PASS / FAIL / UNDECIDED banner with the verdict's
/// reasons and the decision rule that decided.
std::string header_html(const v1::InspectionReport& report);
/// min, max, mean, rms, p95, share out of tolerance, tolerance, points, the U of the statistic
/// judged and the surface criterion's decision.
std::string deviation_table(const v1::Deviation& deviation);
/// One row per bend (class "bend", id "bend-<id>"): nominal, measured, springback, tolerance,
/// radius and the result.
std::string bend_table(const v1::InspectionReport& report);
/// The automatic local best fits, one row per flange segment.
std::string segment_table(const v1::InspectionReport& report);
/// Method, iterations, stop reason, rms before/after, and the fitted transform.
std::string global_fit_table(const v1::InspectionReport& report);
std::string reduction_table(const v1::ReductionReport& reduction);
/// The deformation field and the compensation vectors' sizes.
std::string deformation_table(const v1::InspectionReport& report);
/// Stage times in ms with proportional bars.
std::string timings_table(const v1::Timings& timings);
/// Input files and sizes.
std::string input_table(const v1::InspectionReport& report);
/// The report's warnings (nothing when there are none).
std::string warnings_html(const v1::InspectionReport& report);
std::string footer_html(const v1::InspectionReport& report);

}  // namespace springscan::report
