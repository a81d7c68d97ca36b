#include "rail_track_node/sparse_cholesky.hpp"

#include <suitesparse/cholmod.h>

#include <cstring>
#include <stdexcept>
#include <string>

namespace rail {
namespace track {

struct SparseCholesky::Impl {
  cholmod_common common;
  cholmod_factor* L = nullptr;
  cholmod_dense B;             // header over the caller's right-hand side (no copy)
  cholmod_dense* X = nullptr;  // solution buffer, reused
  cholmod_dense* Y = nullptr;  // workspace, reused
  cholmod_dense* E = nullptr;  // workspace, reused
  int n = 0;
};

SparseCholesky::SparseCholesky(const Eigen::SparseMatrix<double>& A_in) : impl_(new Impl) {
  Impl& s = *impl_;
  if (A_in.rows() != A_in.cols())
    throw std::runtime_error("SparseCholesky: matrix is not square (" + std::to_string(A_in.rows()) + " x " +
                             std::to_string(A_in.cols()) + ")");
  s.n = static_cast<int>(A_in.rows());
  Eigen::SparseMatrix<double> A = A_in;  // compressed, column-major, int indices
  A.makeCompressed();

  cholmod_start(&s.common);
  // Supernodal L L': its cholmod_solve2 path reuses Y and E with no allocation. (The simplicial solve of
  // CHOLMOD 3.0 / SuiteSparse 5.12 allocates on every call.)
  s.common.supernodal = CHOLMOD_SUPERNODAL;

  cholmod_sparse view;
  std::memset(&view, 0, sizeof(view));
  view.nrow = A.rows();
  view.ncol = A.cols();
  view.nzmax = A.nonZeros();
  view.p = A.outerIndexPtr();
  view.i = A.innerIndexPtr();
  view.x = A.valuePtr();
  view.stype = 1;  // symmetric, upper triangle used
  view.itype = CHOLMOD_INT;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  view.sorted = 1;
  view.packed = 1;

  s.L = cholmod_analyze(&view, &s.common);
  if (!s.L || s.common.status < CHOLMOD_OK) {
    cholmod_finish(&s.common);
    throw std::runtime_error("SparseCholesky: cholmod_analyze failed (status " + std::to_string(s.common.status) + ")");
  }
  cholmod_factorize(&view, s.L, &s.common);
  if (s.common.status == CHOLMOD_NOT_POSDEF || s.L->minor < s.L->n) {
    const std::string msg = "SparseCholesky: matrix not positive definite (pivot " + std::to_string(s.L->minor) +
                            " of " + std::to_string(s.L->n) + ")";
    cholmod_free_factor(&s.L, &s.common);
    cholmod_finish(&s.common);
    throw std::runtime_error(msg);
  }
  if (s.common.status < CHOLMOD_OK) {
    const int status = s.common.status;
    cholmod_free_factor(&s.L, &s.common);
    cholmod_finish(&s.common);
    throw std::runtime_error("SparseCholesky: cholmod_factorize failed (status " + std::to_string(status) + ")");
  }

  std::memset(&s.B, 0, sizeof(s.B));
  s.B.nrow = s.n;
  s.B.ncol = 1;
  s.B.nzmax = s.n;
  s.B.d = s.n;
  s.B.xtype = CHOLMOD_REAL;
  s.B.dtype = CHOLMOD_DOUBLE;

  // Warm-up solve: allocates X, Y and E once.
  Eigen::VectorXd b = Eigen::VectorXd::Zero(s.n), x(s.n);
  solve(b, x);
}

SparseCholesky::~SparseCholesky() {
  Impl& s = *impl_;
  cholmod_free_dense(&s.X, &s.common);
  cholmod_free_dense(&s.Y, &s.common);
  cholmod_free_dense(&s.E, &s.common);
  cholmod_free_factor(&s.L, &s.common);
  cholmod_finish(&s.common);
}

void SparseCholesky::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  Impl& s = *impl_;
  s.B.x = const_cast<double*>(b.data());
  cholmod_solve2(CHOLMOD_A, s.L, &s.B, nullptr, &s.X, nullptr, &s.Y, &s.E, &s.common);
  x = Eigen::Map<const Eigen::VectorXd>(static_cast<const double*>(s.X->x), s.n);
}

int SparseCholesky::rows() const { return impl_->n; }

bool SparseCholesky::isSupernodal() const { return impl_->L->is_super != 0; }

double SparseCholesky::factorNonZeros() const { return impl_->common.lnz; }

}  // namespace track
}  // namespace rail
