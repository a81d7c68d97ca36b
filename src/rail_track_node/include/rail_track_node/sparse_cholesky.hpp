// Cholesky factorisation A = L L' of a sparse symmetric positive definite matrix with SuiteSparse CHOLMOD,
// factorised once; repeated solves reuse preallocated workspace (no allocation per solve).
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>

namespace rail {
namespace track {

/// How the factor is stored and solved.
enum class CholeskyLayout {
  /// CHOLMOD's simplicial L L' (fill-reducing ordering P), solved by two loops of dot products, along a row
  /// copy of L and along its columns: the fastest solve on the track's thin factors (about 14 entries per
  /// column).
  kSimplicial,
  /// CHOLMOD's supernodal L L' solved by cholmod_solve2: the reference of the simplicial solve, and the
  /// faster factorisation of long tracks.
  kSupernodal,
  /// kSimplicial on an ordering in two independent parts and a separator (rows of A below n/2, rows above,
  /// and the rows of the second half coupled to the first; CAMD within each): the parts of each triangular
  /// solve can run on two threads (forwardPart, solveSeparator, backwardPart). For matrices numbered along a
  /// line, such as the track's (plane by plane), the separator is one plane.
  kSimplicialTwoParts,
  /// The ordering of kSimplicialTwoParts with CHOLMOD's supernodal factor (a track's supernodes are the
  /// DOFs of a rail plane or of a node), each supernode stored once as the inverse of its triangular
  /// diagonal block and the dense block below it: both triangular passes read the same values, with one
  /// row index per block row, about half the bytes of a simplicial solve. Solved in the same three phases.
  /// When a quarter or more of the blocks' values are zeros (a straight track: the rails' DOFs partly
  /// uncoupled) the same factor is solved as kSimplicialTwoParts, without the zeros (solvesInBlocks()).
  kBlockedTwoParts,
};

/// A layout's name for people ("simplicial in two parts", ...).
const char* choleskyLayoutName(CholeskyLayout layout);

class SparseCholesky {
 public:
  /// Analyses and factorises A (only its upper triangle is read). Throws std::runtime_error naming the
  /// failing column if A is not positive definite.
  explicit SparseCholesky(const Eigen::SparseMatrix<double>& A, CholeskyLayout layout = CholeskyLayout::kSimplicial);
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  /// x = A^{-1} b (sizes must equal rows(); x may be b). No allocation.
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);
  /// The columns of A^{-1} of the count indices in unit (at most kMaxUnitColumns) into the first count
  /// columns of x (rows() x count at least, preallocated): one pass over the factor for all of them. Each
  /// column equals solve(e_unit[c]) to rounding. Each lane (0 .. kColumnLanes - 1) has its own workspace, so
  /// two threads may solve columns at once in different lanes, and beside solve() or the phases below
  /// (except with kSupernodal, whose columns use solve()'s workspace). No allocation.
  static constexpr int kMaxUnitColumns = 6;
  static constexpr int kColumnLanes = 2;
  void solveUnitColumns(const int* unit, int count, Eigen::MatrixXd& x, int lane = 0);

  /// kSimplicialTwoParts, kBlockedTwoParts: the solve of b in three phases. forwardPart(0, b) and forwardPart(1, b) may
  /// run at once on two threads, then solveSeparator(b, x) after both, then backwardPart(0, x) and backwardPart(1, x)
  /// at once; together they give solve(b, x) exactly (the same operations in the same order). x must have rows()
  /// entries. No allocation.
  void forwardPart(int part, const Eigen::VectorXd& b) noexcept;
  void solveSeparator(const Eigen::VectorXd& b, Eigen::VectorXd& x) noexcept;
  void backwardPart(int part, Eigen::VectorXd& x) noexcept;
  /// kSimplicialTwoParts, kBlockedTwoParts: the backward pass of a part in two sweeps, for a caller that needs
  /// x at a few rows early. markFirstRows() marks the rows (blocks) of the parts whose backward results those
  /// rows of A read: theirs and their ancestors in the elimination tree. backwardPart(part, x, kFirst) then
  /// solves only the marked ones, which gives x at the given rows; backwardPart(part, x, kRest) the others.
  /// kFirst then kRest equals backwardPart(part, x) to the last bit (each row from the same values by the
  /// same operations). markFirstRows() allocates nothing; call it while no solve runs. firstCovers(i): x(i)
  /// is final after the kFirst sweeps (marked, or in the separator).
  enum class Sweep { kAll, kFirst, kRest };
  void backwardPart(int part, Eigen::VectorXd& x, Sweep sweep) noexcept;
  void markFirstRows(const int* rows_of_a, int count) noexcept;
  bool firstCovers(int row_of_a) const noexcept;
  /// Rows of the two parts and of the separator (0 for the other layouts).
  int partRows(int part) const;
  int separatorRows() const;

  int rows() const;
  bool isSupernodal() const;
  /// kBlockedTwoParts: true when the factor is solved in blocks (false when too sparse for them).
  bool solvesInBlocks() const;
  CholeskyLayout layout() const;
  /// Non-zeros of the factor L.
  double factorNonZeros() const;

 private:
  struct Impl;
  template <int K>
  static void unitColumns(Impl& s, const int* unit, Eigen::MatrixXd& x, int lane);
  static void forwardRows(Impl& s, const Eigen::VectorXd& b, int begin, int end) noexcept;
  static void backwardRows(Impl& s, Eigen::VectorXd& x, int begin, int end, Sweep sweep = Sweep::kAll) noexcept;
  static void buildBlocks(Impl& s);
  template <int K>
  static void blockedUnitColumns(Impl& s, const int* unit, Eigen::MatrixXd& x, int lane);
  static void forwardBlocks(Impl& s, int region, const Eigen::VectorXd& b) noexcept;
  static void backwardBlocks(Impl& s, int region, Eigen::VectorXd& x, Sweep sweep = Sweep::kAll) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace track
}  // namespace rail
