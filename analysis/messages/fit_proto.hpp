#pragma once
// Results of the reduce, global fit and deviation stages -> report messages (STYLE.md §1: only
// *_proto.cpp files touch proto types).

#include "analysis/deviation/deviation.hpp"
#include "analysis/preprocess/reduction.hpp"
#include "analysis/registration/global_fit.hpp"
#include "proto/springscan.pb.h"

namespace springscan::analysis {

/// 16 numbers, row-major 4x4 (DESIGN.md report.json contract).
void transform_to_proto(const Transform& T, google::protobuf::RepeatedField<double>* out);

/// report.global_fit: transform (T_cad_scan), rms at each step, history, stop reason.
void to_proto(const GlobalFitResult& fit, const GlobalFitSettings& settings, v1::GlobalFit* out);
/// The boundary stage's free directions (replaces out->free_directions).
void to_proto(const std::vector<FreeDirection>& free, v1::GlobalFit* out);

/// report.deviation: statistics, reference ("cad_surface" or "model_points"), the colour scale
/// deviation.ply uses. tolerance_mm and fraction_out_of_tolerance are the verdict's
/// (verdict_proto.hpp).
void to_proto(const DeviationResult& deviation, double color_scale_mm, v1::Deviation* out);

/// report.reduction: k-center counts and covering radii of model and scan.
void to_proto(const ReductionOutcome& reduction, const ReductionSettings& settings,
              std::size_t model_points_in, std::size_t scan_points_in, v1::ReductionReport* out);

}  // namespace springscan::analysis
