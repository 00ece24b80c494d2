#pragma once
// Compensation vectors (DESIGN.md stage 9): at model control points in the CAD frame,
// c = -alpha * d, where d is the deformation field interpolated smoothly at the control point,
// limited to a maximum length. A tool designer moves the tool surface by c to pre-bend against
// the measured springback (docs/matching.md "Compensation").
//
// Interpolation: Nadaraya-Watson, a Gaussian-weighted average of the field vectors near the
// control point, d(x) = sum_i w_i d_i / sum_i w_i, w_i = exp(-|x - p_i|^2 / (2 sigma^2)) over the
// vectors with |x - p_i| <= 3 sigma. It reproduces a constant field exactly, averages the noise
// of single pairs, and never extrapolates: a control point with no vector within 3 sigma gets
// no compensation and is marked unsupported. On a refined field (field_refinement.hpp) a
// control point that is a field point takes its own vector (the refined field is smooth
// already), a field point the scan does not cover gets none, and only other points (e.g. the
// vertices of the CAD tessellation) are interpolated.
//
// Thread safety: pure functions; the writers touch only the file they are given.

#include <cstddef>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/matching/deformation_field.hpp"

namespace springscan::analysis {

struct CompensationSettings {
  double scale = 1.0;                ///< alpha in c = -alpha * d (1: mirror the deformation)
  double max_magnitude_mm = 5.0;     ///< longer vectors are shortened to this, direction kept
  double smoothing_radius_mm = 0.0;  ///< Gaussian sigma; 0: the field's median point spacing
};

struct CompensationVector {
  Vec3 point = Vec3::Zero();        ///< control point, CAD frame, mm
  Vec3 vector = Vec3::Zero();       ///< compensation c, mm
  Vec3 deformation = Vec3::Zero();  ///< interpolated deformation d, mm
  int support = 0;                  ///< field vectors that contributed
  bool supported = false;           ///< false: no field vector within 3 sigma, c = 0
  bool clipped = false;             ///< c was shortened to max_magnitude_mm
};

struct Compensation {
  std::vector<CompensationVector> vectors;  ///< one per control point, in their order
  double smoothing_radius_mm = 0.0;         ///< sigma actually used
  std::size_t unsupported = 0;              ///< control points without compensation
  std::size_t clipped = 0;                  ///< vectors shortened by the magnitude limit
  double max_magnitude_mm = 0.0;            ///< longest c after clipping
};

/// Compensation at `control_points` (CAD frame; by default pass the k-center-reduced model
/// points, or a user grid). Errors: non-finite settings or points, negative radius, a
/// non-positive magnitude limit.
Expected<Compensation> compensation(const DeformationField& field,
                                    const std::vector<Vec3>& control_points,
                                    const CompensationSettings& settings = {});

/// The bytes of compensation.csv / compensation.ply (below), for the atomic writer.
std::string format_compensation_csv(const Compensation& c);
std::string format_compensation_ply(const Compensation& c);

/// Writes a CSV a tool designer can load: header
/// `x_mm,y_mm,z_mm,cx_mm,cy_mm,cz_mm,magnitude_mm,supported,clipped`, one row per vector.
Expected<std::size_t> write_compensation_csv(const std::string& path, const Compensation& c);

/// Writes an ASCII PLY: vertices at the control points with properties nx ny nz (unit
/// direction of c, for viewers that draw normals), cx cy cz (c, mm) and magnitude (mm).
Expected<std::size_t> write_compensation_ply(const std::string& path, const Compensation& c);

}  // namespace springscan::analysis
