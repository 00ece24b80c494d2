#pragma once
// Conversion of the uncertainty stage's settings (STYLE.md §1: only *_proto files touch proto
// types next to our structs).

#include "analysis/core/expected.hpp"
#include "analysis/uncertainty/uncertainty.hpp"
#include "proto/springscan.pb.h"

namespace springscan::analysis {

/// UncertaintySettings{} with the fields `message` sets; errors name the field and the value.
Expected<UncertaintySettings> from_proto(const v1::UncertaintySettings& message);

/// Every field of the proto message, as in force.
void to_proto(const UncertaintySettings& settings, v1::UncertaintySettings* message);

}  // namespace springscan::analysis
