#include "rail_contact/creepage.hpp"

#include <algorithm>
#include <cmath>

namespace rail::contact {

double regularisedSpeed(double V, const CreepageOptions& o) noexcept {
  const double eps = o.v_eps > 0.0 ? o.v_eps : 1.0e-6;
  if (!std::isfinite(V)) return eps;
  return o.mode == SpeedRegularisation::kSmooth ? std::hypot(V, eps) : std::max(std::abs(V), eps);
}

Creepages computeCreepages(const Eigen::Vector3d& v_rel_in_contact, double omega_rel_normal, double V,
                           const CreepageOptions& o) noexcept {
  Creepages c;
  c.V_ref = regularisedSpeed(V, o);
  const double inv = 1.0 / c.V_ref;
  c.nu_x = v_rel_in_contact.x() * inv;
  c.nu_y = v_rel_in_contact.y() * inv;
  c.phi = omega_rel_normal * inv;
  return c;
}

Creepages computeCreepages(const Eigen::Vector3d& v_wheel_point_in_world, const Eigen::Vector3d& v_rail_point_in_world,
                           const Eigen::Vector3d& omega_wheel_in_world, const Eigen::Vector3d& omega_rail_in_world,
                           const Eigen::Matrix3d& R_contact_to_world, double V, const CreepageOptions& o) noexcept {
  const Eigen::Vector3d v_rel_in_contact =
      R_contact_to_world.transpose() * (v_wheel_point_in_world - v_rail_point_in_world);
  const double omega_rel_normal = R_contact_to_world.col(2).dot(omega_wheel_in_world - omega_rail_in_world);
  return computeCreepages(v_rel_in_contact, omega_rel_normal, V, o);
}

}  // namespace rail::contact
