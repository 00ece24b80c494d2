#pragma once
// Minimum-cost one-to-one matching between two point sets (paper section 5, equation (3)):
// every point of the smaller set gets a distinct partner in the larger set, minimising the sum
// of squared Euclidean distances. Exact over ALL pairs, not only over a candidate graph: the
// result carries dual potentials whose certificate is checked against every pair that could
// violate it (docs/matching.md "Global certificate").
//
// Thread safety: pure functions.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "analysis/core/expected.hpp"
#include "analysis/core/point_cloud.hpp"
#include "analysis/matching/assignment.hpp"

namespace springscan::analysis {

struct PointMatchingSettings {
  int candidate_neighbors = 32;      ///< k of the k-nearest candidate graph (sparse solver)
  int dense_limit = 1000;            ///< larger sets (max of both sizes) use the sparse solver
  int max_widening_rounds = 4;       ///< k doubles per round while no perfect matching exists
  int max_pricing_rounds = 8;        ///< rounds adding certificate-violating pairs to the graph
  double relative_tolerance = 1e-9;  ///< certificate tolerance, x the largest matched cost
};

/// How a matching was obtained, and its proof.
struct PointMatching {
  /// Rows are the smaller set: true when rows are the model points (|model| <= |scan|).
  bool rows_are_model = true;
  Assignment assignment;                    ///< rows -> columns, with duals u (rows), v (columns)
  std::vector<std::int32_t> model_to_scan;  ///< scan index per model point, -1 if unmatched
  double total_cost = 0.0;                  ///< sum of squared distances, mm^2
  bool used_dense = false;                  ///< the dense solver ran (small, or fallback)
  int candidate_neighbors = 0;              ///< final k of the candidate graph (sparse)
  int widening_rounds = 0;                  ///< times k was doubled for feasibility
  int pricing_rounds = 0;                   ///< times violating pairs were added
  std::size_t candidate_edges = 0;          ///< edges of the final candidate graph
  bool certified = false;                   ///< the global certificate checked out
  CertificateCheck certificate;             ///< numbers of that check
};

/// Matches `model` and `scan` (mm). Small sets go to the dense solver; larger ones to the
/// sparse solver on a k-nearest graph, widened until Hopcroft-Karp finds a perfect matching,
/// then priced out against the global certificate; the dense point solver is the last
/// fallback, so the answer is always exact. Errors: a non-finite coordinate; bad settings.
Expected<PointMatching> match_points(const std::vector<Vec3>& model, const std::vector<Vec3>& scan,
                                     const PointMatchingSettings& settings = {});

/// The certificate of `assignment` (rows -> cols, squared distances) over ALL row/column
/// pairs. Dual feasibility for row i is u_i <= min_j |p_i - q_j|^2 - v_j: with v_j <= 0 that is
/// a nearest-neighbour query among the points (q_j, sqrt(-v_j)) lifted to 4-D, O(log n) per
/// row instead of n pairs.
CertificateCheck check_point_certificate(const std::vector<Vec3>& rows,
                                         const std::vector<Vec3>& cols,
                                         const Assignment& assignment, double tolerance);

}  // namespace springscan::analysis
