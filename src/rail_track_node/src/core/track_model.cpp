#include "rail_track_node/track_model.hpp"

#include <vector>

namespace rail {
namespace track {

namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

// Scatters a dense element matrix over the free DOFs listed in dofs (-1 entries are fixed and skipped).
template <int N>
void scatter(Triplets& out, const Eigen::Matrix<double, N, N>& m, const int (&dofs)[N]) {
  for (int r = 0; r < N; ++r) {
    if (dofs[r] < 0) continue;
    for (int c = 0; c < N; ++c) {
      if (dofs[c] < 0 || m(r, c) == 0.0) continue;
      out.emplace_back(dofs[r], dofs[c], m(r, c));
    }
  }
}

template <int NN>
void nodeDofs(const TrackMesh& mesh, const int (&nodes)[NN], int (&dofs)[6 * NN]) {
  for (int q = 0; q < NN; ++q)
    for (int d = 0; d < 6; ++d) dofs[6 * q + d] = nodes[q] < 0 ? -1 : mesh.dofIndex(nodes[q], d);
}

}  // namespace

LinearSystem assembleLinearSystem(const TrackMesh& mesh, const TrackData& data, const Eigen::Vector3d& g_in_world) {
  const int n = mesh.n_free_dofs;
  Triplets tm, tc, tk;
  const std::size_t estimate = 144 * mesh.beams.size() + 144 * mesh.springs.size();
  tm.reserve(estimate);
  tc.reserve(estimate);
  tk.reserve(estimate);

  for (const BeamElement& b : mesh.beams) {
    const BeamSection& sec = b.kind == BeamKind::Rail ? data.rail : data.sleeper;
    const Matrix12d T = beamWorldToLocal(b.R_local_to_world);
    const Matrix12d K = T.transpose() * beamStiffnessLocal(sec, b.length) * T;
    const Matrix12d M = T.transpose() * beamConsistentMassLocal(sec, b.length) * T;
    const Matrix12d C = sec.rayleigh_alpha * M + sec.rayleigh_beta * K;
    const int nodes[2] = {b.node_i, b.node_j};
    int dofs[12];
    nodeDofs(mesh, nodes, dofs);
    scatter(tk, K, dofs);
    scatter(tm, M, dofs);
    scatter(tc, C, dofs);
  }

  for (const SpringDamperElement& s : mesh.springs) {
    const Eigen::Vector3d r_a = s.p_point_in_world - mesh.nodes[s.node_a].p_in_world;
    if (s.node_b < 0) {
      const int nodes[1] = {s.node_a};
      int dofs[6];
      nodeDofs(mesh, nodes, dofs);
      scatter(tk, groundSpringDamperMatrix(s.k, s.R_local_to_world, r_a), dofs);
      scatter(tc, groundSpringDamperMatrix(s.c, s.R_local_to_world, r_a), dofs);
    } else {
      const Eigen::Vector3d r_b = s.p_point_in_world - mesh.nodes[s.node_b].p_in_world;
      const int nodes[2] = {s.node_a, s.node_b};
      int dofs[12];
      nodeDofs(mesh, nodes, dofs);
      scatter(tk, springDamperMatrix(s.k, s.R_local_to_world, r_a, r_b), dofs);
      scatter(tc, springDamperMatrix(s.c, s.R_local_to_world, r_a, r_b), dofs);
    }
  }

  for (const PointMass& pm : mesh.masses)
    for (int d = 0; d < 3; ++d) {
      const int i = mesh.dofIndex(pm.node, d);
      if (i >= 0) tm.emplace_back(i, i, pm.mass);
    }

  LinearSystem sys;
  sys.M.resize(n, n);
  sys.C.resize(n, n);
  sys.K.resize(n, n);
  sys.M.setFromTriplets(tm.begin(), tm.end());
  sys.C.setFromTriplets(tc.begin(), tc.end());
  sys.K.setFromTriplets(tk.begin(), tk.end());
  sys.M.makeCompressed();
  sys.C.makeCompressed();
  sys.K.makeCompressed();

  Eigen::VectorXd u_g = Eigen::VectorXd::Zero(n);
  for (std::size_t node = 0; node < mesh.nodes.size(); ++node)
    for (int d = 0; d < 3; ++d) {
      const int i = mesh.dofIndex(static_cast<int>(node), d);
      if (i >= 0) u_g(i) = g_in_world(d);
    }
  sys.f_gravity = sys.M * u_g;
  return sys;
}

TrackModel buildTrackModel(const TrackData& data, const MeshOptions& options, const TrackFrameFunction& frame,
                           const Eigen::Vector3d& g_in_world) {
  TrackModel model;
  model.data = data;
  model.mesh = buildTrackMesh(data, options, frame);
  model.system = assembleLinearSystem(model.mesh, data, g_in_world);
  return model;
}

}  // namespace track
}  // namespace rail
