// The LP-duality optimality certificate of a rectangular assignment (assignment.hpp, and
// docs/matching.md "Certificate"): primal feasibility, dual feasibility, complementary
// slackness. Weak duality then gives cost(x) = sum u + sum v <= cost of any other assignment.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "analysis/matching/assignment.hpp"

namespace springscan::analysis {
namespace {

std::string num(double x) {
  std::ostringstream out;
  out.precision(12);
  out << x;
  return out.str();
}

// Everything that does not depend on how edges are stored: shapes, a proper matching, the
// sign of v, v = 0 on unused columns and the duality gap. Fills `check.failure` on the first
// problem found.
void check_structure(std::size_t rows, std::size_t cols, const Assignment& a, double tolerance,
                     CertificateCheck& check) {
  if (a.row_to_col.size() != rows || a.col_to_row.size() != cols || a.u.size() != rows ||
      a.v.size() != cols) {
    check.failure = "assignment sizes do not match the problem";
    return;
  }
  for (std::size_t i = 0; i < rows; ++i) {
    const std::int32_t j = a.row_to_col[i];
    if (j < 0 || static_cast<std::size_t>(j) >= cols ||
        a.col_to_row[static_cast<std::size_t>(j)] != static_cast<std::int32_t>(i)) {
      check.failure = "primal: row " + std::to_string(i) + " is not properly matched";
      return;
    }
  }
  std::size_t used = 0;
  for (std::size_t j = 0; j < cols; ++j) {
    if (a.col_to_row[j] >= 0) ++used;
    if (a.v[j] > tolerance) {
      check.failure = "dual: v[" + std::to_string(j) + "] = " + num(a.v[j]) + " > 0";
      return;
    }
    if (a.col_to_row[j] < 0 && std::abs(a.v[j]) > tolerance) {
      check.failure = "slackness: unused column " + std::to_string(j) + " has v = " + num(a.v[j]);
      return;
    }
  }
  if (used != rows) {
    check.failure =
        "primal: " + std::to_string(used) + " columns used by " + std::to_string(rows) + " rows";
    return;
  }
  double dual_value = 0.0;
  for (const double x : a.u) dual_value += x;
  for (const double x : a.v) dual_value += x;
  check.duality_gap = std::abs(a.total_cost - dual_value);
  // The gap sums m rounding errors, so it gets m times the per-edge tolerance.
  if (check.duality_gap > tolerance * static_cast<double>(std::max<std::size_t>(rows, 1))) {
    check.failure = "duality gap " + num(check.duality_gap) + " (cost " + num(a.total_cost) +
                    ", dual " + num(dual_value) + ")";
  }
}

// Per-edge conditions; `matched` is true for the edge the assignment uses.
bool check_edge(std::size_t i, std::size_t j, double c, bool matched, const Assignment& a,
                double tolerance, CertificateCheck& check) {
  const double reduced = c - a.u[i] - a.v[j];
  check.max_dual_violation = std::max(check.max_dual_violation, -reduced);
  if (reduced < -tolerance) {
    check.failure = "dual: u[" + std::to_string(i) + "] + v[" + std::to_string(j) +
                    "] - c = " + num(-reduced) + " > 0";
    return false;
  }
  if (matched) {
    check.max_matched_slack = std::max(check.max_matched_slack, std::abs(reduced));
    if (std::abs(reduced) > tolerance) {
      check.failure = "slackness: matched edge (" + std::to_string(i) + ", " + std::to_string(j) +
                      ") has reduced cost " + num(reduced);
      return false;
    }
  }
  return true;
}

}  // namespace

CertificateCheck check_certificate(const DenseCostMatrix& cost, const Assignment& a,
                                   double tolerance) {
  CertificateCheck check;
  check_structure(cost.rows, cost.cols, a, tolerance, check);
  if (!check.failure.empty()) return check;
  for (std::size_t i = 0; i < cost.rows; ++i) {
    const auto matched = static_cast<std::size_t>(a.row_to_col[i]);
    for (std::size_t j = 0; j < cost.cols; ++j) {
      if (!check_edge(i, j, cost.at(i, j), j == matched, a, tolerance, check)) return check;
    }
  }
  check.ok = true;
  return check;
}

CertificateCheck check_certificate(const CandidateGraph& graph, const Assignment& a,
                                   double tolerance) {
  CertificateCheck check;
  if (graph.row_offsets.size() != graph.rows + 1) {
    check.failure = "graph: row_offsets has the wrong size";
    return check;
  }
  check_structure(graph.rows, graph.cols, a, tolerance, check);
  if (!check.failure.empty()) return check;
  for (std::size_t i = 0; i < graph.rows; ++i) {
    const auto matched = static_cast<std::size_t>(a.row_to_col[i]);
    // The matched pair must be an edge; with parallel edges its cheapest copy must be tight.
    double matched_cost = std::numeric_limits<double>::infinity();
    for (std::size_t e = graph.row_offsets[i]; e < graph.row_offsets[i + 1]; ++e) {
      const auto j = static_cast<std::size_t>(graph.col_index[e]);
      if (j == matched) matched_cost = std::min(matched_cost, graph.costs[e]);
      if (!check_edge(i, j, graph.costs[e], false, a, tolerance, check)) return check;
    }
    if (!std::isfinite(matched_cost)) {
      check.failure = "primal: row " + std::to_string(i) + " uses a column it has no edge to";
      return check;
    }
    if (!check_edge(i, matched, matched_cost, true, a, tolerance, check)) return check;
  }
  check.ok = true;
  return check;
}

}  // namespace springscan::analysis
