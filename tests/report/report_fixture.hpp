#pragma once
// A synthetic inspection with known geometry, shared by the report tests and bench_report: a
// hat profile (simulators/parts/sheet_profile.hpp) sampled with a smooth deviation field along the
// profile, and a report whose bends, segments, fit history and compensation vectors follow
// from it. Fixed seeds.

#include <cstddef>

#include "analysis/core/point_cloud.hpp"
#include "proto/springscan.pb.h"

namespace springscan::report::testing {

struct Fixture {
  v1::InspectionReport report;
  analysis::PointCloud cloud;  ///< CAD frame, scalars = signed deviation (mm)
};

/// `points` scan points on a hat profile (4 bends, B2 failing its tolerance), part id
/// "HAT-7 <rev&B>" to exercise escaping.
Fixture make_fixture(std::size_t points);

}  // namespace springscan::report::testing
