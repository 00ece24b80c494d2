#pragma once
// Proto conversions of the deformation-field and compensation stages (STYLE.md section 2: only
// *_proto.cpp files convert; the verdict's are in verdict_proto.hpp). Settings start from the C++
// defaults and take only the fields the message sets; each value is validated here, once, naming
// the field.

#include "analysis/core/expected.hpp"
#include "analysis/matching/compensation.hpp"
#include "analysis/matching/deformation_field.hpp"
#include "proto/springscan.pb.h"

namespace springscan::analysis {

/// deformation_field overrides -> DeformationFieldSettings. Errors name the field and value.
Expected<DeformationFieldSettings> from_proto(const v1::DeformationFieldSettings& message);
/// CompensationSettings overrides -> CompensationSettings.
Expected<CompensationSettings> from_proto(const v1::CompensationSettings& message);

/// The settings in force, every field set (report.settings).
void to_proto(const DeformationFieldSettings& settings, v1::DeformationFieldSettings* message);
void to_proto(const CompensationSettings& settings, v1::CompensationSettings* message);

/// Fills report.deformation_field: method, one Correspondence per vector, coverage (also the
/// nearest-neighbour one), sizes, total cost and whether the optimality certificate held.
void to_proto(const DeformationField& field, v1::DeformationField* message);

/// report.deformation_field -> the field's vectors (model and scan points, CAD frame) and its
/// sizes, as `springscan compensate` reads it back. Errors: a non-finite vector (kCorruption).
Expected<DeformationField> from_proto(const v1::DeformationField& message);

/// Appends the supported compensation vectors to report.compensation (unsupported control
/// points carry no vector; their count is in Compensation::unsupported).
void append_to_report(const Compensation& compensation, v1::InspectionReport* report);

}  // namespace springscan::analysis
