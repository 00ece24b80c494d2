#pragma once
// The datum alignment's settings (settings.alignment) and result (report.alignment) <-> proto
// (STYLE.md §1: only *_proto.cpp files touch proto types).

#include "analysis/core/expected.hpp"
#include "analysis/registration/datum.hpp"
#include "proto/springscan.pb.h"

namespace springscan::analysis {

/// alignment.datums[] (normal and direction normalised; kind given; the ranges and that the
/// datums fix all six directions: validate(DatumAlignmentSettings)), search_mm, band_mm,
/// min_points. Errors name the datum and the field.
Expected<DatumAlignmentSettings> from_proto(const v1::AlignmentSettings& message);
/// The settings in force, every field set (report.settings.alignment).
void to_proto(const DatumAlignmentSettings& settings, v1::AlignmentSettings* message);

/// report.alignment: the result frame. `datum` null: method "best_fit", the best fit's
/// transform; otherwise "datum", its transform, its motion from the best fit and every datum's
/// nominal, measured and residual.
void alignment_to_proto(const Transform& T_cad_scan_best, const DatumAlignmentResult* datum,
                        v1::Alignment* out);

}  // namespace springscan::analysis
