#pragma once
// The model cache's protobuf form (v1::CachedPartModel) <-> PartModel (STYLE.md section 1: only
// *_proto.cpp files convert between messages and our structs).

#include <cstdint>
#include <string>

#include "analysis/cad/model.hpp"
#include "analysis/core/expected.hpp"
#include "analysis/core/part_model.hpp"
#include "proto/springscan.pb.h"

namespace springscan::analysis {

/// Bumped whenever the meaning of a cached field changes: older entries then miss.
constexpr std::uint32_t kCachedPartModelVersion = 2;  // 2: flanges carry their thickness

/// Samples, segmentation and face count (not the distance, not the BRep: the caller adds it).
v1::CachedPartModel to_proto(const PartModel& model, const std::string& source_sha256,
                             const std::string& settings_key);

/// The model without a distance. Errors: inconsistent sample arrays, face ids out of range.
Expected<PartModel> from_proto(const v1::CachedPartModel& message);

/// The analysis settings' model part (sample count, tessellation) applied over the C++ defaults.
/// Errors name the field and the value: sample_count 100..10^7 (a settings file must not be
/// able to size a huge allocation), deflections > 0, angular deflection below 90 degrees.
Expected<CadModelSettings> from_proto(const v1::CadModelSettings& message,
                                      CadModelSettings settings = {});

/// Every value of `settings` that shapes the cached model (import, sampling, segmentation; not
/// the distance queries, which are rebuilt on load), each field set: what the cache key hashes.
v1::CadModelSettings to_proto(const CadModelSettings& settings);

/// The model cache's settings key: the SHA-256 of to_proto(settings) serialized
/// deterministically, so any setting added to v1::CadModelSettings invalidates older entries.
std::string model_settings_key(const CadModelSettings& settings);

}  // namespace springscan::analysis
