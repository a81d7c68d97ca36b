// Rail-pad forces, sleeper-on-ballast forces and rail displacements at the sleepers of an FE track mesh
// (rail_msgs/RailPadForces, effects.pad_force_output). ROS-free.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <vector>

#include <rail_contact/track_geometry.hpp>

#include "rail_track_node/track_mesh.hpp"

namespace rail {
namespace track {

/// One sleeper: pad forces and rail displacements of both rails (index RailSide), track-frame components
/// at the sleeper (x along the track, y left, z normal to the canted track plane, up).
struct PadForceSample {
  double arc_length = 0.0;                                    ///< s of the sleeper, m
  std::array<Eigen::Vector3d, 2> force_in_track;              ///< rail on sleeper through the pad, N (z < 0 presses)
  std::array<Eigen::Vector3d, 2> rail_displacement_in_track;  ///< rail centre-line node at the sleeper, m
  Eigen::Vector3d
      ballast_force_in_track;  ///< sleeper on the ballast, summed over its ballast elements, N (z < 0 presses)
  /// Hanging sleeper: the open void between it and the ballast, mean over its ballast elements, m (0 where
  /// it bears, and under every sleeper that does not hang).
  double ballast_gap = 0.0;
};

/// Indexes a mesh's pads once (set-up, allocates); evaluate() then reads forces from a state without
/// allocating. The pad is the 6-DOF spring-damper between the rail node (a) and the sleeper's seat node
/// (b) acting at the rail seat P (springDamperMatrix): with the relative motion of b's point P with
/// respect to a's, Delta = (u_b + theta_b x r_bP) - (u_a + theta_a x r_aP) in the element frame R, the
/// force on the sleeper is -R (k .* R^T Delta + c .* R^T Delta_dot). A ballast element is the same
/// spring-damper between a sleeper node (a) and its foundation node (b): the force on the ballast; under a
/// hanging sleeper (SpringDamperElement::unilateral) its local z part only presses, once the void has closed.
class PadForceProbe {
 public:
  explicit PadForceProbe(const TrackMesh& mesh);

  int sleeperCount() const { return static_cast<int>(pad_.size()); }

  /// Samples at the sleepers with s in [s_from, s_to] (m) into out (at most capacity of them), in order
  /// of s; returns how many. d and v: displacements and velocities over the mesh's free DOFs; d_static
  /// (optional, same size) is added to d (a track window's self-weight state). geometry gives the track
  /// frame at each sleeper. No allocation, no exception.
  int evaluate(const TrackMesh& mesh, const rail::contact::TrackGeometry& geometry, const Eigen::VectorXd& d,
               const Eigen::VectorXd& v, const Eigen::VectorXd* d_static, double s_from, double s_to,
               PadForceSample* out, int capacity) const noexcept;

 private:
  std::vector<std::array<int, 2>> pad_;  ///< per sleeper, per rail: index into mesh.springs
  std::vector<int> ballast_start_;       ///< per sleeper k: its ballast elements are ballast_[start_k .. start_k+1)
  std::vector<int> ballast_;             ///< indices into mesh.springs
};

}  // namespace track
}  // namespace rail
