#include "rail_track_node/newmark.hpp"

#include <emmintrin.h>

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

// acc[r] += sum over the blocks [b0, b1) of A(r, j) x[j], j ascending, for the 6 rows r of a block row:
// each lane adds its row's products one by one, as a scalar row loop would (no fused multiply-add).
inline void addBlockRow(const int* col, const double* values, int b0, int b1, const double* x, __m128d acc[3]) {
  for (int b = b0; b < b1; ++b) {
    const double* B = values + static_cast<std::ptrdiff_t>(b) * kBlock * kBlock;
    const double* xb = x + static_cast<std::ptrdiff_t>(col[b]) * kBlock;
    for (int j = 0; j < kBlock; ++j) {
      const __m128d xj = _mm_set1_pd(xb[j]);
      acc[0] = _mm_add_pd(acc[0], _mm_mul_pd(_mm_loadu_pd(B + kBlock * j), xj));
      acc[1] = _mm_add_pd(acc[1], _mm_mul_pd(_mm_loadu_pd(B + kBlock * j + 2), xj));
      acc[2] = _mm_add_pd(acc[2], _mm_mul_pd(_mm_loadu_pd(B + kBlock * j + 4), xj));
    }
  }
}

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
    const int n = static_cast<int>(rhs_.size());
    const double* d = st.d.data();
    const double* v = st.v.data();
    const double* a = st.a.data();
    double* x1 = x1_.data();
    double* x2 = x2_.data();
    for (int i = 0; i < n; ++i) {
      x1[i] = c0 * d[i] + c1 * v[i] + a[i];
      x2[i] = c2 * d[i] + v[i];
    }
    const double* g = include_gravity_ ? sys_.f_gravity.data() : nullptr;
    double* rhs = rhs_.data();
    const int block_rows = static_cast<int>(m_blocks_.start.size()) - 1;
    alignas(16) double sum_m[kBlock], sum_c[kBlock];
    for (int I = 0; I < block_rows; ++I) {
      const int i0 = I * kBlock, rows = std::min(kBlock, n - i0);
      __m128d acc_m[3] = {_mm_setzero_pd(), _mm_setzero_pd(), _mm_setzero_pd()};
      if (!damped_ && g != nullptr) {  // the sum starts at the gravity load, as a row loop's would
        for (int r = 0; r < rows; ++r) sum_m[r] = g[i0 + r];
        for (int r = rows; r < kBlock; ++r) sum_m[r] = 0.0;
        for (int k = 0; k < 3; ++k) acc_m[k] = _mm_load_pd(sum_m + 2 * k);
      }
      addBlockRow(m_blocks_.col.data(), m_blocks_.values.data(), m_blocks_.start[I], m_blocks_.start[I + 1], x1, acc_m);
      for (int k = 0; k < 3; ++k) _mm_store_pd(sum_m + 2 * k, acc_m[k]);
      if (damped_) {
        __m128d acc_c[3] = {_mm_setzero_pd(), _mm_setzero_pd(), _mm_setzero_pd()};
        addBlockRow(c_blocks_.col.data(), c_blocks_.values.data(), c_blocks_.start[I], c_blocks_.start[I + 1], x2,
                    acc_c);
        for (int k = 0; k < 3; ++k) _mm_store_pd(sum_c + 2 * k, acc_c[k]);
        for (int r = 0; r < rows; ++r) rhs[i0 + r] = (g ? g[i0 + r] : 0.0) + (sum_m[r] + sum_c[r]);
      } else {
        for (int r = 0; r < rows; ++r) rhs[i0 + r] = sum_m[r];
      }
    }
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
  // a_{n+1} = c0 (d_{n+1} - d_n) - c1 v_n - a_n ;  v_{n+1} = v_n + h/2 (a_n + a_{n+1})
  const double half_h = 0.5 * h;
  double* d = st.d.data();
  double* v = st.v.data();
  double* a = st.a.data();
  const double* d_new = d_new_.data();
  for (int i = begin; i < end; ++i) {
    const double a_new = c0 * (d_new[i] - d[i]) - c1 * v[i] - a[i];
    v[i] += half_h * (a[i] + a_new);
    a[i] = a_new;
    d[i] = d_new[i];
  }
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
