#pragma once
// The pictures of the HTML report: deviation colour maps from the standard views, the bends
// labelled on a view, and the compensation vectors as arrows. Each is an inline <svg> holding
// the rendered raster as a data: URI PNG plus vector overlays, so the page needs no file.

#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"
#include "proto/springscan.pb.h"
#include "report/png.hpp"
#include "report/report_settings.hpp"
#include "report/view.hpp"

namespace springscan::report {

/// The reduced cloud the pictures are drawn from: at most settings.max_points points with
/// their deviation colours and a neutral grey for the pictures that carry overlays.
struct DrawCloud {
  std::vector<Vec3> points;
  std::vector<Rgb> deviation_colors;
  std::vector<Rgb> grey_colors;
  double spacing_mm = 0.0;  ///< typical distance between neighbouring drawn points (0: unknown)
};

/// The typical spacing of points spread over a surface: sqrt(area / count), with the area
/// estimated as the number of occupied voxels (edge 1/150 of the bounding-box diagonal) times
/// the voxel face. Splats of about this size close the surface without smearing it.
double surface_spacing_mm(const std::vector<Vec3>& points);

/// Subsamples `cloud` and colours it: scalars (signed deviation, mm) on +-scale_mm, else the
/// cloud's own colours, else grey.
DrawCloud make_draw_cloud(const analysis::PointCloud& cloud, double scale_mm,
                          const ReportSettings& settings);

/// An <svg> of the view's size holding the points rendered as a PNG (data: URI), an x/y/z
/// triad and `overlay` (SVG elements in pixel coordinates of the view). `label` is the
/// accessible name; spacing_mm sizes the splats when settings.splat_radius_px is 0.
/// Errors: PNG encoding failed.
analysis::Expected<std::string> view_svg(const std::vector<Vec3>& points,
                                         const std::vector<Rgb>& colors, double spacing_mm,
                                         const ViewProjection& view, const ReportSettings& settings,
                                         const std::string& overlay, const std::string& label);

/// Four <figure>s (top, front, side, isometric) coloured by deviation, with each measured free
/// edge of `report` (segments[].edge_deviation_mm) drawn as two lines: the CAD edge and the
/// scan's edge.
analysis::Expected<std::string> deviation_views_html(const v1::InspectionReport& report,
                                                     const DrawCloud& cloud,
                                                     const ReportSettings& settings);

/// The isometric view with every bend axis drawn and labelled "B<id>" in its verdict colour.
analysis::Expected<std::string> bends_figure_html(const v1::InspectionReport& report,
                                                  const DrawCloud& cloud,
                                                  const ReportSettings& settings);

/// The standard view in which the compensation vectors show longest, with the vectors as
/// arrows (scaled up, the factor stated). Without a cloud, the arrows alone.
analysis::Expected<std::string> compensation_figure_html(const v1::InspectionReport& report,
                                                         const DrawCloud& cloud,
                                                         const ReportSettings& settings);

/// The view a bend axis is drawn in and its end points: the stretch of the axis line that
/// lies along the points near it (within max(3 r, 5 % of the part size)); a fixed-length
/// stretch around axis_point when no point is near.
std::pair<Vec3, Vec3> bend_axis_extent(const v1::Bend& bend, const std::vector<Vec3>& points);

}  // namespace springscan::report
