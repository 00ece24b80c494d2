#pragma once
// Orthographic views of a part in the CAD frame: the standard engineering views (top, front,
// side) and an isometric one, and the mapping of 3-D points to image pixels that the raster
// renderer and the SVG overlays (bend labels, compensation arrows) share.

#include <Eigen/Core>
#include <vector>

#include "analysis/core/point_cloud.hpp"

namespace springscan::report {

using analysis::Vec3;

enum class ViewKind {
  kTop,        ///< looking down -z: +x right, +y up
  kFront,      ///< looking along +y: +x right, +z up
  kSide,       ///< right side, looking along -x: +y right, +z up
  kIsometric,  ///< from (+1, -1, +1) towards the origin, +z up
};

/// The view's screen axes in the CAD frame. `forward` points from the viewer into the scene,
/// so a smaller `depth` is nearer. right x up = -forward (a right-handed screen frame).
struct ViewBasis {
  Vec3 right;
  Vec3 up;
  Vec3 forward;
};

ViewBasis view_basis(ViewKind kind);
/// "Top", "Front", "Side (right)", "Isometric".
const char* view_name(ViewKind kind);

struct ViewSettings {
  int width_px = 560;   ///< image width
  int height_px = 400;  ///< image height
  int margin_px = 18;   ///< free border around the part (room for labels and splats)
};

/// An orthographic projection fitted to a set of points: scale and centre chosen so the points
/// fill the image inside its margin, with equal scale on both axes. Value type.
struct ViewProjection {
  ViewBasis basis;
  int width_px = 0;
  int height_px = 0;
  double scale_px_per_mm = 1.0;
  Eigen::Vector2d center_mm = Eigen::Vector2d::Zero();  ///< (right, up) coordinates at the centre

  /// Image coordinates (x right, y down) of p; pixel (i, j) covers [i, i+1) x [j, j+1).
  Eigen::Vector2d to_pixel(const Vec3& p) const {
    return {0.5 * width_px + (p.dot(basis.right) - center_mm.x()) * scale_px_per_mm,
            0.5 * height_px - (p.dot(basis.up) - center_mm.y()) * scale_px_per_mm};
  }
  /// Distance along the viewing direction; smaller is nearer the viewer.
  double depth(const Vec3& p) const { return p.dot(basis.forward); }
  /// The image-plane direction of a 3-D direction, in pixels per mm (y down).
  Eigen::Vector2d direction_to_pixel(const Vec3& d) const {
    return {d.dot(basis.right) * scale_px_per_mm, -d.dot(basis.up) * scale_px_per_mm};
  }
};

/// Fits `kind` to `points` (all of them; pass a reduced cloud). With no points, or all points
/// on one spot, the scale is 1 px/mm around the centroid. Pure function.
ViewProjection fit_view(const std::vector<Vec3>& points, ViewKind kind,
                        const ViewSettings& settings = {});

}  // namespace springscan::report
