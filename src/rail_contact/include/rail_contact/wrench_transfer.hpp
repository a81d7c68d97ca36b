// Transfer of wheel-rail contact forces to equivalent force + moment systems
// (paper eqs. 13-15). A contact force acting at a point is replaced by the same force at a
// reference point plus the transport moment s x f, s the position of the contact point
// relative to the reference point. Forces in N, moments in N m, positions in m.
#pragma once

#include <Eigen/Core>

namespace rail::contact {

/// Resultant of contact forces on the wheelset side: force in the world (inertial) frame,
/// moment about the reference point in the wheelset body frame (the paper's n').
struct WheelsetWrench {
  Eigen::Vector3d force_in_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d moment_in_wheelset = Eigen::Vector3d::Zero();
};

/// Resultant of contact forces on a rail cross-section, all in the world frame.
struct RailWrench {
  Eigen::Vector3d force_in_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d moment_in_world = Eigen::Vector3d::Zero();
};

/// Eq. 13: tread and flange contact forces on one wheel to the wheel centre.
///   f_wheel = f_tr + f_fl
///   n'_wheel = s'_tr x (A_ws^T f_tr) + s'_fl x (A_ws^T f_fl)
/// f_*_on_wheel_in_world: contact forces on the wheel (pass zero for an inactive contact);
/// s_*_from_wheel_centre_in_wheelset: contact point minus wheel centre, wheelset frame;
/// R_wheelset_to_world: A_ws.
WheelsetWrench wheelCentreWrench(const Eigen::Vector3d& f_tread_on_wheel_in_world,
                                 const Eigen::Vector3d& f_flange_on_wheel_in_world,
                                 const Eigen::Vector3d& s_tread_from_wheel_centre_in_wheelset,
                                 const Eigen::Vector3d& s_flange_from_wheel_centre_in_wheelset,
                                 const Eigen::Matrix3d& R_wheelset_to_world) noexcept;

/// Eq. 14: a wheel-centre wrench to the wheelset mass centre.
///   f_ws = f_wheel,  n'_ws = s'_w x (A_ws^T f_wheel) + n'_wheel
/// s_wheel_centre_from_wheelset_centre_in_wheelset: s'_w.
WheelsetWrench wheelsetCentreWrench(const WheelsetWrench& wheel_centre,
                                    const Eigen::Vector3d& s_wheel_centre_from_wheelset_centre_in_wheelset,
                                    const Eigen::Matrix3d& R_wheelset_to_world) noexcept;

/// Adds `w` to `sum` (both about the same point, same frames): sums left and right wheels.
void accumulate(WheelsetWrench& sum, const WheelsetWrench& w) noexcept;

/// Eq. 15: contact forces on the rail to the rail cross-section centre.
///   f_r = f_tr,r + f_fl,r,  n_r = s_tr,r x f_tr,r + s_fl,r x f_fl,r
/// f_*_on_rail_in_world are the forces on the rail (opposite to those on the wheel);
/// s_*_from_section_centre_in_world: contact point minus section centre, world frame.
RailWrench railSectionWrench(const Eigen::Vector3d& f_tread_on_rail_in_world,
                             const Eigen::Vector3d& f_flange_on_rail_in_world,
                             const Eigen::Vector3d& s_tread_from_section_centre_in_world,
                             const Eigen::Vector3d& s_flange_from_section_centre_in_world) noexcept;

/// Eq. 15 helper: position given in rail cross-section coordinates to world: s = A_r s'.
inline Eigen::Vector3d sectionOffsetToWorld(const Eigen::Matrix3d& R_section_to_world,
                                            const Eigen::Vector3d& s_in_section) noexcept {
  return R_section_to_world * s_in_section;
}

/// Contact force on the wheel from its contact-frame components (paper eq. 12):
///   f = N n + F_long t_rolling + F_lat t_lateral, R_contact_to_world = [t_rolling t_lateral n].
inline Eigen::Vector3d contactForceInWorld(const Eigen::Matrix3d& R_contact_to_world, double F_long, double F_lat,
                                           double N) noexcept {
  return R_contact_to_world * Eigen::Vector3d(F_long, F_lat, N);
}

}  // namespace rail::contact
