// Assembled track model (paper eq. 2: M a + C v + K d = f_track): global sparse M, C, K over the free DOFs
// of a TrackMesh and the gravity load f_g. Built once; constant afterwards.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "rail_track_node/track_data.hpp"
#include "rail_track_node/track_mesh.hpp"

namespace rail {
namespace track {

/// Linear second-order system M a + C v + K d = f_gravity + f_external (free DOFs only).
struct LinearSystem {
  Eigen::SparseMatrix<double> M;  ///< mass, kg (kg m^2 on rotations)
  Eigen::SparseMatrix<double> C;  ///< damping, N s/m
  Eigen::SparseMatrix<double> K;  ///< stiffness, N/m
  Eigen::VectorXd f_gravity;      ///< gravity load f_g, N (N m on rotations)

  int size() const { return static_cast<int>(M.rows()); }
};

/// Mesh + data + assembled matrices.
struct TrackModel {
  TrackData data;
  TrackMesh mesh;
  LinearSystem system;
};

/// Assembles M (consistent beam mass + lumped point masses), C (Rayleigh damping of each beam family,
/// C_e = alpha M_e + beta K_e, plus the spring-damper dampers) and K over the mesh's free DOFs, and
/// f_g = M u_g where u_g holds g_in_world (m/s^2) on every node's translations.
LinearSystem assembleLinearSystem(const TrackMesh& mesh, const TrackData& data, const Eigen::Vector3d& g_in_world);

/// Builds the mesh from the frames and assembles it (gravity g_in_world, default 9.81 m/s^2 down world z).
TrackModel buildTrackModel(const TrackData& data, const MeshOptions& options, const TrackFrameFunction& frame,
                           const Eigen::Vector3d& g_in_world = Eigen::Vector3d(0.0, 0.0, -9.81));

}  // namespace track
}  // namespace rail
