#include "rail_track_node/hanging_support.hpp"

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>

#include <stdexcept>
#include <string>

namespace rail {
namespace track {

HangingSupports::HangingSupports(const TrackMesh& mesh) {
  for (const SpringDamperElement& s : mesh.springs) {
    if (!s.unilateral) continue;
    Element el;
    const Eigen::Vector3d n = s.R_local_to_world.col(2);
    const Eigen::Vector3d r = s.p_point_in_world - mesh.nodes[static_cast<std::size_t>(s.node_a)].p_in_world;
    el.b.head<3>() = n;
    el.b.tail<3>() = r.cross(n);
    for (int j = 0; j < 6; ++j) el.dofs[static_cast<std::size_t>(j)] = mesh.dofIndex(s.node_a, j);
    el.k = s.k(2);
    el.c = s.c(2);
    el.gap = s.gap;
    elements_.push_back(el);
  }
}

double HangingSupports::lift(int e, const Eigen::VectorXd& d, const Eigen::VectorXd* d_static) const noexcept {
  const Element& el = elements_[static_cast<std::size_t>(e)];
  double z = 0.0;
  for (int j = 0; j < 6; ++j) {
    const int i = el.dofs[static_cast<std::size_t>(j)];
    if (i >= 0) z += el.b(j) * (d(i) + (d_static != nullptr ? (*d_static)(i) : 0.0));
  }
  return z;
}

double HangingSupports::bearingForce(int e, double z, double z_dot) const noexcept {
  const Element& el = elements_[static_cast<std::size_t>(e)];
  const double f = -el.k * (z + el.gap) - el.c * z_dot;
  return f > 0.0 ? f : 0.0;
}

// Real force on the sleeper along local z minus the linear element's, -(k z + c z').
double HangingSupports::correction(const Element& el, double z, double z_dot) const noexcept {
  const double bearing = -el.k * (z + el.gap) - el.c * z_dot;
  return (bearing > 0.0 ? bearing : 0.0) + el.k * z + el.c * z_dot;
}

bool HangingSupports::addLoads(const Eigen::VectorXd& d, const Eigen::VectorXd& v, const Eigen::VectorXd* d_static,
                               double dt, NodalLoads& loads) const noexcept {
  for (const Element& el : elements_) {
    double z = 0.0, z_dot = 0.0;
    for (int j = 0; j < 6; ++j) {
      const int i = el.dofs[static_cast<std::size_t>(j)];
      if (i < 0) continue;
      z += el.b(j) * (d(i) + dt * v(i) + (d_static != nullptr ? (*d_static)(i) : 0.0));
      z_dot += el.b(j) * v(i);
    }
    const double f = correction(el, z, z_dot) - el.baseline;
    if (f == 0.0) continue;
    for (int j = 0; j < 6; ++j)
      if (el.b(j) != 0.0 && !loads.add(el.dofs[static_cast<std::size_t>(j)], el.b(j) * f)) return false;
  }
  return true;
}

void HangingSupports::setBaseline(const Eigen::VectorXd& d_static) {
  for (std::size_t e = 0; e < elements_.size(); ++e) {
    elements_[e].baseline = correction(elements_[e], lift(static_cast<int>(e), d_static, nullptr), 0.0);
  }
}

Eigen::VectorXd HangingSupports::solveStatic(const LinearSystem& sys, const Eigen::VectorXd& f) const {
  std::vector<char> closed(elements_.size(), 1);  // start from the linear track
  Eigen::VectorXd d;
  for (int pass = 0; pass < 100; ++pass) {
    // Open voids take their element out of K; closed ones push by k (closure) = -k (z + gap).
    Eigen::SparseMatrix<double> K = sys.K;
    Eigen::VectorXd rhs = f;
    std::vector<Eigen::Triplet<double>> drop;
    for (std::size_t e = 0; e < elements_.size(); ++e) {
      const Element& el = elements_[e];
      for (int a = 0; a < 6; ++a) {
        const int i = el.dofs[static_cast<std::size_t>(a)];
        if (i < 0) continue;
        if (closed[e]) {
          rhs(i) -= el.k * el.gap * el.b(a);
          continue;
        }
        for (int c = 0; c < 6; ++c) {
          const int j = el.dofs[static_cast<std::size_t>(c)];
          if (j >= 0) drop.emplace_back(i, j, -el.k * el.b(a) * el.b(c));
        }
      }
    }
    if (!drop.empty()) {
      Eigen::SparseMatrix<double> D(K.rows(), K.cols());
      D.setFromTriplets(drop.begin(), drop.end());
      K += D;
    }
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(K);
    if (ldlt.info() != Eigen::Success)
      throw std::runtime_error("hanging sleepers: the static track matrix could not be factorised");
    d = ldlt.solve(rhs);
    bool settled = true;
    for (std::size_t e = 0; e < elements_.size(); ++e) {
      const bool now = lift(static_cast<int>(e), d, nullptr) + elements_[e].gap <= 0.0;
      if (now != static_cast<bool>(closed[e])) settled = false;
      closed[e] = now ? 1 : 0;
    }
    if (settled) return d;
  }
  throw std::runtime_error("hanging sleepers: the static state's closed voids did not settle in 100 solves");
}

Eigen::VectorXd solveStaticWithSupports(const TrackMesh& mesh, const LinearSystem& sys, const Eigen::VectorXd& f) {
  const HangingSupports hanging(mesh);
  if (hanging.empty()) return solveStatic(sys, f);
  return hanging.solveStatic(sys, f);
}

}  // namespace track
}  // namespace rail
