#pragma once
// Proto conversions of the verdict (STYLE.md §1: only *_proto.cpp files convert): its settings
// in, its decision out into the report. The verdict owns every tolerance, so this is the one
// place that reads and validates them, each with one range.

#include "analysis/core/expected.hpp"
#include "analysis/inspection/verdict.hpp"
#include "proto/springscan.pb.h"

namespace springscan::analysis {

/// VerdictSettings overrides -> VerdictSettings: verdict.tolerance_mm (0 < mm <= 1e6),
/// angle_tolerance_deg (0 < deg <= 180), deviation_statistic, min_coverage (0 to 1),
/// max_fit_rms_mm (> 0), the shape limits max_angle_spread_deg, min_curl_radius_mm,
/// max_flatness_mm, max_edge_deviation_mm (0 = off, to 1e6), decision_rule (unset: GUARD_BAND).
/// Errors name the field and the value.
Expected<VerdictSettings> from_proto(const v1::VerdictSettings& message);

/// The verdict's settings from a whole AnalysisSettings: its own section, plus
/// deviation.tolerance_mm, the older place of the surface tolerance, which still sets it when
/// verdict.tolerance_mm is unset (same range; docs/architecture.md "Settings sections").
Expected<VerdictSettings> verdict_settings_from_proto(const v1::AnalysisSettings& message);

/// The settings in force, every field set (report.settings).
void to_proto(const VerdictSettings& settings, v1::VerdictSettings* message);

/// Copies the decision into `report`: verdict.pass, decision, decision_rule and reasons;
/// deviation.tolerance_mm, fraction_out_of_tolerance, decision and uncertainty_mm (the U of the
/// statistic the verdict compared); each bend's pass, decision and angle_tolerance_deg (report
/// bends matched by id); each segment's shape_decision (by flange id). Call after the stages
/// filled the report.
void to_proto(const VerdictResult& verdict, v1::InspectionReport* report);

}  // namespace springscan::analysis
