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
  // solveUnitColumns, per lane: rows x kMaxUnitColumns, row-major.
  std::vector<double> y_many[SparseCholesky::kColumnLanes];
  // kSimplicialTwoParts: rows [0, part_end[0]) and [part_end[0], part_end[1]) of P A P' are the two
  // independent parts, [part_end[1], n) the separator.
  int part_end[2] = {0, 0};
  Eigen::VectorXd unit_b, unit_x;  // supernodal solveUnitColumns: one unit right-hand side and its solution
  // kBlockedTwoParts: per supernode of CHOLMOD's factor, the inverse of its diagonal block (lower triangle,
  // packed by columns) followed by the block below it (column-major), in block_value.
  struct Block {
    int first = 0;             // first row (and column) of the supernode in P A P'
    int cols = 0;              // its columns
    int below = 0;             // rows below its diagonal block
    int below_own = 0;         // of them, those in its own region (the others are rows of the separator)
    int row_at = 0;            // its rows below the diagonal block start at block_row[row_at]
    std::size_t value_at = 0;  // its values start at block_value[value_at]
  };
  std::vector<Block> blocks;
  std::vector<int> block_row;
  std::vector<double> block_value;
  int block_end[3] = {0, 0, 0};  // the blocks of part 0, part 1 and the separator end here
  int max_cols = 0, max_below = 0;
  std::vector<double> separator_sum[2];  // the forward updates of the separator's rows by each part
  std::vector<double> scratch[3];        // per region (part 0, part 1, separator): a block's v and t
  // solveUnitColumns, per lane: a block's v, u and t for kMaxUnitColumns.
  std::vector<double> unit_scratch[SparseCholesky::kColumnLanes];
  // kBlockedTwoParts: solved in blocks; false when the blocks would carry more than kMaxBlockZeros of zeros
  // (a straight track's factor, whose planes' DOFs are partly uncoupled): then the simplicial loops solve
  // the same factor without its zeros.
  bool blocked = false;
  // Two parts: the rows (blocked: the blocks) that backwardPart's kFirst sweep solves (markFirstRows).
  std::vector<char> first;
  std::vector<int> block_of_row;  // kBlockedTwoParts solved in blocks: the block of each row of P A P'
};

namespace {
// kBlockedTwoParts solves in blocks unless this fraction of the blocks' values or more are zeros: on the
// paper track's window 14 % in a curve (blocks faster), 38 % on the straight (blocks slower).
constexpr double kMaxBlockZeros = 0.25;
// The blocked passes ask for the values of the block this many blocks ahead.
constexpr int kPrefetchAhead = 2;

// The region of row i of P A P' in the two-part ordering: 0 and 1 the parts, 2 the separator.
inline int regionOf(const int* part_end, int i) { return i < part_end[0] ? 0 : i < part_end[1] ? 1 : 2; }

}  // namespace

// kBlockedTwoParts: the blocks of the supernodal factor s.L (see Impl::Block), a supernode that spans two
// regions (CHOLMOD may merge a part's last columns into the separator's) split at the region's end. Throws
// when the parts meet.
void SparseCholesky::buildBlocks(Impl& s) {
  const cholmod_factor* L = s.L;
  if (!L->is_super || !L->is_ll || L->xtype != CHOLMOD_REAL || L->itype != CHOLMOD_INT)
    throw std::runtime_error("SparseCholesky: CHOLMOD did not return a supernodal real L L' factor");
  const int* super = static_cast<const int*>(L->super);
  const int* pi = static_cast<const int*>(L->pi);
  const int* px = static_cast<const int*>(L->px);
  const int* ls = static_cast<const int*>(L->s);
  const double* lx = static_cast<const double*>(L->x);
  const int* P = static_cast<const int*>(L->Perm);
  const int nsuper = static_cast<int>(L->nsuper);
  s.perm.resize(static_cast<std::size_t>(s.n));
  for (int j = 0; j < s.n; ++j) s.perm[static_cast<std::size_t>(j)] = P ? P[j] : j;
  int region_before = 0;
  for (int k = 0; k < nsuper; ++k) {
    const int first = super[k], cols = super[k + 1] - super[k], rows = pi[k + 1] - pi[k];
    const int* R = ls + pi[k];
    const double* Lk = lx + px[k];
    bool ordered = true;
    for (int i = 0; i < rows && ordered; ++i) ordered = i < cols ? R[i] == first + i : R[i] > R[i - 1];
    if (!ordered)
      throw std::runtime_error("SparseCholesky: the rows of supernode " + std::to_string(k) + " are not ascending");
    for (int c0 = 0; c0 < cols;) {  // the piece of columns [c0, c1) of the supernode that lies in one region
      const int region = regionOf(s.part_end, first + c0);
      const int region_end = region == 2 ? s.n : s.part_end[region];
      const int c1 = std::min(cols, region_end - first);
      if (region < region_before)
        throw std::runtime_error("SparseCholesky: supernode " + std::to_string(k) +
                                 " lies before a region it does not belong to");
      region_before = region;
      Impl::Block blk;
      blk.first = first + c0;
      blk.cols = c1 - c0;
      blk.below = rows - c1;
      blk.below_own = 0;
      for (int i = c1; i < rows; ++i) {
        const int r = regionOf(s.part_end, R[i]);
        if (r != region && r != 2)
          throw std::runtime_error("SparseCholesky: the two parts of the ordering are coupled in L (row " +
                                   std::to_string(R[i]) + " of supernode " + std::to_string(k) + ")");
        if (r == region) ++blk.below_own;
      }
      blk.row_at = static_cast<int>(s.block_row.size());
      s.block_row.insert(s.block_row.end(), R + c1, R + rows);
      blk.value_at = s.block_value.size();
      Eigen::MatrixXd D = Eigen::MatrixXd::Zero(blk.cols, blk.cols);
      for (int j = 0; j < blk.cols; ++j)
        for (int i = j; i < blk.cols; ++i) D(i, j) = Lk[static_cast<std::ptrdiff_t>(c0 + j) * rows + c0 + i];
      const Eigen::MatrixXd D_inv =
          D.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd::Identity(blk.cols, blk.cols));
      for (int j = 0; j < blk.cols; ++j)
        for (int i = j; i < blk.cols; ++i) s.block_value.push_back(D_inv(i, j));
      for (int j = 0; j < blk.cols; ++j)
        for (int i = c1; i < rows; ++i) s.block_value.push_back(Lk[static_cast<std::ptrdiff_t>(c0 + j) * rows + i]);
      s.blocks.push_back(blk);
      s.block_end[region] = static_cast<int>(s.blocks.size());
      s.max_cols = std::max(s.max_cols, blk.cols);
      s.max_below = std::max(s.max_below, blk.below);
      c0 = c1;
    }
  }
  const std::size_t zeros = static_cast<std::size_t>(std::count(s.block_value.begin(), s.block_value.end(), 0.0));
  s.blocked = static_cast<double>(zeros) < kMaxBlockZeros * static_cast<double>(s.block_value.size());
  if (!s.blocked) {
    s.blocks = {};
    s.block_row = {};
    s.block_value = {};
    return;
  }
  s.block_of_row.assign(static_cast<std::size_t>(s.n), 0);
  for (std::size_t k = 0; k < s.blocks.size(); ++k)
    for (int i = 0; i < s.blocks[k].cols; ++i)
      s.block_of_row[static_cast<std::size_t>(s.blocks[k].first + i)] = static_cast<int>(k);
  s.first.assign(s.blocks.size(), 0);
  s.block_end[1] = std::max(s.block_end[1], s.block_end[0]);
  s.block_end[2] = std::max(s.block_end[2], s.block_end[1]);
  const int separator = s.n - s.part_end[1];
  for (auto& sum : s.separator_sum) sum.assign(static_cast<std::size_t>(separator), 0.0);
  for (auto& work : s.scratch) work.assign(static_cast<std::size_t>(s.max_cols + s.max_below), 0.0);
  for (auto& work : s.unit_scratch)
    work.assign(static_cast<std::size_t>(2 * s.max_cols + s.max_below) * SparseCholesky::kMaxUnitColumns, 0.0);
  s.y.assign(static_cast<std::size_t>(s.n), 0.0);
  s.inverse.assign(static_cast<std::size_t>(s.n), 0);
  for (int j = 0; j < s.n; ++j) s.inverse[static_cast<std::size_t>(s.perm[static_cast<std::size_t>(j)])] = j;
  for (auto& y : s.y_many) y.assign(static_cast<std::size_t>(s.n) * SparseCholesky::kMaxUnitColumns, 0.0);
}

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
  const bool two_parts = layout == CholeskyLayout::kSimplicialTwoParts || layout == CholeskyLayout::kBlockedTwoParts;
  s.common.supernodal = layout == CholeskyLayout::kSupernodal || layout == CholeskyLayout::kBlockedTwoParts
                            ? CHOLMOD_SUPERNODAL
                            : CHOLMOD_SIMPLICIAL;
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

  std::vector<int> given;  // two parts: the ordering
  if (two_parts) {
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

  if (layout == CholeskyLayout::kBlockedTwoParts) {
    try {
      buildBlocks(s);
    } catch (...) {
      cholmod_free_factor(&s.L, &s.common);
      cholmod_finish(&s.common);
      throw;
    }
    if (s.blocked) return;
    // Too sparse for blocks: the same factor as a simplicial one (same ordering, same parts).
    if (!cholmod_change_factor(CHOLMOD_REAL, 1, 0, 1, 1, s.L, &s.common)) {
      cholmod_free_factor(&s.L, &s.common);
      cholmod_finish(&s.common);
      throw std::runtime_error("SparseCholesky: cholmod_change_factor could not make the factor simplicial");
    }
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
    // A supernodal factor made simplicial (kBlockedTwoParts) keeps the supernodes' zeros: left out.
    const bool drop_zeros = layout == CholeskyLayout::kBlockedTwoParts;
    std::size_t nnz = 0;
    for (int j = 0; j < s.n; ++j)
      for (int p = Lp[j]; p < Lp[j] + Lnz[j]; ++p) nnz += p == Lp[j] || !drop_zeros || Lx[p] != 0.0;
    s.row.resize(nnz);
    s.value.resize(nnz);
    std::size_t k = 0;
    for (int j = 0; j < s.n; ++j) {
      s.perm[static_cast<std::size_t>(j)] = P ? P[j] : j;
      s.col_start[static_cast<std::size_t>(j)] = static_cast<int>(k);
      if (Lnz[j] < 1 || Li[Lp[j]] != j)
        throw std::runtime_error("SparseCholesky: column " + std::to_string(j) +
                                 " of L does not start at its diagonal");
      for (int p = Lp[j]; p < Lp[j] + Lnz[j]; ++p) {
        if (p != Lp[j] && drop_zeros && Lx[p] == 0.0) continue;
        s.row[k] = Li[p];
        s.value[k] = p == Lp[j] ? 1.0 / Lx[p] : Lx[p];
        ++k;
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
    for (auto& y : s.y_many) y.assign(static_cast<std::size_t>(s.n) * kMaxUnitColumns, 0.0);
    if (two_parts) s.first.assign(static_cast<std::size_t>(s.n), 0);
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
  if (s.blocked) {
    for (int region = 0; region < 3; ++region) forwardBlocks(s, region, b);
    backwardBlocks(s, 2, x);
    backwardBlocks(s, 0, x);
    backwardBlocks(s, 1, x);
    return;
  }
  forwardRows(s, b, 0, s.n);
  backwardRows(s, x, 0, s.n);
}

namespace {
// Asks for block k's values ahead of their use: in a co-simulation step the rest of the step has evicted
// the factor from the core's caches, and each block's loads would wait on memory. Nothing for k outside
// [begin, end).
template <class Impl>
inline void prefetchBlock(const Impl& s, int k, int begin, int end) noexcept {
  if (k < begin || k >= end) return;
  const std::size_t first = s.blocks[static_cast<std::size_t>(k)].value_at;
  const std::size_t last = static_cast<std::size_t>(k) + 1 < s.blocks.size()
                               ? s.blocks[static_cast<std::size_t>(k) + 1].value_at
                               : s.block_value.size();
  const char* p = reinterpret_cast<const char*>(s.block_value.data() + first);
  const char* stop = reinterpret_cast<const char*>(s.block_value.data() + last);
  for (; p < stop; p += 64) __builtin_prefetch(p);
}
}  // namespace

// kBlockedTwoParts, L y = P b over the rows of one region (0, 1: the parts, 2: the separator), block by
// block: the block's unknowns are its inverse diagonal block times its right-hand side, then the block
// below them updates the rows below (a part's updates of the separator's rows are summed apart, so that
// the two parts can run at once; the separator subtracts part 0's sums, then part 1's).
void SparseCholesky::forwardBlocks(Impl& s, int region, const Eigen::VectorXd& b) noexcept {
  const int row_begin = region == 0 ? 0 : s.part_end[region - 1];
  const int row_end = region == 2 ? s.n : s.part_end[region];
  const int* perm = s.perm.data();
  double* y = s.y.data();
  double* separator_sum = nullptr;  // indexed by row of P A P'
  if (region < 2) {
    for (int i = row_begin; i < row_end; ++i) y[i] = b[perm[i]];
    std::fill(s.separator_sum[region].begin(), s.separator_sum[region].end(), 0.0);
    separator_sum = s.separator_sum[region].data() - s.part_end[1];
  } else {
    const double* sum0 = s.separator_sum[0].data() - row_begin;
    const double* sum1 = s.separator_sum[1].data() - row_begin;
    for (int i = row_begin; i < row_end; ++i) y[i] = (b[perm[i]] - sum0[i]) - sum1[i];
  }
  double* v = s.scratch[region].data();
  double* t = v + s.max_cols;
  const int* block_row = s.block_row.data();
  const int k_begin = region == 0 ? 0 : s.block_end[region - 1], k_end = s.block_end[region];
  for (int k = k_begin; k < k_end; ++k) {
    prefetchBlock(s, k + kPrefetchAhead, k_begin, k_end);
    const Impl::Block& blk = s.blocks[static_cast<std::size_t>(k)];
    const int nc = blk.cols, nb = blk.below;
    const double* value = s.block_value.data() + blk.value_at;
    double* yk = y + blk.first;
    // v = D^{-1} y_k and t = B v by the columns, two and four at a time: each sum's chain of dependent
    // additions is the pass's critical path.
    for (int i = 0; i < nc; ++i) v[i] = 0.0;
    int j = 0;
    for (; j + 1 < nc; j += 2) {
      const double y0 = yk[j], y1 = yk[j + 1];
      const double* c1 = value + (nc - j);
      v[j] += value[0] * y0;
      for (int i = j + 1; i < nc; ++i) v[i] += value[i - j] * y0 + c1[i - j - 1] * y1;
      value = c1 + (nc - j - 1);
    }
    if (j < nc) {
      v[j] += value[0] * yk[j];
      value += 1;
    }
    for (int i = 0; i < nc; ++i) yk[i] = v[i];
    if (nb == 0) continue;
    for (int i = 0; i < nb; ++i) t[i] = 0.0;
    j = 0;
    for (; j + 3 < nc; j += 4, value += 4 * nb) {
      const double v0 = v[j], v1 = v[j + 1], v2 = v[j + 2], v3 = v[j + 3];
      const double *c0 = value, *c1 = value + nb, *c2 = value + 2 * nb, *c3 = value + 3 * nb;
      for (int i = 0; i < nb; ++i) t[i] += (c0[i] * v0 + c1[i] * v1) + (c2[i] * v2 + c3[i] * v3);
    }
    for (; j < nc; ++j, value += nb) {
      const double vj = v[j];
      for (int i = 0; i < nb; ++i) t[i] += value[i] * vj;
    }
    const int* R = block_row + blk.row_at;
    for (int i = 0; i < blk.below_own; ++i) y[R[i]] -= t[i];
    for (int i = blk.below_own; i < nb; ++i) separator_sum[R[i]] += t[i];
  }
}

// kBlockedTwoParts, L' z = y over the rows of one region, blocks descending (the rows below a block are
// solved: its own region's and the separator's), then x = P' z over those rows.
void SparseCholesky::backwardBlocks(Impl& s, int region, Eigen::VectorXd& x, Sweep sweep) noexcept {
  const int row_begin = region == 0 ? 0 : s.part_end[region - 1];
  const int row_end = region == 2 ? s.n : s.part_end[region];
  const char* marked = sweep == Sweep::kAll ? nullptr : s.first.data();
  const char wanted = sweep == Sweep::kFirst ? 1 : 0;
  const int* perm = s.perm.data();
  double* y = s.y.data();
  double* u = s.scratch[region].data();
  double* t = u + s.max_cols;
  const int* block_row = s.block_row.data();
  const int k_begin = region == 0 ? 0 : s.block_end[region - 1], k_end = s.block_end[region];
  for (int k = k_end - 1; k >= k_begin; --k) {
    if (marked != nullptr && marked[k] != wanted) continue;
    prefetchBlock(s, k - kPrefetchAhead, k_begin, k_end);
    const Impl::Block& blk = s.blocks[static_cast<std::size_t>(k)];
    const int nc = blk.cols, nb = blk.below;
    const double* inverse = s.block_value.data() + blk.value_at;
    const double* below = inverse + static_cast<std::ptrdiff_t>(nc) * (nc + 1) / 2;
    double* yk = y + blk.first;
    const int* R = block_row + blk.row_at;
    for (int i = 0; i < nb; ++i) t[i] = y[R[i]];
    for (int j = 0; j < nc; ++j, below += nb) {  // u = y_k - B' t
      double sum0 = 0.0, sum1 = 0.0, sum2 = 0.0, sum3 = 0.0;
      int i = 0;
      for (; i + 3 < nb; i += 4) {
        sum0 += below[i] * t[i];
        sum1 += below[i + 1] * t[i + 1];
        sum2 += below[i + 2] * t[i + 2];
        sum3 += below[i + 3] * t[i + 3];
      }
      for (; i < nb; ++i) sum0 += below[i] * t[i];
      u[j] = yk[j] - ((sum0 + sum1) + (sum2 + sum3));
    }
    for (int i = 0; i < nc; ++i) {  // y_k = D^{-T} u: column i of D^{-1} (rows i and below) times u
      double sum0 = 0.0, sum1 = 0.0;
      int q = i;
      for (; q + 1 < nc; q += 2) {
        sum0 += inverse[q - i] * u[q];
        sum1 += inverse[q + 1 - i] * u[q + 1];
      }
      if (q < nc) sum0 += inverse[q - i] * u[q];
      yk[i] = sum0 + sum1;
      inverse += nc - i;
    }
    if (marked != nullptr)
      for (int i = 0; i < nc; ++i) x[perm[blk.first + i]] = yk[i];
  }
  if (marked == nullptr)
    for (int i = row_begin; i < row_end; ++i) x[perm[i]] = y[i];
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
void SparseCholesky::backwardRows(Impl& s, Eigen::VectorXd& x, int begin, int end, Sweep sweep) noexcept {
  const int* perm = s.perm.data();
  const int* start = s.col_start.data();
  const int* row = s.row.data();
  const double* value = s.value.data();
  double* y = s.y.data();
  if (sweep == Sweep::kAll) {
    for (int j = end - 1; j >= begin; --j)
      y[j] = minusDot(y[j], value, row, start[j] + 1, start[j + 1], y) * value[start[j]];
    for (int k = begin; k < end; ++k) x[perm[k]] = y[k];
    return;
  }
  const char* marked = s.first.data();
  const char wanted = sweep == Sweep::kFirst ? 1 : 0;
  for (int j = end - 1; j >= begin; --j) {
    if (marked[j] != wanted) continue;
    y[j] = minusDot(y[j], value, row, start[j] + 1, start[j + 1], y) * value[start[j]];
    x[perm[j]] = y[j];
  }
}

void SparseCholesky::forwardPart(int part, const Eigen::VectorXd& b) noexcept {
  Impl& s = *impl_;
  if (s.blocked) return forwardBlocks(s, part, b);
  forwardRows(s, b, part == 0 ? 0 : s.part_end[0], s.part_end[part]);
}

void SparseCholesky::solveSeparator(const Eigen::VectorXd& b, Eigen::VectorXd& x) noexcept {
  Impl& s = *impl_;
  if (s.blocked) {
    forwardBlocks(s, 2, b);
    backwardBlocks(s, 2, x);
    return;
  }
  forwardRows(s, b, s.part_end[1], s.n);
  backwardRows(s, x, s.part_end[1], s.n);
}

void SparseCholesky::backwardPart(int part, Eigen::VectorXd& x) noexcept { backwardPart(part, x, Sweep::kAll); }

void SparseCholesky::backwardPart(int part, Eigen::VectorXd& x, Sweep sweep) noexcept {
  Impl& s = *impl_;
  if (s.blocked) return backwardBlocks(s, part, x, sweep);
  backwardRows(s, x, part == 0 ? 0 : s.part_end[0], s.part_end[part], sweep);
}

// A row's (block's) backward result reads those of the rows below it in its column of L (its block's rows
// below): marked in one ascending pass, each marked row (block) marks them.
void SparseCholesky::markFirstRows(const int* rows_of_a, int count) noexcept {
  Impl& s = *impl_;
  if (s.first.empty()) return;
  std::fill(s.first.begin(), s.first.end(), 0);
  char* marked = s.first.data();
  if (s.blocked) {
    for (int c = 0; c < count; ++c)
      if (rows_of_a[c] >= 0 && rows_of_a[c] < s.n)
        marked[s.block_of_row[static_cast<std::size_t>(s.inverse[static_cast<std::size_t>(rows_of_a[c])])]] = 1;
    for (std::size_t k = 0; k < s.blocks.size(); ++k) {
      if (!marked[k]) continue;
      const Impl::Block& blk = s.blocks[k];
      for (int i = 0; i < blk.below; ++i)
        marked[s.block_of_row[static_cast<std::size_t>(s.block_row[static_cast<std::size_t>(blk.row_at + i)])]] = 1;
    }
    return;
  }
  for (int c = 0; c < count; ++c)
    if (rows_of_a[c] >= 0 && rows_of_a[c] < s.n) marked[s.inverse[static_cast<std::size_t>(rows_of_a[c])]] = 1;
  for (int j = 0; j < s.n; ++j) {
    if (!marked[j]) continue;
    for (int q = s.col_start[static_cast<std::size_t>(j)] + 1; q < s.col_start[static_cast<std::size_t>(j) + 1]; ++q)
      marked[s.row[static_cast<std::size_t>(q)]] = 1;
  }
}

bool SparseCholesky::firstCovers(int row_of_a) const noexcept {
  const Impl& s = *impl_;
  if (s.first.empty() || row_of_a < 0 || row_of_a >= s.n) return false;
  const int i = s.inverse[static_cast<std::size_t>(row_of_a)];
  if (i >= s.part_end[1]) return true;  // the separator: solved before both parts
  return s.first[static_cast<std::size_t>(s.blocked ? s.block_of_row[static_cast<std::size_t>(i)] : i)] != 0;
}

int SparseCholesky::partRows(int part) const {
  const Impl& s = *impl_;
  if (s.layout != CholeskyLayout::kSimplicialTwoParts && s.layout != CholeskyLayout::kBlockedTwoParts) return 0;
  return part == 0 ? s.part_end[0] : s.part_end[1] - s.part_end[0];
}

int SparseCholesky::separatorRows() const {
  const Impl& s = *impl_;
  return s.layout == CholeskyLayout::kSimplicialTwoParts || s.layout == CholeskyLayout::kBlockedTwoParts
             ? s.n - s.part_end[1]
             : 0;
}

// solveUnitColumns on the simplicial factor with K right-hand sides, rows interleaved (y[i * K + c]) so
// that each factor entry is read once for all of them.
template <int K>
void SparseCholesky::unitColumns(Impl& s, const int* unit, Eigen::MatrixXd& x, int lane) {
  const int n = s.n;
  const int* start = s.col_start.data();
  const int* row = s.row.data();
  const double* value = s.value.data();
  double* y = s.y_many[lane].data();
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

// solveUnitColumns on the blocks with K right-hand sides, rows interleaved (y[i * K + c]). The forward pass
// skips the blocks whose right-hand sides are still zero (those off the unit rows' paths to the root).
template <int K>
void SparseCholesky::blockedUnitColumns(Impl& s, const int* unit, Eigen::MatrixXd& x, int lane) {
  const int n = s.n;
  double* y = s.y_many[lane].data();
  std::fill(y, y + static_cast<std::ptrdiff_t>(n) * K, 0.0);
  for (int c = 0; c < K; ++c)
    y[static_cast<std::ptrdiff_t>(s.inverse[static_cast<std::size_t>(unit[c])]) * K + c] = 1.0;
  double* v = s.unit_scratch[lane].data();
  double* u = v + static_cast<std::ptrdiff_t>(s.max_cols) * K;
  double* t = u + static_cast<std::ptrdiff_t>(s.max_cols) * K;
  const int* block_row = s.block_row.data();
  const int blocks = static_cast<int>(s.blocks.size());
  for (int k = 0; k < blocks; ++k) {
    const Impl::Block& blk = s.blocks[static_cast<std::size_t>(k)];
    const int nc = blk.cols, nb = blk.below;
    double* yk = y + static_cast<std::ptrdiff_t>(blk.first) * K;
    bool zero = true;
    for (int i = 0; i < nc * K && zero; ++i) zero = yk[i] == 0.0;
    if (zero) continue;
    const double* value = s.block_value.data() + blk.value_at;
    std::fill(v, v + nc * K, 0.0);
    for (int j = 0; j < nc; ++j) {
      for (int i = j; i < nc; ++i)
        for (int c = 0; c < K; ++c) v[i * K + c] += value[i - j] * yk[j * K + c];
      value += nc - j;
    }
    std::copy(v, v + nc * K, yk);
    std::fill(t, t + nb * K, 0.0);
    for (int j = 0; j < nc; ++j, value += nb)
      for (int i = 0; i < nb; ++i)
        for (int c = 0; c < K; ++c) t[i * K + c] += value[i] * v[j * K + c];
    const int* R = block_row + blk.row_at;
    for (int i = 0; i < nb; ++i) {
      double* yi = y + static_cast<std::ptrdiff_t>(R[i]) * K;
      for (int c = 0; c < K; ++c) yi[c] -= t[i * K + c];
    }
  }
  for (int k = blocks - 1; k >= 0; --k) {
    const Impl::Block& blk = s.blocks[static_cast<std::size_t>(k)];
    const int nc = blk.cols, nb = blk.below;
    const double* inverse = s.block_value.data() + blk.value_at;
    const double* below = inverse + static_cast<std::ptrdiff_t>(nc) * (nc + 1) / 2;
    double* yk = y + static_cast<std::ptrdiff_t>(blk.first) * K;
    const int* R = block_row + blk.row_at;
    for (int i = 0; i < nb; ++i) {
      const double* yi = y + static_cast<std::ptrdiff_t>(R[i]) * K;
      for (int c = 0; c < K; ++c) t[i * K + c] = yi[c];
    }
    std::copy(yk, yk + nc * K, u);
    for (int j = 0; j < nc; ++j, below += nb)
      for (int i = 0; i < nb; ++i)
        for (int c = 0; c < K; ++c) u[j * K + c] -= below[i] * t[i * K + c];
    for (int i = 0; i < nc; ++i) {
      double sum[K] = {};
      for (int q = i; q < nc; ++q)
        for (int c = 0; c < K; ++c) sum[c] += inverse[q - i] * u[q * K + c];
      for (int c = 0; c < K; ++c) yk[i * K + c] = sum[c];
      inverse += nc - i;
    }
  }
  for (int i = 0; i < n; ++i) {
    const double* yi = y + static_cast<std::ptrdiff_t>(i) * K;
    const int r = s.perm[static_cast<std::size_t>(i)];
    for (int c = 0; c < K; ++c) x(r, c) = yi[c];
  }
}

void SparseCholesky::solveUnitColumns(const int* unit, int count, Eigen::MatrixXd& x, int lane) {
  Impl& s = *impl_;
  if (s.blocked) {
    switch (count) {
      case 1:
        return blockedUnitColumns<1>(s, unit, x, lane);
      case 2:
        return blockedUnitColumns<2>(s, unit, x, lane);
      case 3:
        return blockedUnitColumns<3>(s, unit, x, lane);
      case 4:
        return blockedUnitColumns<4>(s, unit, x, lane);
      case 5:
        return blockedUnitColumns<5>(s, unit, x, lane);
      default:
        return blockedUnitColumns<6>(s, unit, x, lane);
    }
  }
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
      return unitColumns<1>(s, unit, x, lane);
    case 2:
      return unitColumns<2>(s, unit, x, lane);
    case 3:
      return unitColumns<3>(s, unit, x, lane);
    case 4:
      return unitColumns<4>(s, unit, x, lane);
    case 5:
      return unitColumns<5>(s, unit, x, lane);
    default:
      return unitColumns<6>(s, unit, x, lane);
  }
}

const char* choleskyLayoutName(CholeskyLayout layout) {
  switch (layout) {
    case CholeskyLayout::kSimplicial:
      return "simplicial";
    case CholeskyLayout::kSupernodal:
      return "supernodal (CHOLMOD's solve)";
    case CholeskyLayout::kSimplicialTwoParts:
      return "simplicial in two parts";
    case CholeskyLayout::kBlockedTwoParts:
      return "blocks in two parts";
  }
  return "?";
}

int SparseCholesky::rows() const { return impl_->n; }

bool SparseCholesky::solvesInBlocks() const { return impl_->blocked; }

bool SparseCholesky::isSupernodal() const { return impl_->layout == CholeskyLayout::kSupernodal; }

CholeskyLayout SparseCholesky::layout() const { return impl_->layout; }

double SparseCholesky::factorNonZeros() const {
  const Impl& s = *impl_;
  return s.layout == CholeskyLayout::kSupernodal || s.layout == CholeskyLayout::kBlockedTwoParts
             ? s.common.lnz
             : static_cast<double>(s.value.size());
}

}  // namespace track
}  // namespace rail
