#include "report/view.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace springscan::report {

ViewBasis view_basis(ViewKind kind) {
  switch (kind) {
    case ViewKind::kTop:
      return {Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitZ()};
    case ViewKind::kFront:
      return {Vec3::UnitX(), Vec3::UnitZ(), Vec3::UnitY()};
    case ViewKind::kSide:
      return {Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitX()};
    case ViewKind::kIsometric:
      break;
  }
  // The viewer sits at (+1, -1, +1): front-right-top. right = forward x up keeps the frame
  // right-handed; up is +z made orthogonal to the viewing direction.
  const Vec3 forward = Vec3(-1, 1, -1).normalized();
  const Vec3 up = (Vec3::UnitZ() - Vec3::UnitZ().dot(forward) * forward).normalized();
  return {forward.cross(up).normalized(), up, forward};
}

const char* view_name(ViewKind kind) {
  switch (kind) {
    case ViewKind::kTop:
      return "Top";
    case ViewKind::kFront:
      return "Front";
    case ViewKind::kSide:
      return "Side (right)";
    case ViewKind::kIsometric:
      return "Isometric";
  }
  return "?";
}

ViewProjection fit_view(const std::vector<Vec3>& points, ViewKind kind,
                        const ViewSettings& settings) {
  ViewProjection view;
  view.basis = view_basis(kind);
  view.width_px = std::max(settings.width_px, 1);
  view.height_px = std::max(settings.height_px, 1);
  if (points.empty()) return view;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double u_min = kInf, u_max = -kInf, v_min = kInf, v_max = -kInf;
  for (const auto& p : points) {
    const double u = p.dot(view.basis.right), v = p.dot(view.basis.up);
    if (!std::isfinite(u) || !std::isfinite(v)) continue;
    u_min = std::min(u_min, u);
    u_max = std::max(u_max, u);
    v_min = std::min(v_min, v);
    v_max = std::max(v_max, v);
  }
  if (u_min > u_max) return view;  // no finite point
  view.center_mm = {0.5 * (u_min + u_max), 0.5 * (v_min + v_max)};
  const double free_w = std::max(view.width_px - 2.0 * settings.margin_px, 1.0);
  const double free_h = std::max(view.height_px - 2.0 * settings.margin_px, 1.0);
  const double span_u = u_max - u_min, span_v = v_max - v_min;
  double scale = kInf;
  if (span_u > 0) scale = std::min(scale, free_w / span_u);
  if (span_v > 0) scale = std::min(scale, free_h / span_v);
  view.scale_px_per_mm = std::isfinite(scale) ? scale : 1.0;
  return view;
}

}  // namespace springscan::report
