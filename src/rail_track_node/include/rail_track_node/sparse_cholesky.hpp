// Cholesky factorisation A = L L' of a sparse symmetric positive definite matrix with SuiteSparse CHOLMOD,
// factorised once; repeated solves reuse preallocated CHOLMOD workspace (no allocation per solve).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>

namespace rail {
namespace track {

class SparseCholesky {
 public:
  /// Analyses and factorises A (only its upper triangle is read). Throws std::runtime_error naming the
  /// failing column if A is not positive definite.
  explicit SparseCholesky(const Eigen::SparseMatrix<double>& A);
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  /// x = A^{-1} b (sizes must equal rows()). No allocation: b is passed to CHOLMOD without copy and the
  /// solution and workspace buffers allocated at construction are reused (cholmod_solve2).
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);

  int rows() const;
  bool isSupernodal() const;
  /// Non-zeros of the factor L.
  double factorNonZeros() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace track
}  // namespace rail
