#pragma once
// Conversion of the springback results into the report messages (STYLE.md §1: only *_proto
// files touch proto types next to our structs).

#include "analysis/springback/springback.hpp"
#include "proto/springscan.pb.h"

namespace springscan::analysis {

/// Appends one v1::Segment per flange (cad_faces, points, local_fit, kind "flange") and one
/// v1::Bend per bend (nominal axis in the CAD frame, angles, springback, verdict input) to
/// `report`. Segment ids are flange ids, so Bend.segment_a/b name the segments directly.
void fill_springback_report(const SpringbackResult& result, v1::InspectionReport& report);

/// The LocalFit message of one fit: row-major 4x4 transform, rms, inliers, history.
void to_proto(const LocalFitResult& fit, v1::LocalFit& out);

}  // namespace springscan::analysis
