// Points onto the canonical faces that replace moved faces (compensated_internal.hpp
// onto_surfaces): the moved edges and vertices are put where their planes and cylinders meet.
#include <cmath>

#include "analysis/cad/compensated_internal.hpp"

namespace springscan::analysis::compensated {
namespace {

// Enough for two faces meeting at any angle a sheet part has; a flange and the bend it runs into
// meet tangentially, where the points converge slowly but start within the field's scatter.
constexpr int kRounds = 30;

// The foot of q on a plane or cylinder.
Vec3 foot(const FaceFit& fit, const Vec3& q) {
  const Vec3 w = q - fit.origin;
  if (fit.kind == "plane") return q - fit.z.dot(w) * fit.z;
  const Vec3 along = fit.z.dot(w) * fit.z, across = w - along;
  if (!(across.norm() > 0.0)) return q;
  return fit.origin + along + fit.radius * across.normalized();
}

}  // namespace

Vec3 onto_surfaces(const std::vector<const FaceFit*>& fits, Vec3 q) {
  if (fits.empty()) return q;
  // Alternating projections (von Neumann): they converge to the surfaces' common curve or point
  // where there is one.
  const int rounds = fits.size() == 1 ? 1 : kRounds;
  for (int k = 0; k < rounds; ++k)
    for (const FaceFit* fit : fits) q = foot(*fit, q);
  return q;
}

}  // namespace springscan::analysis::compensated
