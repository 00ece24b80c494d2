// Deformation field by nearest neighbour or by minimum-cost matching (paper section 5).
#include "analysis/matching/deformation_field.hpp"

#include <limits>
#include <string>

#include "analysis/core/kdtree.hpp"

namespace springscan::analysis {
namespace {

DeformationVector make_vector(const std::vector<Vec3>& model, const std::vector<Vec3>& scan,
                              std::size_t i, std::size_t j) {
  DeformationVector v;
  v.model_index = static_cast<std::uint32_t>(i);
  v.scan_index = static_cast<std::uint32_t>(j);
  v.model = model[i];
  v.scan = scan[j];
  v.squared_distance_mm2 = (scan[j] - model[i]).squaredNorm();
  return v;
}

double share(std::size_t part, std::size_t whole) {
  return whole == 0 ? 0.0 : static_cast<double>(part) / static_cast<double>(whole);
}

std::string first_non_finite(const std::vector<Vec3>& points, const char* name) {
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (!points[k].allFinite()) return std::string(name) + " point " + std::to_string(k);
  }
  return {};
}

}  // namespace

const char* to_string(CorrespondenceMethod method) {
  return method == CorrespondenceMethod::kNearestNeighbor ? "nearest_neighbor"
                                                          : "min_cost_matching";
}

std::vector<DeformationVector> nearest_neighbor_vectors(const std::vector<Vec3>& model,
                                                        const std::vector<Vec3>& scan) {
  std::vector<DeformationVector> out;
  if (model.empty() || scan.empty()) return out;
  // The ICP direction of the paper: data (scan) point -> nearest model point.
  const KdTree tree(model);
  std::vector<std::int64_t> best_scan(model.size(), -1);
  std::vector<double> best_d2(model.size(), std::numeric_limits<double>::infinity());
  for (std::size_t j = 0; j < scan.size(); ++j) {
    const auto nearest = tree.nearest(scan[j]);
    if (!nearest) continue;
    const std::size_t i = nearest->index;
    if (nearest->squared_distance < best_d2[i]) {  // ties keep the lowest scan index
      best_d2[i] = nearest->squared_distance;
      best_scan[i] = static_cast<std::int64_t>(j);
    }
  }
  for (std::size_t i = 0; i < model.size(); ++i) {
    if (best_scan[i] >= 0) {
      out.push_back(make_vector(model, scan, i, static_cast<std::size_t>(best_scan[i])));
    }
  }
  return out;
}

Expected<DeformationField> deformation_field(const std::vector<Vec3>& model,
                                             const std::vector<Vec3>& scan,
                                             const DeformationFieldSettings& settings) {
  for (const auto& problem : {first_non_finite(model, "model"), first_non_finite(scan, "scan")}) {
    if (!problem.empty()) return fail("deformation field: " + problem + " is not finite");
  }
  DeformationField field;
  field.method = settings.method;
  field.model_points = model.size();
  field.scan_points = scan.size();
  const auto nearest = nearest_neighbor_vectors(model, scan);
  field.nearest_neighbor_coverage = share(nearest.size(), model.size());

  if (settings.method == CorrespondenceMethod::kNearestNeighbor) {
    field.vectors = nearest;
  } else {
    auto matched = match_points(model, scan, settings.matching);
    if (!matched.ok()) return matched.error().prepend("deformation field: ");
    field.matching = std::move(matched).value();
    field.optimality_certified = field.matching.certified;
    for (std::size_t i = 0; i < model.size(); ++i) {
      const std::int32_t j = field.matching.model_to_scan[i];
      if (j >= 0) field.vectors.push_back(make_vector(model, scan, i, static_cast<std::size_t>(j)));
    }
  }
  field.coverage = share(field.vectors.size(), model.size());
  for (const auto& v : field.vectors) field.total_cost_mm2 += v.squared_distance_mm2;
  return field;
}

}  // namespace springscan::analysis
