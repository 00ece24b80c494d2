#pragma once
// Bent sheet-metal profiles (L, U, hat, Z, ...) described by flange lengths, bend angles and
// radii: the geometry shared by the CAD tests (built as OpenCASCADE shapes), the springback
// tests and the scanner simulator (sampled analytically), so that every test knows its ground
// truth exactly.
//
// Convention: the profile lies in the x-z plane of its own frame and is extruded along +y by
// `width_mm`. The path describes the *reference side* of the sheet (the side a scanner looks
// at), starting at the origin heading +x. A positive bend angle turns the path to the left
// (from +x towards +z); its arc has radius
// `bend_radii_mm[i]` on the reference side. With thickness > 0 the other side of the sheet is
// offset by the thickness to the right of the path (towards -z at the start).

#include <vector>

#include "analysis/core/point_cloud.hpp"

namespace springscan::parts {

// The parts are built of the analysis types (points, models, segmentation).
using namespace springscan::analysis;

struct ProfileSpec {
  std::vector<double> flange_lengths_mm;  ///< n straight segments, in path order
  std::vector<double> bend_angles_deg;    ///< n-1 signed turns; |angle| is the nominal bend angle
  std::vector<double> bend_radii_mm;      ///< n-1 radii of the reference-side arcs
  double width_mm = 60.0;                 ///< extrusion length along +y
  double thickness_mm = 0.0;              ///< 0: a surface (one side only)
};

/// One element of the reference-side path, in the profile's (x, z) plane.
struct ProfileElement {
  enum class Kind { kLine, kArc };
  Kind kind = Kind::kLine;
  Eigen::Vector2d start = Eigen::Vector2d::Zero();
  Eigen::Vector2d end = Eigen::Vector2d::Zero();
  // Arcs only: centre, radius, the polar angle of `start` around the centre, signed sweep.
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double radius_mm = 0.0;
  double start_angle_rad = 0.0;
  double sweep_rad = 0.0;  ///< > 0 counter-clockwise (a left turn)
  int flange_index = -1;   ///< lines: index into flange_lengths_mm
  int bend_index = -1;     ///< arcs: index into bend_angles_deg
  double length_mm() const;
};

/// True when the spec is consistent (sizes match, lengths and radii positive, |angle| < 180).
bool is_valid(const ProfileSpec& spec);

/// The path as alternating lines and arcs: line 0, arc 0, line 1, ... Requires is_valid(spec).
std::vector<ProfileElement> profile_path(const ProfileSpec& spec);

/// Maps a profile-plane point (x, z) at extrusion coordinate y into 3-D.
inline Vec3 profile_to_3d(const Eigen::Vector2d& xz, double y) { return {xz.x(), y, xz.y()}; }

// Common profiles (inner radius r, sheet width w); handy in tests, the simulator and the demo.
ProfileSpec l_profile(double leg_a_mm, double leg_b_mm, double angle_deg, double radius_mm);
ProfileSpec u_profile(double flange_mm, double web_mm, double angle_deg, double radius_mm);
ProfileSpec hat_profile(double brim_mm, double wall_mm, double top_mm, double angle_deg,
                        double radius_mm);
ProfileSpec z_profile(double flange_mm, double web_mm, double angle_deg, double radius_mm);

}  // namespace springscan::parts
