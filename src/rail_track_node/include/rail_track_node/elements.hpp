// Element matrices of the track finite element model (paper section 3.1): 3-D Euler-Bernoulli beams
// (rails, sleepers), 6-DOF spring-dampers (pads, ballast, sleeper interaction, absorbing ends), Rayleigh
// damping. SI units; rotations in rad.
//
// Nodal DOF order (6 per node): 3 displacements then 3 small rotations. Beam element DOF vector (12):
// [u_i, v_i, w_i, theta_x_i, theta_y_i, theta_z_i, u_j, ..., theta_z_j] in the element local frame
// (x along the axis from node i to node j, y and z principal axes of the section), the same ordering as
// rail_contact/beam_shape.hpp.
#pragma once

#include <Eigen/Core>

namespace rail {
namespace track {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Matrix12d = Eigen::Matrix<double, 12, 12>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

/// Cross-section and material of a beam (paper Table 1 symbols in brackets).
struct BeamSection {
  double E = 0.0;               ///< Young's modulus [E], Pa
  double G = 0.0;               ///< shear modulus [G], Pa
  double A = 0.0;               ///< area [A], m^2
  double J = 0.0;               ///< torsion constant used in G J [J_xixi], m^4
  double I_y = 0.0;             ///< second moment about local y [I_etaeta]: bending in the x-z plane, m^4
  double I_z = 0.0;             ///< second moment about local z [I_zetazeta]: bending in the x-y plane, m^4
  double rho = 0.0;             ///< density [rho], kg/m^3
  double rayleigh_alpha = 0.0;  ///< mass-proportional Rayleigh coefficient, 1/s (C = alpha M + beta K)
  double rayleigh_beta = 0.0;   ///< stiffness-proportional Rayleigh coefficient, s
};

/// 12x12 stiffness of a beam of length L (m) in its local frame (N/m, N, N m).
Matrix12d beamStiffnessLocal(const BeamSection& section, double L);

/// 12x12 consistent mass of a beam of length L in its local frame (kg, kg m, kg m^2): Hermite cubic
/// bending, linear axial, linear torsion with the polar mass rho (I_y + I_z) per unit length.
/// Rotary inertia of bending is not included (Euler-Bernoulli).
Matrix12d beamConsistentMassLocal(const BeamSection& section, double L);

/// 12x12 block-diagonal transformation T with d_local = T d_world; R_local_to_world has the local x, y, z
/// axes (in world coordinates) as columns. Element matrices transform as K_world = T^T K_local T.
Matrix12d beamWorldToLocal(const Eigen::Matrix3d& R_local_to_world);

/// Rayleigh damping ratio zeta(omega) = alpha / (2 omega) + beta omega / 2 (omega in rad/s).
double rayleighDampingRatio(double alpha, double beta, double omega);

/// 12x12 stiffness (or damping) of a 6-DOF spring-damper joining nodes a and b through a point P.
/// Each node is rigidly attached to P; the element resists the relative motion at P of b with respect to a,
/// measured in the element frame (columns of R_local_to_world): 3 translations and 3 small rotations with
/// the per-direction coefficients diag (N/m for the first three, N m/rad for the rotations; the same
/// formula with damping coefficients gives the damping matrix). r_a_to_P and r_b_to_P are the world
/// vectors from each node to P. DOF order: node a (6) then node b (6), world frame.
Matrix12d springDamperMatrix(const Vector6d& diag, const Eigen::Matrix3d& R_local_to_world,
                             const Eigen::Vector3d& r_a_to_P, const Eigen::Vector3d& r_b_to_P);

/// 6x6 matrix of a spring-damper from node a to the fixed ground through point P (see springDamperMatrix).
Matrix6d groundSpringDamperMatrix(const Vector6d& diag, const Eigen::Matrix3d& R_local_to_world,
                                  const Eigen::Vector3d& r_a_to_P);

/// Dashpot coefficients that absorb waves leaving a rail end, in the rail local frame
/// [axial, lateral (y), vertical (z), torsion, rotation about y, rotation about z]:
///   axial   c = A sqrt(E rho)                        (impedance of a rod)
///   torsion c = sqrt(G J rho (I_y + I_z))            (impedance of a shaft)
///   bending (per plane, I = I_y for z / rotation y, I = I_z for y / rotation z): a propagating flexural
///   wave of the beam on a Winkler foundation k_f (N/m^2) at the design angular frequency omega0 has
///   wavenumber kappa with E I kappa^4 = rho A omega0^2 - k_f (free-beam value if omega0 is below cut-off);
///   the end forces of that wave are in phase with the velocities: c_force = E I kappa^3 / omega0,
///   c_moment = E I kappa / omega0.
Vector6d absorbingEndDashpots(const BeamSection& rail, double k_foundation_lateral, double k_foundation_vertical,
                              double omega0);

}  // namespace track
}  // namespace rail
