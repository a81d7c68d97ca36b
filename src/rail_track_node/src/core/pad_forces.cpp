#include "rail_track_node/pad_forces.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rail {
namespace track {

PadForceProbe::PadForceProbe(const TrackMesh& mesh) {
  pad_.assign(static_cast<std::size_t>(mesh.n_sleepers), {-1, -1});
  const int n_e = mesh.rail_elements_between_sleepers;
  for (std::size_t i = 0; i < mesh.springs.size(); ++i) {
    const SpringDamperElement& e = mesh.springs[i];
    if (e.kind != SpringKind::Pad) continue;
    for (int r = 0; r < 2; ++r) {
      const auto& nodes = mesh.rail_nodes[static_cast<std::size_t>(r)];
      const auto it = std::find(nodes.begin(), nodes.end(), e.node_a);
      if (it == nodes.end()) continue;
      const auto k = static_cast<int>(it - nodes.begin());
      if (k % n_e == 0 && k / n_e < mesh.n_sleepers)
        pad_[static_cast<std::size_t>(k / n_e)][static_cast<std::size_t>(r)] = static_cast<int>(i);
    }
  }
  for (std::size_t k = 0; k < pad_.size(); ++k) {
    if (pad_[k][0] < 0 || pad_[k][1] < 0) {
      throw std::runtime_error("pad forces: sleeper " + std::to_string(k) + " has no pad on each rail");
    }
  }
  // Ballast elements by the sleeper of their node a.
  std::vector<int> sleeper_of(mesh.nodes.size(), -1);
  for (std::size_t k = 0; k < mesh.sleeper_nodes.size(); ++k)
    for (const int node : mesh.sleeper_nodes[k]) sleeper_of[static_cast<std::size_t>(node)] = static_cast<int>(k);
  std::vector<std::vector<int>> by_sleeper(pad_.size());
  for (std::size_t i = 0; i < mesh.springs.size(); ++i) {
    const SpringDamperElement& e = mesh.springs[i];
    if (e.kind != SpringKind::Ballast) continue;
    const int k = sleeper_of[static_cast<std::size_t>(e.node_a)];
    if (k >= 0 && k < static_cast<int>(by_sleeper.size()))
      by_sleeper[static_cast<std::size_t>(k)].push_back(static_cast<int>(i));
  }
  ballast_start_.assign(1, 0);
  for (const std::vector<int>& b : by_sleeper) {
    ballast_.insert(ballast_.end(), b.begin(), b.end());
    ballast_start_.push_back(static_cast<int>(ballast_.size()));
  }
}

namespace {

// Translation (dof 0..2) and small rotation (3..5) of a node from a free-DOF vector (fixed DOFs: 0).
void nodeMotion(const TrackMesh& mesh, int node, const Eigen::VectorXd& x, const Eigen::VectorXd* x_add,
                Eigen::Vector3d& u, Eigen::Vector3d& theta) {
  for (int j = 0; j < 6; ++j) {
    const int i = mesh.dofIndex(node, j);
    double value = 0.0;
    if (i >= 0) value = x[i] + (x_add != nullptr ? (*x_add)[i] : 0.0);
    (j < 3 ? u : theta)[j % 3] = value;
  }
}

// Motion at point P of node `node` rigidly attached to it.
Eigen::Vector3d pointMotion(const TrackMesh& mesh, int node, const Eigen::Vector3d& p, const Eigen::VectorXd& x,
                            const Eigen::VectorXd* x_add) {
  Eigen::Vector3d u, theta;
  nodeMotion(mesh, node, x, x_add, u, theta);
  return u + theta.cross(p - mesh.nodes[static_cast<std::size_t>(node)].p_in_world);
}

// Force of spring-damper e on its node b (world), translational part (see PadForceProbe).
Eigen::Vector3d forceOnB(const TrackMesh& mesh, const SpringDamperElement& e, const Eigen::VectorXd& d,
                         const Eigen::VectorXd& v, const Eigen::VectorXd* d_static) {
  const Eigen::Vector3d& P = e.p_point_in_world;
  Eigen::Vector3d delta = -pointMotion(mesh, e.node_a, P, d, d_static);
  Eigen::Vector3d delta_dot = -pointMotion(mesh, e.node_a, P, v, nullptr);
  if (e.node_b >= 0) {
    delta += pointMotion(mesh, e.node_b, P, d, d_static);
    delta_dot += pointMotion(mesh, e.node_b, P, v, nullptr);
  }
  const Eigen::Vector3d local = e.R_local_to_world.transpose() * delta;
  const Eigen::Vector3d local_dot = e.R_local_to_world.transpose() * delta_dot;
  Eigen::Vector3d f_local = -(e.k.head<3>().cwiseProduct(local) + e.c.head<3>().cwiseProduct(local_dot));
  if (e.unilateral) {
    // Hanging sleeper: local(2) = -z is the sleeper point's drop; the ballast bears once it exceeds the gap.
    const double bearing = e.k(2) * (local(2) - e.gap) + e.c(2) * local_dot(2);
    f_local(2) = bearing > 0.0 ? -bearing : 0.0;
  }
  return e.R_local_to_world * f_local;
}

// Open void between a unilateral element's point on the sleeper and the ballast, m (0 bearing).
double openGap(const TrackMesh& mesh, const SpringDamperElement& e, const Eigen::VectorXd& d,
               const Eigen::VectorXd* d_static) {
  const double drop =
      -(e.R_local_to_world.transpose() * pointMotion(mesh, e.node_a, e.p_point_in_world, d, d_static))(2);
  return e.gap - drop > 0.0 ? e.gap - drop : 0.0;
}

}  // namespace

int PadForceProbe::evaluate(const TrackMesh& mesh, const rail::contact::TrackGeometry& geometry,
                            const Eigen::VectorXd& d, const Eigen::VectorXd& v, const Eigen::VectorXd* d_static,
                            double s_from, double s_to, PadForceSample* out, int capacity) const noexcept {
  if (mesh.sleeper_spacing <= 0.0 || !(s_to >= s_from)) return 0;
  const int k0 = std::max(0, static_cast<int>(std::ceil((s_from - mesh.s_start) / mesh.sleeper_spacing - 1e-9)));
  const int k1 =
      std::min(sleeperCount() - 1, static_cast<int>(std::floor((s_to - mesh.s_start) / mesh.sleeper_spacing + 1e-9)));
  int n = 0;
  rail::contact::TrackPoint tp;
  for (int k = k0; k <= k1 && n < capacity; ++k, ++n) {
    PadForceSample& o = out[n];
    o.arc_length = mesh.s_start + k * mesh.sleeper_spacing;
    geometry.centre(o.arc_length, tp);
    for (int r = 0; r < 2; ++r) {
      const SpringDamperElement& e =
          mesh.springs[static_cast<std::size_t>(pad_[static_cast<std::size_t>(k)][static_cast<std::size_t>(r)])];
      o.force_in_track[static_cast<std::size_t>(r)] =
          tp.R_track_to_world.transpose() * forceOnB(mesh, e, d, v, d_static);
      Eigen::Vector3d u, theta;
      nodeMotion(mesh, e.node_a, d, d_static, u, theta);
      o.rail_displacement_in_track[static_cast<std::size_t>(r)] = tp.R_track_to_world.transpose() * u;
    }
    Eigen::Vector3d ballast = Eigen::Vector3d::Zero();
    double gap_sum = 0.0;
    int gaps = 0;
    for (int b = ballast_start_[static_cast<std::size_t>(k)]; b < ballast_start_[static_cast<std::size_t>(k) + 1];
         ++b) {
      const SpringDamperElement& e = mesh.springs[static_cast<std::size_t>(ballast_[static_cast<std::size_t>(b)])];
      ballast += forceOnB(mesh, e, d, v, d_static);
      if (e.unilateral) {
        gap_sum += openGap(mesh, e, d, d_static);
        ++gaps;
      }
    }
    o.ballast_force_in_track = tp.R_track_to_world.transpose() * ballast;
    o.ballast_gap = gaps > 0 ? gap_sum / gaps : 0.0;
  }
  return n;
}

}  // namespace track
}  // namespace rail
