#pragma once
// Eigen's solvers for the symmetric 6x6 systems of a rigid motion (three rotations, three
// translations) that the ICP step, the datum frame and the part-motion fit solve. A fixed-size
// 6x6 SelfAdjointEigenSolver or LDLT costs 10-35 s of compile time wherever it is instantiated
// (more under the sanitizers, and CI builds the project three times), so each is instantiated
// once, in small_solvers.cpp, and the stages call these functions.

#include <Eigen/Core>

namespace springscan::analysis {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

struct SymmetricEigen6 {
  Vec6 values;   ///< ascending
  Mat6 vectors;  ///< column k belongs to values(k); orthonormal
};

/// The eigenvalues and eigenvectors of the symmetric matrix `m` (its lower triangle is read).
SymmetricEigen6 symmetric_eigen(const Mat6& m);

/// x with m x = b for a symmetric positive (semi)definite `m`, by Eigen's LDLT (robust pivoting).
Vec6 ldlt_solve(const Mat6& m, const Vec6& b);

}  // namespace springscan::analysis
