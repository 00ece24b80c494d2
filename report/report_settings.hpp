#pragma once
// Settings of the HTML inspection report. Defaults work as they are.

#include <cstddef>
#include <cstdint>
#include <string>

namespace springscan::report {

struct ReportSettings {
  std::size_t max_points = 100'000;  ///< points drawn in the pictures (random, fixed seed)
  std::uint32_t seed = 1;            ///< seed of that subsample: same report, same pictures
  int view_width_px = 560;           ///< size of each rendered view
  int view_height_px = 400;
  int splat_radius_px = 0;         ///< each point is a (2r+1)^2 pixel square; 0: from the
                                   ///< point spacing, so that surfaces close
  double shading = 0.35;           ///< depth-slope shading of the views, 0 = flat colours
  double color_scale_mm = 0.0;     ///< |deviation| shown full blue/red; 0: the report's
                                   ///< deviation.color_scale_mm, else 3 x tolerance, else
                                   ///< 1 mm (the rule deviation.ply is coloured by)
  int max_bend_labels = 100;       ///< bend axes drawn on the picture (all stay in the table)
  std::size_t max_arrows = 300;    ///< compensation arrows drawn (random subset beyond)
  int png_compression_level = 3;   ///< zlib level of the embedded PNGs, 0..9 (3: within 4 %
                                   ///< of level 6's size at 2/3 of its time)
  int threads = 0;                 ///< views rendered at once; 0 = hardware_concurrency.
                                   ///< The page is the same byte for byte for any count.
  std::string missing_cloud_note;  ///< why there is no deviation cloud, shown in its place
};

}  // namespace springscan::report
