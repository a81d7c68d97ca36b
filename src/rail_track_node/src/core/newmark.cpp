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
  // Rows of M and C merged over the union of their column indices (zeros where only one has an entry).
  const Eigen::SparseMatrix<double, Eigen::RowMajor> M_rows = sys.M, C_rows = sys.C;
  row_start_.assign(static_cast<std::size_t>(n) + 1, 0);
  col_.reserve(static_cast<std::size_t>(M_rows.nonZeros() + C_rows.nonZeros()));
  m_.reserve(col_.capacity());
  c_.reserve(col_.capacity());
  for (int i = 0; i < n; ++i) {
    Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator pm(M_rows, i), pc(C_rows, i);
    while (pm || pc) {
      const int j = !pc ? pm.col() : !pm ? pc.col() : std::min(pm.col(), pc.col());
      double m = 0.0, c = 0.0;
      if (pm && pm.col() == j) {
        m = pm.value();
        ++pm;
      }
      if (pc && pc.col() == j) {
        c = pc.value();
        ++pc;
      }
      col_.push_back(j);
      m_.push_back(m);
      c_.push_back(c);
    }
    row_start_[static_cast<std::size_t>(i) + 1] = static_cast<int>(col_.size());
  }
  rhs_.setZero(n);
  x1_.setZero(n);
  x2_.setZero(n);
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
    const int* start = row_start_.data();
    const int* col = col_.data();
    const double* m = m_.data();
    const double* c = c_.data();
    const double* g = include_gravity_ ? sys_.f_gravity.data() : nullptr;
    double* rhs = rhs_.data();
    if (damped_) {
      for (int i = 0; i < n; ++i) {
        double sum_m = 0.0, sum_c = 0.0;  // two chains of additions
        for (int p = start[i]; p < start[i + 1]; ++p) {
          sum_m += m[p] * x1[col[p]];
          sum_c += c[p] * x2[col[p]];
        }
        rhs[i] = (g ? g[i] : 0.0) + (sum_m + sum_c);
      }
      if (cost_ != nullptr) {
        ++cost_->counts[rail::core::CostClock::kDampingProducts];
        cost_->counts[rail::core::CostClock::kEndDashpotForces] += end_dashpots_;
      }
    } else {
      for (int i = 0; i < n; ++i) {
        double sum = g ? g[i] : 0.0;
        for (int p = start[i]; p < start[i + 1]; ++p) sum += m[p] * x1[col[p]];
        rhs[i] = sum;
      }
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
