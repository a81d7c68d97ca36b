// Rail deformation providers for the contact search on a flexible track (paper section 4.1, eqs. 6-8).
//
// A provider gives, at a rail side and track arc length s (m), the motion of the rail cross-section centre
// (the beam's centre line): displacement u and small rotation theta with their derivatives along s and
// their velocities, all in world axes. The contact search applies it to the rigid rail surface (eq. 8):
//   r = c0 + u + A(theta) (r_rigid - c0),   A(theta) = exp([theta]x) (first order: I + [theta]x, eq. 7)
// with c0 the rigid section centre.
//
// Providers are plain classes with the member
//   void sectionMotion(RailSide side, double s, RailSectionMotion& out) const noexcept;
// and a compile-time flag kRigid. The contact code is a template over the provider type, so the rigid
// case compiles to no deformation arithmetic and no call at all (if constexpr on kRigid), and the beam
// case is a direct (inlinable) call. RailDeformation is an abstract base for user providers (one virtual
// call per Newton iteration).
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "rail_contact/track_geometry.hpp"

namespace rail {
namespace contact {

using Vector6d = Eigen::Matrix<double, 6, 1>;

/// Motion of one rail cross-section centre, world axes.
struct RailSectionMotion {
  Eigen::Vector3d u = Eigen::Vector3d::Zero();          ///< displacement of the section centre, m
  Eigen::Vector3d theta = Eigen::Vector3d::Zero();      ///< small rotation vector of the section, rad
  Eigen::Vector3d du_ds = Eigen::Vector3d::Zero();      ///< d u / d s, -
  Eigen::Vector3d dtheta_ds = Eigen::Vector3d::Zero();  ///< d theta / d s, rad/m
  Eigen::Vector3d u_dot = Eigen::Vector3d::Zero();      ///< velocity of the section centre, m/s
  Eigen::Vector3d theta_dot = Eigen::Vector3d::Zero();  ///< angular velocity of the section, rad/s
  void setZero() noexcept {
    u.setZero();
    theta.setZero();
    du_ds.setZero();
    dtheta_ds.setZero();
    u_dot.setZero();
    theta_dot.setZero();
  }
};

/// Rigid track: every section at rest. Costs nothing: templated contact code skips the deformation terms.
struct RigidRailDeformation {
  static constexpr bool kRigid = true;
  void sectionMotion(RailSide, double, RailSectionMotion& out) const noexcept { out.setZero(); }
};

/// Abstract provider for user-defined deformation (one virtual call per evaluation).
class RailDeformation {
 public:
  static constexpr bool kRigid = false;
  virtual ~RailDeformation() = default;
  /// Section motion at (side, s), world axes; must not throw or allocate.
  virtual void sectionMotion(RailSide side, double s, RailSectionMotion& out) const noexcept = 0;
};

/// One rail beam element: chord length and local frame (columns: local x from node i to node j, y, z).
struct RailBeamElement {
  double length = 0.0;  ///< m
  Eigen::Matrix3d R_local_to_world = Eigen::Matrix3d::Identity();
};

/// Rails discretised by two-node Euler-Bernoulli beams (beam_shape.hpp), nodes equally spaced in the
/// track arc length: node k of a rail at s = s_start + k * element_arc_length, element k between nodes k
/// and k + 1. The layout is constant after construction; the nodal values are written by the FE code
/// into preallocated arrays, 6 doubles per node [u_x u_y u_z theta_x theta_y theta_z] in world axes (m,
/// rad), node-major, and the same layout for the velocities (m/s, rad/s). Beyond the first or last node
/// the section is at rest.
class BeamRailDeformation {
 public:
  static constexpr bool kRigid = false;

  /// elements[side] lists the elements of that rail in order of s. Throws std::runtime_error on a
  /// non-positive spacing or element length, or an empty rail.
  BeamRailDeformation(double s_start, double element_arc_length, std::array<std::vector<RailBeamElement>, 2> elements);

  int numNodes(RailSide side) const { return static_cast<int>(elements_[idx(side)].size()) + 1; }
  double sStart() const { return s_start_; }
  double elementArcLength() const { return h_; }

  /// Contiguous nodal displacement array of a rail (6 * numNodes doubles), for the FE code to fill.
  double* nodalDisplacements(RailSide side) { return q_[idx(side)].data(); }
  /// Contiguous nodal velocity array of a rail (6 * numNodes doubles).
  double* nodalVelocities(RailSide side) { return qdot_[idx(side)].data(); }
  /// Typed access to node k's 6 displacement / velocity values (world axes).
  Eigen::Map<Vector6d> nodeDisplacement(RailSide side, int k) {
    return Eigen::Map<Vector6d>(q_[idx(side)].data() + 6 * k);
  }
  Eigen::Map<Vector6d> nodeVelocity(RailSide side, int k) {
    return Eigen::Map<Vector6d>(qdot_[idx(side)].data() + 6 * k);
  }
  /// Zeroes all nodal values.
  void setZero();

  /// Section motion at (side, s) from the element shape functions (eq. 6); no allocation, no exception.
  void sectionMotion(RailSide side, double s, RailSectionMotion& out) const noexcept;

  /// Element index and coordinate xi in [0, 1] of arc length s; false outside the rail.
  bool locate(RailSide side, double s, int& element, double& xi) const noexcept;

 private:
  static int idx(RailSide side) { return side == RailSide::kLeft ? 0 : 1; }
  double s_start_ = 0.0, h_ = 0.0;
  std::array<std::vector<RailBeamElement>, 2> elements_;
  std::array<std::vector<double>, 2> q_, qdot_;
};

/// Rotation matrix exp([theta]x) (Rodrigues), the finite form of the paper's small-rotation matrix (eq. 7).
Eigen::Matrix3d smallRotationMatrix(const Eigen::Vector3d& theta) noexcept;

}  // namespace contact
}  // namespace rail
