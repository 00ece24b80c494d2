#include "report/check_part.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "report/trend.hpp"

namespace springscan::report {
namespace {

// "pose rotation x|y|z" (deg) and "pose translation x|y|z" (mm) of the result frame's
// transform (16 numbers, row-major).
void add_pose(const v1::InspectionReport& report, std::map<std::string, double>& out) {
  const auto& t = report.alignment().transform();
  if (t.size() != 16) return;
  Eigen::Matrix3d R;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R(r, c) = t[4 * r + c];
  const Eigen::AngleAxisd turn(R);
  const Eigen::Vector3d rotation = turn.angle() * turn.axis() * 180.0 / std::numbers::pi;
  const char* axes[] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    out[std::string("pose rotation ") + axes[i]] = rotation[i];
    out[std::string("pose translation ") + axes[i]] = t[4 * i + 3];
  }
}

}  // namespace

std::map<std::string, double> check_characteristics(const v1::InspectionReport& report) {
  std::map<std::string, double> out;
  for (const Characteristic& c : collect_characteristics({report})) out[c.name] = c.values.front();
  add_pose(report, out);
  return out;
}

v1::CheckResult check_part(const v1::InspectionReport& report, const v1::CheckPartConfig& check) {
  const std::map<std::string, double> measured = check_characteristics(report);
  v1::CheckResult result;
  for (const v1::CheckReference& ref : check.reference()) {
    v1::CheckItem* item = result.add_items();
    item->set_characteristic(ref.characteristic());
    item->set_reference(ref.value());
    item->set_limit(ref.limit());
    const auto found = measured.find(ref.characteristic());
    // Not measured cannot be vouched for: the station is treated as drifted.
    bool beyond = found == measured.end();
    if (!beyond) {
      item->set_measured(found->second);
      beyond = !(std::abs(found->second - ref.value()) <= ref.limit());
    }
    item->set_beyond(beyond);
    result.set_drift(result.drift() || beyond);
  }
  return result;
}

}  // namespace springscan::report
