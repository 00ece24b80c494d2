// Compensation vectors from the deformation field (compensation.hpp, docs/matching.md).
#include "analysis/matching/compensation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "analysis/core/kdtree.hpp"
#include "analysis/core/spacing.hpp"

namespace springscan::analysis {
namespace {

// A control point this close to a field point is that point (the k-center model points).
constexpr double kSamePointMm = 1e-9;

// The median distance from each field point to its nearest other field point: the sampling
// spacing of the reduced model (about the k-center radius w).
double median_spacing(const std::vector<Vec3>& points) {
  if (points.size() < 2) return 0.0;
  return median_neighbour_spacing(KdTree(points), points);
}

std::string validate(const std::vector<Vec3>& control, const CompensationSettings& s) {
  if (!std::isfinite(s.scale)) return "scale is not finite";
  if (!(s.max_magnitude_mm > 0.0) || !std::isfinite(s.max_magnitude_mm)) {
    return "max_magnitude_mm = " + std::to_string(s.max_magnitude_mm) + " (must be > 0)";
  }
  if (!(s.smoothing_radius_mm >= 0.0) || !std::isfinite(s.smoothing_radius_mm)) {
    return "smoothing_radius_mm = " + std::to_string(s.smoothing_radius_mm) + " (must be >= 0)";
  }
  for (std::size_t k = 0; k < control.size(); ++k) {
    if (!control[k].allFinite()) return "control point " + std::to_string(k) + " is not finite";
  }
  return {};
}

// Prints -0.0 as 0.0: the files are read by people and by CAM tools.
double clean(double x) { return x == 0.0 ? 0.0 : x; }

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

}  // namespace

Expected<Compensation> compensation(const DeformationField& field,
                                    const std::vector<Vec3>& control_points,
                                    const CompensationSettings& settings) {
  if (const std::string problem = validate(control_points, settings); !problem.empty()) {
    return fail("compensation: " + problem);
  }
  std::vector<Vec3> anchors;
  anchors.reserve(field.vectors.size());
  for (const auto& v : field.vectors) anchors.push_back(v.model);

  Compensation out;
  out.smoothing_radius_mm =
      settings.smoothing_radius_mm > 0.0 ? settings.smoothing_radius_mm : median_spacing(anchors);
  const double sigma = out.smoothing_radius_mm;
  const KdTree tree(anchors);
  std::vector<Neighbor> near;
  out.vectors.reserve(control_points.size());
  const KdTree uncovered(field.uncovered_points);
  for (const Vec3& x : control_points) {
    CompensationVector c;
    c.point = x;
    Vec3 sum = Vec3::Zero();
    double weight_sum = 0.0;
    const auto own = tree.nearest(x, kSamePointMm);
    if (own && field.refined) {
      // A control point of the refined field: its own vector, already smooth (a rigid motion
      // per flange plus an averaged normal offset); a Gaussian average would bend it at edges.
      sum = field.vectors[own->index].displacement();
      weight_sum = 1.0;
      c.support = 1;
    } else if (!uncovered.nearest(x, kSamePointMm)) {
      // sigma = 0 (a single field vector): only a coinciding point is supported.
      tree.radius(x, 3.0 * sigma, near);
      for (const Neighbor& n : near) {
        const double w = sigma > 0.0 ? std::exp(-n.squared_distance / (2.0 * sigma * sigma)) : 1.0;
        weight_sum += w;
        sum += w * field.vectors[n.index].displacement();
      }
      c.support = static_cast<int>(near.size());
    }
    c.supported = weight_sum > 0.0;
    if (c.supported) {
      c.deformation = sum / weight_sum;
      c.vector = -settings.scale * c.deformation;
      const double length = c.vector.norm();
      if (length > settings.max_magnitude_mm) {
        c.vector *= settings.max_magnitude_mm / length;
        c.clipped = true;
        ++out.clipped;
      }
      out.max_magnitude_mm = std::max(out.max_magnitude_mm, c.vector.norm());
    } else {
      ++out.unsupported;
    }
    out.vectors.push_back(c);
  }
  return out;
}

std::string format_compensation_csv(const Compensation& c) {
  std::string out = "x_mm,y_mm,z_mm,cx_mm,cy_mm,cz_mm,magnitude_mm,supported,clipped\n";
  char line[320];
  for (const auto& v : c.vectors) {
    const int n =
        std::snprintf(line, sizeof line, "%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%d,%d\n", v.point.x(),
                      v.point.y(), v.point.z(), clean(v.vector.x()), clean(v.vector.y()),
                      clean(v.vector.z()), v.vector.norm(), v.supported ? 1 : 0, v.clipped ? 1 : 0);
    out.append(line, static_cast<std::size_t>(std::clamp(n, 0, static_cast<int>(sizeof line) - 1)));
  }
  return out;
}

std::string format_compensation_ply(const Compensation& c) {
  char line[400];
  std::snprintf(line, sizeof line,
                "ply\nformat ascii 1.0\ncomment springscan compensation vectors, result frame, mm\n"
                "element vertex %zu\nproperty double x\nproperty double y\nproperty double z\n"
                "property float nx\nproperty float ny\nproperty float nz\nproperty float cx\n"
                "property float cy\nproperty float cz\nproperty float magnitude\nend_header\n",
                c.vectors.size());
  std::string out = line;
  for (const auto& v : c.vectors) {
    const double length = v.vector.norm();
    const Vec3 dir = length > 0.0 ? Vec3(v.vector / length) : Vec3::Zero();
    const int n = std::snprintf(
        line, sizeof line, "%.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f\n", v.point.x(),
        v.point.y(), v.point.z(), clean(dir.x()), clean(dir.y()), clean(dir.z()),
        clean(v.vector.x()), clean(v.vector.y()), clean(v.vector.z()), length);
    out.append(line, static_cast<std::size_t>(std::clamp(n, 0, static_cast<int>(sizeof line) - 1)));
  }
  return out;
}

namespace {

Expected<std::size_t> write_text(const std::string& path, const std::string& text,
                                 std::size_t rows) {
  const File f(std::fopen(path.c_str(), "w"));
  if (!f) return fail(path + ": cannot open for writing");
  std::fwrite(text.data(), 1, text.size(), f.get());
  if (std::ferror(f.get())) return fail(path + ": write failed");
  return rows;
}

}  // namespace

Expected<std::size_t> write_compensation_csv(const std::string& path, const Compensation& c) {
  return write_text(path, format_compensation_csv(c), c.vectors.size());
}

Expected<std::size_t> write_compensation_ply(const std::string& path, const Compensation& c) {
  return write_text(path, format_compensation_ply(c), c.vectors.size());
}

}  // namespace springscan::analysis
