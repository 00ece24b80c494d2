#pragma once
// Proto settings (v1::*Settings, `optional` fields) -> the stages' C++ settings structs, and
// back for report.settings. Each conversion starts from the struct's defaults and overrides
// only the fields the message sets, validating each, naming the field and the value
// (STYLE.md §4). One function per stage: other stages append theirs here or in their own
// *_proto.cpp.

#include "analysis/core/expected.hpp"
#include "analysis/preprocess/normals.hpp"
#include "analysis/preprocess/reduction.hpp"
#include "analysis/registration/global_fit.hpp"
#include "analysis/springback/springback.hpp"
#include "proto/springscan.pb.h"

namespace springscan::analysis {

/// normals.k_neighbors (3..1000), normals.radius_mm (>= 0).
Expected<NormalSettings> from_proto(const v1::NormalSettings& message);
/// reduction.kcenter_radius_mm (> 0), kcenter_count (0..10^7), voxel_size_mm (>= 0, 0 = auto),
/// min_curvature (>= 0), mesh_decimation.* (validate(DecimationSettings)'s ranges).
Expected<ReductionSettings> from_proto(const v1::ReductionSettings& message);
/// registration.*: method, max_iterations, max_correspondence_distance_mm, trimmed_fraction,
/// robust_kernel, kernel_scale_mm, min_error_mm, error_ratio_stop (0 = off),
/// pca_initial_alignment; the ranges are validate(IcpSettings)'s (analysis/registration/icp.hpp).
Expected<GlobalFitSettings> from_proto(const v1::RegistrationSettings& message);
/// springback.bend_margin_mm (0 to 1000), max_iterations, max_correspondence_distance_mm (> 0;
/// also the distance up to which scan points are assigned to flanges); the ranges otherwise
/// are validate(LocalFitSettings)'s, i.e. the ICP engine's. The deviation section's one field,
/// tolerance_mm, and every other tolerance belong to the verdict (verdict_proto.hpp).
Expected<SpringbackSettings> from_proto(const v1::SpringbackSettings& message);
/// threads (0..1024; 0 = all cores).
Expected<int> threads_from_proto(const v1::AnalysisSettings& message);

/// The settings in force, every field set (report.settings).
void to_proto(const NormalSettings& settings, v1::NormalSettings* message);
void to_proto(const ReductionSettings& settings, v1::ReductionSettings* message);
void to_proto(const GlobalFitSettings& settings, v1::RegistrationSettings* message);
void to_proto(const SpringbackSettings& settings, v1::SpringbackSettings* message);

}  // namespace springscan::analysis
