#include "rail_track_node/newmark.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "rail_contact/beam_shape.hpp"
#include "rail_contact/format.hpp"

namespace rail {
namespace track {

bool addRailPointLoad(const TrackMesh& mesh, int rail, double s, const Eigen::Vector3d& f_world,
                      const Eigen::Vector3d& m_world, NodalLoads& loads) {
  int beam = 0;
  double xi = 0.0;
  if (!mesh.locateRail(rail, s, beam, xi)) return false;
  const BeamElement& b = mesh.beams[beam];
  const rail::contact::Vector12d F =
      rail::contact::beamEquivalentNodalLoadsWorld(xi, b.length, b.R_local_to_world, f_world, m_world);
  bool ok = true;
  for (int d = 0; d < 6; ++d) {
    ok = loads.add(mesh.dofIndex(b.node_i, d), F(d)) && ok;
    ok = loads.add(mesh.dofIndex(b.node_j, d), F(6 + d)) && ok;
  }
  return ok;
}

int countEndDashpots(const TrackMesh& mesh) {
  int n = 0;
  for (const SpringDamperElement& e : mesh.springs)
    if (e.kind == SpringKind::AbsorbingEnd) ++n;
  return n;
}

namespace {

constexpr int kBlock = 6;

// The per-step loops over every DOF, each compiled twice: for AVX2 where the CPU has it (chosen once, at
// load) and for the baseline x86-64. Each result is its own chain of multiplies and adds in a fixed order
// (no fused multiply-add, no reordered sums), so both give the same bits; AVX2 does four lanes at once.
#define RAIL_NEWMARK_KERNEL __attribute__((target_clones("avx2", "default")))

// sum[r] += A(r, j) x[j] over the blocks [b0, b1) of a block row, j ascending, for its 6 rows r (each block
// stored column by column). Inlined into each compiled version of its caller.
__attribute__((always_inline)) inline void addBlockRow(const int* col, const double* values, int b0, int b1,
                                                       const double* x, double sum[kBlock]) {
  for (int b = b0; b < b1; ++b) {
    const double* B = values + static_cast<std::ptrdiff_t>(b) * kBlock * kBlock;
    const double* xb = x + static_cast<std::ptrdiff_t>(col[b]) * kBlock;
    for (int j = 0; j < kBlock; ++j)
      for (int r = 0; r < kBlock; ++r) sum[r] += B[kBlock * j + r] * xb[j];
  }
}

// rhs = f + M x1 + C x2 with x1 = c0 d + c1 v + a and x2 = c2 d + v (c_blocks null: no damping, rhs = f + M
// x1), f the gravity load g when not null. Per row, the blocks' products add in block and column order, as
// a row-by-row product would.
RAIL_NEWMARK_KERNEL
void rightHandSideRows(int n, double c0, double c1, double c2, const double* d, const double* v, const double* a,
                       const double* g, const int* m_start, const int* m_col, const double* m_values,
                       const int* c_start, const int* c_col, const double* c_values, double* x1, double* x2,
                       double* rhs) {
  for (int i = 0; i < n; ++i) {
    x1[i] = c0 * d[i] + c1 * v[i] + a[i];
    x2[i] = c2 * d[i] + v[i];
  }
  const int block_rows = (n + kBlock - 1) / kBlock;
  for (int I = 0; I < block_rows; ++I) {
    const int i0 = I * kBlock, rows = std::min(kBlock, n - i0);
    double sum_m[kBlock] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    if (c_values == nullptr && g != nullptr)  // the sum starts at the gravity load, as a row loop's would
      for (int r = 0; r < rows; ++r) sum_m[r] = g[i0 + r];
    addBlockRow(m_col, m_values, m_start[I], m_start[I + 1], x1, sum_m);
    if (c_values == nullptr) {
      for (int r = 0; r < rows; ++r) rhs[i0 + r] = sum_m[r];
      continue;
    }
    double sum_c[kBlock] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    addBlockRow(c_col, c_values, c_start[I], c_start[I + 1], x2, sum_c);
    for (int r = 0; r < rows; ++r) rhs[i0 + r] = (g ? g[i0 + r] : 0.0) + (sum_m[r] + sum_c[r]);
  }
}

// a_{n+1} = c0 (d_{n+1} - d_n) - c1 v_n - a_n ;  v_{n+1} = v_n + h/2 (a_n + a_{n+1}) over [begin, end).
RAIL_NEWMARK_KERNEL
void completeNewmarkRows(int begin, int end, double c0, double c1, double half_h, const double* d_new, double* d,
                         double* v, double* a) {
  for (int i = begin; i < end; ++i) {
    const double a_new = c0 * (d_new[i] - d[i]) - c1 * v[i] - a[i];
    v[i] += half_h * (a[i] + a_new);
    a[i] = a_new;
    d[i] = d_new[i];
  }
}

#undef RAIL_NEWMARK_KERNEL

}  // namespace

void NewmarkIntegrator::BlockRows::build(const Eigen::SparseMatrix<double, Eigen::RowMajor>& A, int block_rows) {
  start.assign(static_cast<std::size_t>(block_rows) + 1, 0);
  col.clear();
  values.clear();
  std::vector<int> slot(static_cast<std::size_t>(block_rows), -1);  // block column -> block in this block row
  for (int I = 0; I < block_rows; ++I) {
    const int first = static_cast<int>(col.size());
    for (int r = 0; r < kBlock && I * kBlock + r < A.rows(); ++r)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(A, I * kBlock + r); it; ++it)
        if (it.value() != 0.0 && slot[static_cast<std::size_t>(it.col() / kBlock)] < 0) {
          slot[static_cast<std::size_t>(it.col() / kBlock)] = 0;
          col.push_back(static_cast<int>(it.col() / kBlock));
        }
    std::sort(col.begin() + first, col.end());
    for (int b = first; b < static_cast<int>(col.size()); ++b) slot[static_cast<std::size_t>(col[b])] = b;
    values.resize(col.size() * kBlock * kBlock, 0.0);
    for (int r = 0; r < kBlock && I * kBlock + r < A.rows(); ++r)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(A, I * kBlock + r); it; ++it)
        if (it.value() != 0.0)
          values[static_cast<std::size_t>(slot[static_cast<std::size_t>(it.col() / kBlock)]) * kBlock * kBlock +
                 static_cast<std::size_t>(it.col() % kBlock) * kBlock + static_cast<std::size_t>(r)] = it.value();
    for (int b = first; b < static_cast<int>(col.size()); ++b) slot[static_cast<std::size_t>(col[b])] = -1;
    start[static_cast<std::size_t>(I) + 1] = static_cast<int>(col.size());
  }
}

NewmarkIntegrator::NewmarkIntegrator(const LinearSystem& sys, double dt, bool include_gravity,
                                     rail::core::CostClock* cost, int end_dashpots, CholeskyLayout layout)
    : sys_(sys),
      dt_(dt),
      include_gravity_(include_gravity),
      damped_(sys.C.nonZeros() > 0),
      cost_(cost),
      end_dashpots_(end_dashpots) {
  if (!(dt > 0.0))
    throw std::runtime_error("NewmarkIntegrator: time step must be positive, got " + contact::formatNumber(dt));
  const int n = sys.size();
  if (sys.K.rows() != n || sys.C.rows() != n || (include_gravity && sys.f_gravity.size() != n))
    throw std::runtime_error("NewmarkIntegrator: M, C, K and f_gravity sizes differ");
  const Eigen::SparseMatrix<double> K_eff = sys.K + (4.0 / (dt * dt)) * sys.M + (2.0 / dt) * sys.C;
  factor_.reset(new SparseCholesky(K_eff, layout));
  const int block_rows = (n + kBlock - 1) / kBlock;
  m_blocks_.build(sys.M, block_rows);
  c_blocks_.build(sys.C, block_rows);
  rhs_.setZero(n);
  x1_.setZero(static_cast<Eigen::Index>(block_rows) * kBlock);
  x2_.setZero(static_cast<Eigen::Index>(block_rows) * kBlock);
  d_new_.setZero(n);
}

NewmarkState NewmarkIntegrator::initialState(const Eigen::VectorXd& d0, const NodalLoads* loads) const {
  const int n = sys_.size();
  NewmarkState st;
  st.d = d0;
  st.v = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
  if (include_gravity_) f += sys_.f_gravity;
  if (loads)
    for (int k = 0; k < loads->size(); ++k) f(loads->index(k)) += loads->value(k);
  f -= sys_.K * d0;
  SparseCholesky Mfac(sys_.M);
  st.a.resize(n);
  Mfac.solve(f, st.a);
  st.t = 0.0;
  return st;
}

void NewmarkIntegrator::step(NewmarkState& st, const NodalLoads& loads, const NodalLoads* more) {
  solveStep(st, loads, more);
  completeStep(st);
}

void NewmarkIntegrator::solveStep(const NewmarkState& st, const NodalLoads& loads, const NodalLoads* more) {
  buildRhs(st, loads, more);
  rail::core::CostClock::Scope timing(cost_, rail::core::CostClock::kTrackSolve);
  factor_->solve(rhs_, d_new_);
}

void NewmarkIntegrator::buildRhs(const NewmarkState& st, const NodalLoads& loads, const NodalLoads* more) {
  const double h = dt_;
  const double c0 = 4.0 / (h * h), c1 = 4.0 / h, c2 = 2.0 / h;
  {
    rail::core::CostClock::Scope timing(cost_, rail::core::CostClock::kTrackRhs);
    // K_eff d_{n+1} = f_{n+1} + M (c0 d + c1 v + a) + C (c2 d + v), both products in one pass over the rows.
    rightHandSideRows(static_cast<int>(rhs_.size()), c0, c1, c2, st.d.data(), st.v.data(), st.a.data(),
                      include_gravity_ ? sys_.f_gravity.data() : nullptr, m_blocks_.start.data(), m_blocks_.col.data(),
                      m_blocks_.values.data(), c_blocks_.start.data(), c_blocks_.col.data(),
                      damped_ ? c_blocks_.values.data() : nullptr, x1_.data(), x2_.data(), rhs_.data());
    if (damped_ && cost_ != nullptr) {
      ++cost_->counts[rail::core::CostClock::kDampingProducts];
      cost_->counts[rail::core::CostClock::kEndDashpotForces] += end_dashpots_;
    }
    for (int k = 0; k < loads.size(); ++k) rhs_(loads.index(k)) += loads.value(k);
    if (more != nullptr)
      for (int k = 0; k < more->size(); ++k) rhs_(more->index(k)) += more->value(k);
  }
}

void NewmarkIntegrator::completeStep(NewmarkState& st) {
  rail::core::CostClock::Scope timing(cost_, rail::core::CostClock::kTrackRhs);
  completeRows(st, 0, static_cast<int>(d_new_.size()));
  advanceTime(st);
}

void NewmarkIntegrator::completeRows(NewmarkState& st, int begin, int end) const noexcept {
  const double h = dt_;
  const double c0 = 4.0 / (h * h), c1 = 4.0 / h;
  completeNewmarkRows(begin, end, c0, c1, 0.5 * h, d_new_.data(), st.d.data(), st.v.data(), st.a.data());
}

Eigen::VectorXd solveStatic(const LinearSystem& sys, const Eigen::VectorXd& f) {
  SparseCholesky K(sys.K);
  Eigen::VectorXd d(sys.size());
  K.solve(f, d);
  return d;
}

Eigen::VectorXd staticGravityDeflection(const LinearSystem& sys) { return solveStatic(sys, sys.f_gravity); }

double mechanicalEnergy(const LinearSystem& sys, const NewmarkState& st) {
  return 0.5 * st.v.dot(sys.M * st.v) + 0.5 * st.d.dot(sys.K * st.d);
}

}  // namespace track
}  // namespace rail
