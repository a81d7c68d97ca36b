// Creepages (nu_x, nu_y, phi) at a wheel-rail contact point.
// Contact frame: x along rolling direction (t_w), y lateral (t_u), z along the contact normal.
#pragma once

#include <Eigen/Core>

namespace rail::contact {

/// How the reference speed is kept away from zero.
enum class SpeedRegularisation {
  kSmooth,  ///< V_ref = sqrt(V^2 + v_eps^2): smooth, no kink; slightly lowers creepages at low speed
  kMax,     ///< V_ref = max(|V|, v_eps): exact above v_eps, kink at |V| = v_eps
};

/// Options (constant after building).
struct CreepageOptions {
  /// Regularisation speed [m/s]. Below it the creepages stop growing as 1/V and the creep forces
  /// act as a linear viscous law in the slip velocity, so standstill gives finite forces.
  double v_eps = 0.1;
  SpeedRegularisation mode = SpeedRegularisation::kSmooth;
};

/// Creepages and the regularised reference speed used.
struct Creepages {
  double nu_x = 0.0;   ///< longitudinal creepage [-]
  double nu_y = 0.0;   ///< lateral creepage [-]
  double phi = 0.0;    ///< spin creepage [1/m]
  double V_ref = 0.0;  ///< regularised reference speed [m/s]
};

/// Regularised reference speed [m/s] (never below v_eps > 0; v_eps <= 0 is treated as 1e-6 m/s).
double regularisedSpeed(double V, const CreepageOptions& options) noexcept;

/// Creepages from the relative velocity of the wheel material point w.r.t. the rail material
/// point at the contact, in the contact frame [m/s], the relative angular velocity of the wheel
/// w.r.t. the rail about the contact normal [rad/s], and the rolling speed V [m/s]:
///   nu_x = v_rel_x / V_ref, nu_y = v_rel_y / V_ref, phi = omega_rel_n / V_ref.
Creepages computeCreepages(const Eigen::Vector3d& v_rel_in_contact, double omega_rel_normal, double V,
                           const CreepageOptions& options) noexcept;

/// Same, from world-frame velocities of the two material points and angular velocities of the
/// two bodies; R_contact_to_world has columns (t_rolling, t_lateral, n) in world coordinates.
Creepages computeCreepages(const Eigen::Vector3d& v_wheel_point_in_world, const Eigen::Vector3d& v_rail_point_in_world,
                           const Eigen::Vector3d& omega_wheel_in_world, const Eigen::Vector3d& omega_rail_in_world,
                           const Eigen::Matrix3d& R_contact_to_world, double V,
                           const CreepageOptions& options) noexcept;

}  // namespace rail::contact
