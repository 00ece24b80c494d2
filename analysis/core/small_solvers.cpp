#include "analysis/core/small_solvers.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace springscan::analysis {

SymmetricEigen6 symmetric_eigen(const Mat6& m) {
  const Eigen::SelfAdjointEigenSolver<Mat6> solver(m);
  return {solver.eigenvalues(), solver.eigenvectors()};
}

Vec6 ldlt_solve(const Mat6& m, const Vec6& b) { return m.ldlt().solve(b); }

}  // namespace springscan::analysis
