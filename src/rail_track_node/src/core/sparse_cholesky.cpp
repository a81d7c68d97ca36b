#include "rail_track_node/sparse_cholesky.hpp"

#include <suitesparse/cholmod.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace rail {
namespace track {

struct SparseCholesky::Impl {
  cholmod_common common;
  cholmod_factor* L = nullptr;
  CholeskyLayout layout = CholeskyLayout::kSimplicial;
  int n = 0;
  // Supernodal: CHOLMOD's solve with reused buffers.
  cholmod_dense B;             // header over the caller's right-hand side (no copy)
  cholmod_dense* X = nullptr;  // solution buffer, reused
  cholmod_dense* Y = nullptr;  // workspace, reused
  cholmod_dense* E = nullptr;  // workspace, reused
  // Simplicial: L of P A P' = L L' copied packed, column-major, diagonal first in each column and stored as
  // its reciprocal (the solves' chain of dependent steps then multiplies where it would divide).
  std::vector<int> perm;       // row k of P A P' is row perm[k] of A
  std::vector<int> col_start;  // n + 1
  std::vector<int> row;        // row index of each entry
  std::vector<double> value;   // entry
  // The same L by rows (diagonal last, as its reciprocal): the forward solve gathers instead of scattering.
  std::vector<int> l_row_start;  // n + 1
  std::vector<int> l_col;        // column index of each entry
  std::vector<double> l_value;   // entry
  std::vector<double> y;         // permuted solution, reused
  std::vector<int> inverse;      // row of P A P' that holds row i of A
  std::vector<double> y_many;    // solveUnitColumns: rows x kMaxUnitColumns, row-major
  // kSimplicialTwoParts: rows [0, part_end[0]) and [part_end[0], part_end[1]) of P A P' are the two
  // independent parts, [part_end[1], n) the separator.
  int part_end[2] = {0, 0};
  Eigen::VectorXd unit_b, unit_x;  // supernodal solveUnitColumns: one unit right-hand side and its solution
};

SparseCholesky::SparseCholesky(const Eigen::SparseMatrix<double>& A_in, CholeskyLayout layout) : impl_(new Impl) {
  Impl& s = *impl_;
  if (A_in.rows() != A_in.cols())
    throw std::runtime_error("SparseCholesky: matrix is not square (" + std::to_string(A_in.rows()) + " x " +
                             std::to_string(A_in.cols()) + ")");
  s.n = static_cast<int>(A_in.rows());
  s.layout = layout;
  Eigen::SparseMatrix<double> A = A_in;  // compressed, column-major, int indices
  A.makeCompressed();

  cholmod_start(&s.common);
  s.common.supernodal = layout == CholeskyLayout::kSupernodal ? CHOLMOD_SUPERNODAL : CHOLMOD_SIMPLICIAL;
  s.common.final_ll = 1;  // simplicial: L L', not L D L'

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

  std::vector<int> given;  // kSimplicialTwoParts: the ordering
  if (layout == CholeskyLayout::kSimplicialTwoParts) {
    // Rows below n/2 are part 0, the others part 1, except those of part 1 coupled to part 0: the
    // separator (constraint set 2, ordered last). CAMD orders within each set.
    const int half = s.n / 2;
    std::vector<int> member(static_cast<std::size_t>(s.n), 0);
    for (int i = half; i < s.n; ++i) member[static_cast<std::size_t>(i)] = 1;
    for (int j = 0; j < s.n; ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it) {
        const int i = static_cast<int>(it.row());
        if ((i < half) != (j < half)) member[static_cast<std::size_t>(std::max(i, j))] = 2;
      }
    const int separator = static_cast<int>(std::count(member.begin(), member.end(), 2));
    s.part_end[0] = half;
    s.part_end[1] = s.n - separator;
    given.resize(static_cast<std::size_t>(s.n));
    bool ordered = cholmod_camd(&view, nullptr, 0, member.data(), given.data(), &s.common) != 0;
    for (int k = 0; k < s.n && ordered; ++k)  // set 0, then set 1, then the separator
      ordered = member[static_cast<std::size_t>(given[static_cast<std::size_t>(k)])] == (k < s.part_end[0]   ? 0
                                                                                         : k < s.part_end[1] ? 1
                                                                                                             : 2);
    if (!ordered) {
      cholmod_finish(&s.common);
      throw std::runtime_error("SparseCholesky: cholmod_camd did not order the two parts and the separator");
    }
    s.common.nmethods = 1;
    s.common.method[0].ordering = CHOLMOD_GIVEN;
    s.common.postorder = 0;  // keep the parts contiguous
  }
  s.L =
      given.empty() ? cholmod_analyze(&view, &s.common) : cholmod_analyze_p(&view, given.data(), nullptr, 0, &s.common);
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

  if (layout != CholeskyLayout::kSupernodal) {
    if (s.L->is_super || !s.L->is_ll || s.L->xtype != CHOLMOD_REAL) {
      cholmod_free_factor(&s.L, &s.common);
      cholmod_finish(&s.common);
      throw std::runtime_error("SparseCholesky: CHOLMOD did not return a simplicial real L L' factor");
    }
    const int* Lp = static_cast<const int*>(s.L->p);
    const int* Li = static_cast<const int*>(s.L->i);
    const int* Lnz = static_cast<const int*>(s.L->nz);
    const double* Lx = static_cast<const double*>(s.L->x);
    const int* P = static_cast<const int*>(s.L->Perm);
    s.perm.resize(static_cast<std::size_t>(s.n));
    s.col_start.resize(static_cast<std::size_t>(s.n) + 1);
    std::size_t nnz = 0;
    for (int j = 0; j < s.n; ++j) nnz += static_cast<std::size_t>(Lnz[j]);
    s.row.resize(nnz);
    s.value.resize(nnz);
    std::size_t k = 0;
    for (int j = 0; j < s.n; ++j) {
      s.perm[static_cast<std::size_t>(j)] = P ? P[j] : j;
      s.col_start[static_cast<std::size_t>(j)] = static_cast<int>(k);
      if (Lnz[j] < 1 || Li[Lp[j]] != j)
        throw std::runtime_error("SparseCholesky: column " + std::to_string(j) +
                                 " of L does not start at its diagonal");
      for (int p = Lp[j]; p < Lp[j] + Lnz[j]; ++p, ++k) {
        s.row[k] = Li[p];
        s.value[k] = p == Lp[j] ? 1.0 / Lx[p] : Lx[p];
      }
    }
    s.col_start[static_cast<std::size_t>(s.n)] = static_cast<int>(k);
    s.l_row_start.assign(static_cast<std::size_t>(s.n) + 1, 0);
    for (std::size_t q = 0; q < nnz; ++q) ++s.l_row_start[static_cast<std::size_t>(s.row[q]) + 1];
    for (int i = 0; i < s.n; ++i)
      s.l_row_start[static_cast<std::size_t>(i) + 1] += s.l_row_start[static_cast<std::size_t>(i)];
    s.l_col.resize(nnz);
    s.l_value.resize(nnz);
    std::vector<int> next(s.l_row_start.begin(), s.l_row_start.end() - 1);
    for (int j = 0; j < s.n; ++j)  // ascending columns: each row's entries end with its diagonal
      for (int q = s.col_start[static_cast<std::size_t>(j)]; q < s.col_start[static_cast<std::size_t>(j) + 1]; ++q) {
        const int at = next[static_cast<std::size_t>(s.row[static_cast<std::size_t>(q)])]++;
        s.l_col[static_cast<std::size_t>(at)] = j;
        s.l_value[static_cast<std::size_t>(at)] = s.value[static_cast<std::size_t>(q)];
      }
    s.y.assign(static_cast<std::size_t>(s.n), 0.0);
    s.inverse.assign(static_cast<std::size_t>(s.n), 0);
    for (int j = 0; j < s.n; ++j) s.inverse[static_cast<std::size_t>(s.perm[static_cast<std::size_t>(j)])] = j;
    s.y_many.assign(static_cast<std::size_t>(s.n) * kMaxUnitColumns, 0.0);
    if (!given.empty()) {
      // The parts must not meet in L: no row of part 1 reads a column of part 0.
      for (int i = s.part_end[0]; i < s.part_end[1]; ++i)
        for (int q = s.l_row_start[static_cast<std::size_t>(i)]; q < s.l_row_start[static_cast<std::size_t>(i) + 1];
             ++q)
          if (s.l_col[static_cast<std::size_t>(q)] < s.part_end[0]) {
            cholmod_free_factor(&s.L, &s.common);
            cholmod_finish(&s.common);
            throw std::runtime_error("SparseCholesky: the two parts of the ordering are coupled in L (row " +
                                     std::to_string(i) + ")");
          }
    }
    return;
  }
  s.unit_b = Eigen::VectorXd::Zero(s.n);
  s.unit_x = Eigen::VectorXd::Zero(s.n);

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

namespace {
// first - sum of value[p] y[index[p]] over p in [begin, end), in four partial sums: a triangular solve is
// bound by the latency of these additions.
inline double minusDot(double first, const double* value, const int* index, int begin, int end,
                       const double* y) noexcept {
  double sum0 = first, sum1 = 0.0, sum2 = 0.0, sum3 = 0.0;
  int p = begin;
  for (; p + 3 < end; p += 4) {
    sum0 -= value[p] * y[index[p]];
    sum1 -= value[p + 1] * y[index[p + 1]];
    sum2 -= value[p + 2] * y[index[p + 2]];
    sum3 -= value[p + 3] * y[index[p + 3]];
  }
  for (; p < end; ++p) sum0 -= value[p] * y[index[p]];
  return (sum0 + sum1) + (sum2 + sum3);
}
}  // namespace

void SparseCholesky::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  Impl& s = *impl_;
  if (s.layout == CholeskyLayout::kSupernodal) {
    s.B.x = const_cast<double*>(b.data());
    cholmod_solve2(CHOLMOD_A, s.L, &s.B, nullptr, &s.X, nullptr, &s.Y, &s.E, &s.common);
    x = Eigen::Map<const Eigen::VectorXd>(static_cast<const double*>(s.X->x), s.n);
    return;
  }
  if (x.size() != s.n) x.resize(s.n);
  forwardRows(s, b, 0, s.n);
  backwardRows(s, x, 0, s.n);
}

// L y = P b over rows [begin, end), each unknown a dot product with its row (rows before begin that it reads
// are solved).
void SparseCholesky::forwardRows(Impl& s, const Eigen::VectorXd& b, int begin, int end) noexcept {
  const int* perm = s.perm.data();
  const int* row_start = s.l_row_start.data();
  const int* col = s.l_col.data();
  const double* l_value = s.l_value.data();
  double* y = s.y.data();
  for (int i = begin; i < end; ++i) {
    const int diag = row_start[i + 1] - 1;
    y[i] = minusDot(b[perm[i]], l_value, col, row_start[i], diag, y) * l_value[diag];
  }
}

// L' z = y over rows [begin, end), descending, each a dot product with its column (rows after it that it
// reads are solved); then x = P' z over those rows.
void SparseCholesky::backwardRows(Impl& s, Eigen::VectorXd& x, int begin, int end) noexcept {
  const int* perm = s.perm.data();
  const int* start = s.col_start.data();
  const int* row = s.row.data();
  const double* value = s.value.data();
  double* y = s.y.data();
  for (int j = end - 1; j >= begin; --j)
    y[j] = minusDot(y[j], value, row, start[j] + 1, start[j + 1], y) * value[start[j]];
  for (int k = begin; k < end; ++k) x[perm[k]] = y[k];
}

void SparseCholesky::forwardPart(int part, const Eigen::VectorXd& b) noexcept {
  Impl& s = *impl_;
  forwardRows(s, b, part == 0 ? 0 : s.part_end[0], s.part_end[part]);
}

void SparseCholesky::solveSeparator(const Eigen::VectorXd& b, Eigen::VectorXd& x) noexcept {
  Impl& s = *impl_;
  forwardRows(s, b, s.part_end[1], s.n);
  backwardRows(s, x, s.part_end[1], s.n);
}

void SparseCholesky::backwardPart(int part, Eigen::VectorXd& x) noexcept {
  Impl& s = *impl_;
  backwardRows(s, x, part == 0 ? 0 : s.part_end[0], s.part_end[part]);
}

int SparseCholesky::partRows(int part) const {
  const Impl& s = *impl_;
  if (s.layout != CholeskyLayout::kSimplicialTwoParts) return 0;
  return part == 0 ? s.part_end[0] : s.part_end[1] - s.part_end[0];
}

int SparseCholesky::separatorRows() const {
  const Impl& s = *impl_;
  return s.layout == CholeskyLayout::kSimplicialTwoParts ? s.n - s.part_end[1] : 0;
}

// solveUnitColumns on the simplicial factor with K right-hand sides, rows interleaved (y[i * K + c]) so
// that each factor entry is read once for all of them.
template <int K>
void SparseCholesky::unitColumns(Impl& s, const int* unit, Eigen::MatrixXd& x) {
  const int n = s.n;
  const int* start = s.col_start.data();
  const int* row = s.row.data();
  const double* value = s.value.data();
  double* y = s.y_many.data();
  std::fill(y, y + static_cast<std::ptrdiff_t>(n) * K, 0.0);
  for (int c = 0; c < K; ++c)
    y[static_cast<std::ptrdiff_t>(s.inverse[static_cast<std::size_t>(unit[c])]) * K + c] = 1.0;
  for (int j = 0; j < n; ++j) {
    double* yj = y + static_cast<std::ptrdiff_t>(j) * K;
    const double inv_d = value[start[j]];
    for (int c = 0; c < K; ++c) yj[c] *= inv_d;
    for (int p = start[j] + 1; p < start[j + 1]; ++p) {
      double* yi = y + static_cast<std::ptrdiff_t>(row[p]) * K;
      const double l = value[p];
      for (int c = 0; c < K; ++c) yi[c] -= l * yj[c];
    }
  }
  for (int j = n - 1; j >= 0; --j) {
    double* yj = y + static_cast<std::ptrdiff_t>(j) * K;
    double sum0[K], sum1[K];
    for (int c = 0; c < K; ++c) {
      sum0[c] = yj[c];
      sum1[c] = 0.0;
    }
    int p = start[j] + 1;
    const int end = start[j + 1];
    for (; p + 1 < end; p += 2) {
      const double* y0 = y + static_cast<std::ptrdiff_t>(row[p]) * K;
      const double* y1 = y + static_cast<std::ptrdiff_t>(row[p + 1]) * K;
      const double l0 = value[p], l1 = value[p + 1];
      for (int c = 0; c < K; ++c) {
        sum0[c] -= l0 * y0[c];
        sum1[c] -= l1 * y1[c];
      }
    }
    if (p < end) {
      const double* y0 = y + static_cast<std::ptrdiff_t>(row[p]) * K;
      for (int c = 0; c < K; ++c) sum0[c] -= value[p] * y0[c];
    }
    const double inv_d = value[start[j]];
    for (int c = 0; c < K; ++c) yj[c] = (sum0[c] + sum1[c]) * inv_d;
  }
  for (int i = 0; i < n; ++i) {
    const double* yi = y + static_cast<std::ptrdiff_t>(i) * K;
    const int r = s.perm[static_cast<std::size_t>(i)];
    for (int c = 0; c < K; ++c) x(r, c) = yi[c];
  }
}

void SparseCholesky::solveUnitColumns(const int* unit, int count, Eigen::MatrixXd& x) {
  Impl& s = *impl_;
  if (s.layout == CholeskyLayout::kSupernodal) {
    for (int c = 0; c < count; ++c) {
      s.unit_b(unit[c]) = 1.0;
      solve(s.unit_b, s.unit_x);
      s.unit_b(unit[c]) = 0.0;
      x.col(c) = s.unit_x;
    }
    return;
  }
  switch (count) {
    case 1:
      return unitColumns<1>(s, unit, x);
    case 2:
      return unitColumns<2>(s, unit, x);
    case 3:
      return unitColumns<3>(s, unit, x);
    case 4:
      return unitColumns<4>(s, unit, x);
    case 5:
      return unitColumns<5>(s, unit, x);
    default:
      return unitColumns<6>(s, unit, x);
  }
}

int SparseCholesky::rows() const { return impl_->n; }

bool SparseCholesky::isSupernodal() const { return impl_->L->is_super != 0; }

CholeskyLayout SparseCholesky::layout() const { return impl_->layout; }

double SparseCholesky::factorNonZeros() const {
  return impl_->layout != CholeskyLayout::kSupernodal ? static_cast<double>(impl_->value.size()) : impl_->common.lnz;
}

}  // namespace track
}  // namespace rail
