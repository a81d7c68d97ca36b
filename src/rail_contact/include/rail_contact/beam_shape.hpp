// Shape functions of the two-node 3-D Euler-Bernoulli beam element (paper eqs. 6 and 16).
//
// Element local frame: x along the beam axis from node i to node j, y and z the principal axes of the
// cross-section. Element DOF vector d_e (12), all in the local frame, SI units (m, rad):
//   d_e = [u_i, v_i, w_i, theta_x_i, theta_y_i, theta_z_i,  u_j, v_j, w_j, theta_x_j, theta_y_j, theta_z_j]
// u, v, w: centre-line displacements along x, y, z; theta_*: small rotations of the cross-section about
// x, y, z. Euler-Bernoulli kinematics: theta_z = dv/ds, theta_y = -dw/ds.
// Interpolation at xi = s / L in [0, 1]: linear for u and theta_x, Hermite cubics for v and w.
#pragma once

#include <Eigen/Core>

namespace rail {
namespace contact {

using Matrix3x12 = Eigen::Matrix<double, 3, 12>;
using Vector12d = Eigen::Matrix<double, 12, 1>;

/// Centre-line displacement at xi: u(xi) = N_u * d_e (local frame, m). L: element length (m).
void beamShapeDisplacement(double xi, double L, Matrix3x12& N_u);

/// Cross-section small rotation at xi: theta(xi) = N_theta * d_e (local frame, rad).
void beamShapeRotation(double xi, double L, Matrix3x12& N_theta);

/// d N_u / ds at xi (s = xi * L is the arc length along the element, m): du/ds = dN_u_ds * d_e.
void beamShapeDisplacementDs(double xi, double L, Matrix3x12& dN_u_ds);

/// d N_theta / ds at xi: dtheta/ds = dN_theta_ds * d_e (1/m times the nodal DOFs).
void beamShapeRotationDs(double xi, double L, Matrix3x12& dN_theta_ds);

/// Equivalent nodal loads (paper eq. 16) of a concentrated force f (N) and moment m (N m) acting on the
/// centre line at xi, all in the element local frame: F_e = N_u^T f + N_theta^T m (12 entries, same
/// ordering as d_e: force then moment at node i, force then moment at node j).
Vector12d beamEquivalentNodalLoads(double xi, double L, const Eigen::Vector3d& f, const Eigen::Vector3d& m);

/// Same as beamEquivalentNodalLoads with f_world and m_world given in the world frame and the result in
/// the world frame; R_local_to_world has the element's local x, y, z axes as columns.
Vector12d beamEquivalentNodalLoadsWorld(double xi, double L, const Eigen::Matrix3d& R_local_to_world,
                                        const Eigen::Vector3d& f_world, const Eigen::Vector3d& m_world);

}  // namespace contact
}  // namespace rail
