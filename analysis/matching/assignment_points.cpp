// Point-set matching driver: dense for small sets, sparse on a k-nearest candidate graph with
// Hopcroft-Karp widening and certificate pricing for large ones (docs/matching.md).
#include "analysis/matching/assignment_points.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "analysis/core/kdtree.hpp"

namespace springscan::analysis {
namespace {

using Edge = std::pair<std::int32_t, std::int32_t>;  // (row, column)

// The graph of each row's k nearest columns plus `extra` edges (sorted by row).
CandidateGraph knn_graph(const std::vector<Vec3>& rows, const KdTree& tree, std::size_t k,
                         const std::vector<Edge>& extra) {
  CandidateGraph g;
  g.rows = rows.size();
  g.cols = tree.size();
  g.row_offsets.reserve(g.rows + 1);
  g.row_offsets.push_back(0);
  g.col_index.reserve(g.rows * k + extra.size());
  g.costs.reserve(g.rows * k + extra.size());
  std::vector<std::uint32_t> idx(k);
  std::vector<double> d2(k);
  std::size_t next_extra = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::size_t found = tree.knn(rows[i], k, idx.data(), d2.data());
    for (std::size_t t = 0; t < found; ++t) {
      g.col_index.push_back(static_cast<std::int32_t>(idx[t]));
      g.costs.push_back(d2[t]);
    }
    for (; next_extra < extra.size() && extra[next_extra].first == static_cast<std::int32_t>(i);
         ++next_extra) {
      const auto j = extra[next_extra].second;
      g.col_index.push_back(j);
      g.costs.push_back((rows[i] - tree.points()[static_cast<std::size_t>(j)]).squaredNorm());
    }
    g.row_offsets.push_back(g.col_index.size());
  }
  return g;
}

// The certificate over all pairs: the structural part and slackness through the graph of the
// matched pairs; dual feasibility u_i <= min_j (c_ij - v_j) by one additively weighted nearest
// neighbour query per row, with weights -v_j >= 0 (docs/matching.md "Global certificate").
// Violating pairs are appended to `violations` if given.
CertificateCheck scan_certificate(const std::vector<Vec3>& rows, const KdTree& tree,
                                  const Assignment& a, double tolerance,
                                  std::vector<Edge>* violations) {
  CandidateGraph matched{rows.size(), tree.size(), {0}, {}, {}};
  if (a.row_to_col.size() == rows.size()) {
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const std::int32_t j = a.row_to_col[i];
      if (j >= 0 && static_cast<std::size_t>(j) < tree.size()) {
        matched.col_index.push_back(j);
        matched.costs.push_back(
            (rows[i] - tree.points()[static_cast<std::size_t>(j)]).squaredNorm());
      }
      matched.row_offsets.push_back(matched.col_index.size());
    }
  }
  CertificateCheck check = check_certificate(matched, a, tolerance);
  if (!check.ok || rows.empty()) return check;
  // v_j <= tolerance was checked above; clamp the rounding noise so the weights are >= 0.
  std::vector<double> weights(a.v.size());
  for (std::size_t j = 0; j < a.v.size(); ++j) weights[j] = std::max(0.0, -a.v[j]);
  const WeightedKdTree weighted(tree.points(), weights);
  std::vector<Neighbor> below;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto best = weighted.nearest(rows[i]);
    const double violation = best ? a.u[i] - best->squared_distance : 0.0;
    check.max_dual_violation = std::max(check.max_dual_violation, violation);
    if (violation <= tolerance) continue;
    if (check.ok) {
      check.ok = false;
      check.failure = "dual: pair (" + std::to_string(i) + ", " + std::to_string(best->index) +
                      ") violates u + v <= c by " + std::to_string(violation);
    }
    if (violations == nullptr) return check;
    weighted.below(rows[i], a.u[i] - tolerance, below);
    for (const Neighbor& nb : below) {
      violations->emplace_back(static_cast<std::int32_t>(i), static_cast<std::int32_t>(nb.index));
    }
  }
  return check;
}

// Absolute certificate tolerance: relative to the magnitude of the potentials, which bounds
// the rounding error accumulated by the dual updates.
double tolerance_for(const Assignment& a, double relative) {
  double scale = 1.0;
  for (const double x : a.u) scale = std::max(scale, std::abs(x));
  for (const double x : a.v) scale = std::max(scale, std::abs(x));
  return relative * scale;
}

// Sparse path: widen until feasible, then solve and price until the global certificate holds.
// Returns false when the caller should fall back to the dense solver.
bool solve_sparse_priced(const std::vector<Vec3>& rows, const KdTree& tree,
                         const PointMatchingSettings& s, PointMatching& out) {
  std::size_t k =
      std::min<std::size_t>(static_cast<std::size_t>(s.candidate_neighbors), tree.size());
  CandidateGraph graph = knn_graph(rows, tree, k, {});
  std::vector<std::int32_t> matching(rows.size(), -1);  // carried over: k only grows
  while (maximum_matching(graph, matching) < rows.size()) {
    if (out.widening_rounds >= s.max_widening_rounds || k >= tree.size()) return false;
    ++out.widening_rounds;
    k = std::min(2 * k, tree.size());
    graph = knn_graph(rows, tree, k, {});
  }
  out.candidate_neighbors = static_cast<int>(k);
  std::vector<Edge> extra;
  while (true) {
    auto solved = solve_sparse(graph);
    if (!solved.ok()) return false;
    out.assignment = std::move(solved).value();
    out.candidate_edges = graph.edge_count();
    std::vector<Edge> violations;
    const double tol = tolerance_for(out.assignment, s.relative_tolerance);
    out.certificate = scan_certificate(rows, tree, out.assignment, tol, &violations);
    if (out.certificate.ok) return true;
    if (violations.empty() || out.pricing_rounds >= s.max_pricing_rounds) return false;
    ++out.pricing_rounds;
    extra.insert(extra.end(), violations.begin(), violations.end());
    std::sort(extra.begin(), extra.end());
    extra.erase(std::unique(extra.begin(), extra.end()), extra.end());
    graph = knn_graph(rows, tree, k, extra);
  }
}

std::string validate(const std::vector<Vec3>& model, const std::vector<Vec3>& scan,
                     const PointMatchingSettings& s) {
  for (const auto* set : {&model, &scan}) {
    for (std::size_t k = 0; k < set->size(); ++k) {
      if (!(*set)[k].allFinite()) {
        return std::string(set == &model ? "model" : "scan") + " point " + std::to_string(k) +
               " is not finite";
      }
    }
  }
  if (s.candidate_neighbors < 1) {
    return "candidate_neighbors = " + std::to_string(s.candidate_neighbors) + " (must be >= 1)";
  }
  if (s.dense_limit < 0 || s.max_widening_rounds < 0 || s.max_pricing_rounds < 0) {
    return "dense_limit, max_widening_rounds and max_pricing_rounds must be >= 0";
  }
  if (!(s.relative_tolerance > 0.0)) return "relative_tolerance must be > 0";
  return {};
}

}  // namespace

Expected<PointMatching> match_points(const std::vector<Vec3>& model, const std::vector<Vec3>& scan,
                                     const PointMatchingSettings& settings) {
  if (const std::string problem = validate(model, scan, settings); !problem.empty()) {
    return fail("matching: " + problem);
  }
  PointMatching out;
  out.rows_are_model = model.size() <= scan.size();
  const std::vector<Vec3>& rows = out.rows_are_model ? model : scan;
  const KdTree tree(out.rows_are_model ? scan : model);

  const std::size_t largest = std::max(model.size(), scan.size());
  const bool sparse = largest > static_cast<std::size_t>(settings.dense_limit);
  if (!sparse || !solve_sparse_priced(rows, tree, settings, out)) {
    auto solved = solve_dense_points(rows, tree.points());
    if (!solved.ok()) return solved.error().prepend("matching: ");
    out.assignment = std::move(solved).value();
    out.used_dense = true;
    const double tol = tolerance_for(out.assignment, settings.relative_tolerance);
    out.certificate = scan_certificate(rows, tree, out.assignment, tol, nullptr);
  }
  out.certified = out.certificate.ok;
  out.total_cost = out.assignment.total_cost;
  if (out.rows_are_model) {
    out.model_to_scan = out.assignment.row_to_col;
  } else {
    out.model_to_scan = out.assignment.col_to_row;
  }
  return out;
}

CertificateCheck check_point_certificate(const std::vector<Vec3>& rows,
                                         const std::vector<Vec3>& cols,
                                         const Assignment& assignment, double tolerance) {
  const KdTree tree(cols);
  return scan_certificate(rows, tree, assignment, tolerance, nullptr);
}

}  // namespace springscan::analysis
