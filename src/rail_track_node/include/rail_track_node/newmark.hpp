// Newmark trapezoidal rule (average acceleration: gamma = 1/2, beta = 1/4) with a fixed step for
// M a + C v + K d = f (paper section 3.3), and the static equilibrium K d = f.
// The model (LinearSystem) is separate from the integrator state (NewmarkState).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include <rail_core/cost_profile.hpp>

#include "rail_track_node/sparse_cholesky.hpp"
#include "rail_track_node/track_mesh.hpp"
#include "rail_track_node/track_model.hpp"

namespace rail {
namespace track {

/// External nodal loads of one step: a sparse vector (free DOF index, value) with capacity fixed at
/// construction. Values on the same index add up.
class NodalLoads {
 public:
  explicit NodalLoads(int capacity) : index_(capacity), value_(capacity) {}
  void clear() { count_ = 0; }
  /// Adds value (N or N m) on free DOF i; ignored if i < 0 (fixed DOF). Returns false if full.
  bool add(int i, double value) {
    if (i < 0) return true;
    if (count_ >= static_cast<int>(index_.size())) return false;
    index_[count_] = i;
    value_[count_] = value;
    ++count_;
    return true;
  }
  int size() const { return count_; }
  int capacity() const { return static_cast<int>(index_.size()); }
  int index(int k) const { return index_[k]; }
  double value(int k) const { return value_[k]; }

 private:
  std::vector<int> index_;
  std::vector<double> value_;
  int count_ = 0;
};

/// Adds the equivalent nodal loads (paper eq. 16) of a force f_world (N) and moment m_world (N m) applied on
/// the centre line of rail `rail` (RailSide) at centre-line arc length s. Returns false if s is off the
/// rails or the load vector is full. No allocation.
bool addRailPointLoad(const TrackMesh& mesh, int rail, double s, const Eigen::Vector3d& f_world,
                      const Eigen::Vector3d& m_world, NodalLoads& loads);

/// Integrator state: displacement d (m, rad), velocity v, acceleration a over the free DOFs; time t (s).
struct NewmarkState {
  Eigen::VectorXd d, v, a;
  double t = 0.0;
};

/// Grounded end dashpots (SpringKind::AbsorbingEnd) of a mesh: the dashpot forces each C v product computes.
int countEndDashpots(const TrackMesh& mesh);

/// Fixed-step Newmark trapezoidal integrator. Factorises K_eff = K + 4/dt^2 M + 2/dt C once (CHOLMOD);
/// each step builds one right-hand side in preallocated vectors and does one solve. The damping product
/// C (c2 d + v) is skipped when C has no entries (effects.track_damping and absorbing_ends off).
class NewmarkIntegrator {
 public:
  /// sys must outlive the integrator. include_gravity: add sys.f_gravity to the load of every step.
  /// cost (optional, must outlive the integrator): right-hand side build and completion into kTrackRhs,
  /// the K_eff solve of each step into kTrackSolve, C v products into kDampingProducts and, per product,
  /// end_dashpots (countEndDashpots of the mesh) into kEndDashpotForces. solveEffective() is not timed.
  /// layout: how K_eff is factorised and solved (SparseCholesky).
  NewmarkIntegrator(const LinearSystem& sys, double dt, bool include_gravity = true,
                    rail::core::CostClock* cost = nullptr, int end_dashpots = 0,
                    CholeskyLayout layout = CholeskyLayout::kSimplicial);

  /// State at rest at displacement d0 (zero velocity); the acceleration is solved from
  /// M a0 = f - C v0 - K d0 with f = gravity (if included) + loads. Allocates: call at set-up.
  NewmarkState initialState(const Eigen::VectorXd& d0, const NodalLoads* loads = nullptr) const;

  /// Advances state by dt with the external loads at the end of the step (t + dt), plus `more` when not
  /// null (e.g. HangingSupports' loads). No allocation. Same as solveStep(state, loads, more) then
  /// completeStep(state).
  void step(NewmarkState& state, const NodalLoads& loads, const NodalLoads* more = nullptr);

  /// First half of step(): solves K_eff d_{n+1} = f_{n+1} + M (c0 d + c1 v + a) + C (c2 d + v) into
  /// stepDisplacement() without changing state. A caller may then correct stepDisplacement() (e.g. by the
  /// response K_eff^{-1} f to extra loads f found after the solve) before completeStep(). No allocation.
  void solveStep(const NewmarkState& state, const NodalLoads& loads, const NodalLoads* more = nullptr);
  /// solveStep() in phases, for a factor in two parts (CholeskyLayout::kSimplicialTwoParts): buildRhs(),
  /// then forwardPart(0) and forwardPart(1) (at once on two threads), solveSeparator(), then backwardPart(0)
  /// and backwardPart(1) (at once). The same result as solveStep(). The parts are not timed. No allocation.
  void buildRhs(const NewmarkState& state, const NodalLoads& loads, const NodalLoads* more = nullptr);
  void forwardPart(int part) noexcept { factor_->forwardPart(part, rhs_); }
  void solveSeparator() noexcept { factor_->solveSeparator(rhs_, d_new_); }
  void backwardPart(int part) noexcept { factor_->backwardPart(part, d_new_); }
  /// The backward part in two sweeps: the rows marked by markFirstRows() (DOFs whose stepDisplacement() a
  /// caller needs first), then the others (SparseCholesky::markFirstRows). No allocation.
  void backwardPart(int part, SparseCholesky::Sweep sweep) noexcept { factor_->backwardPart(part, d_new_, sweep); }
  void markFirstRows(const int* dofs, int count) noexcept { factor_->markFirstRows(dofs, count); }
  bool firstCovers(int dof) const noexcept { return factor_->firstCovers(dof); }
  /// The right-hand side of the last buildRhs() or solveStep() (N, N m over the free DOFs).
  const Eigen::VectorXd& rightHandSide() const { return rhs_; }
  /// d_{n+1} of the last solveStep() (m, rad over the free DOFs), writable.
  Eigen::VectorXd& stepDisplacement() { return d_new_; }
  /// Second half of step(): a_{n+1}, v_{n+1} from stepDisplacement() and state; state becomes t + dt.
  /// No allocation.
  void completeStep(NewmarkState& state);
  /// completeStep() split so that two threads can share it: completeRows() for the DOFs [begin, end) of
  /// stepDisplacement() (not timed), then advanceTime() once every DOF is done. No allocation.
  void completeRows(NewmarkState& state, int begin, int end) const noexcept;
  void advanceTime(NewmarkState& state) const noexcept { state.t += dt_; }
  /// x = K_eff^{-1} b (b, x of size n; x preallocated). No allocation.
  void solveEffective(const Eigen::VectorXd& b, Eigen::VectorXd& x) { factor_->solve(b, x); }
  /// Columns K_eff^{-1} e_dofs[c], c < count <= SparseCholesky::kMaxUnitColumns, into x (n x count at least,
  /// preallocated) in one pass over the factor, in the factor's column workspace `lane`
  /// (SparseCholesky::solveUnitColumns). No allocation.
  void solveEffectiveColumns(const int* dofs, int count, Eigen::MatrixXd& x, int lane = 0) {
    factor_->solveUnitColumns(dofs, count, x, lane);
  }

  double dt() const { return dt_; }
  const SparseCholesky& factor() const { return *factor_; }
  /// Where the right-hand side and solve are timed from now on (null: not timed).
  void setCostClock(rail::core::CostClock* cost) { cost_ = cost; }

 private:
  const LinearSystem& sys_;
  double dt_;
  bool include_gravity_;
  bool damped_;  // C has entries
  rail::core::CostClock* cost_;
  int end_dashpots_;
  std::unique_ptr<SparseCholesky> factor_;
  // M and C in 6 x 6 blocks of DOFs (block rows of 6 rows, each block stored column by column): per row the
  // products add the same terms in the same order as a row-by-row product, a block row at once.
  struct BlockRows {
    std::vector<int> start, col;  // per block row: its blocks [start[I], start[I + 1]); block column
    std::vector<double> values;   // 36 per block
    void build(const Eigen::SparseMatrix<double, Eigen::RowMajor>& A, int block_rows);
  };
  BlockRows m_blocks_, c_blocks_;
  Eigen::VectorXd rhs_, x1_, x2_, d_new_;  // per-step work vectors (x1_, x2_ padded to whole blocks)
};

/// Static equilibrium d = K^{-1} f (factorises K; call at set-up).
Eigen::VectorXd solveStatic(const LinearSystem& sys, const Eigen::VectorXd& f);

/// Static equilibrium under gravity, K d = f_g: the initial state of a simulation.
Eigen::VectorXd staticGravityDeflection(const LinearSystem& sys);

/// Mechanical energy 1/2 v' M v + 1/2 d' K d, J.
double mechanicalEnergy(const LinearSystem& sys, const NewmarkState& state);

}  // namespace track
}  // namespace rail
