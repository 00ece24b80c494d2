#pragma once
// The check part (docs/calibration.md, issue 42): a reference part measured every shift; each
// configured characteristic of its report is compared with its reference value, and one beyond
// its limit (or not measured) means the station has drifted (CALIBRATION_DRIFT).
//
// Characteristics: `springscan trend`'s names (report/trend.hpp: "bend 2 springback",
// "deviation p95", ...), and the pose of the result frame, "pose rotation x|y|z" (deg, the
// rotation vector of alignment.transform) and "pose translation x|y|z" (mm). A head that turns
// rigidly moves the whole scan, which the best fit then takes back: the springback does not see
// it, the pose of a check part held in a fixture does.
//
// Thread safety: pure functions.

#include <map>
#include <string>

#include "proto/springscan.pb.h"

namespace springscan::report {

/// Every characteristic `report` measured, by name (trend's and the pose's).
std::map<std::string, double> check_characteristics(const v1::InspectionReport& report);

/// The comparison of `report` with `check`'s references.
v1::CheckResult check_part(const v1::InspectionReport& report, const v1::CheckPartConfig& check);

}  // namespace springscan::report
