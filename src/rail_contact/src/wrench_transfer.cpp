#include "rail_contact/wrench_transfer.hpp"

#include <Eigen/Geometry>

namespace rail::contact {

WheelsetWrench wheelCentreWrench(const Eigen::Vector3d& f_tread_on_wheel_in_world,
                                 const Eigen::Vector3d& f_flange_on_wheel_in_world,
                                 const Eigen::Vector3d& s_tread_from_wheel_centre_in_wheelset,
                                 const Eigen::Vector3d& s_flange_from_wheel_centre_in_wheelset,
                                 const Eigen::Matrix3d& R_wheelset_to_world) noexcept {
  WheelsetWrench w;
  w.force_in_world = f_tread_on_wheel_in_world + f_flange_on_wheel_in_world;
  const Eigen::Vector3d f_tread_in_wheelset = R_wheelset_to_world.transpose() * f_tread_on_wheel_in_world;
  const Eigen::Vector3d f_flange_in_wheelset = R_wheelset_to_world.transpose() * f_flange_on_wheel_in_world;
  w.moment_in_wheelset = s_tread_from_wheel_centre_in_wheelset.cross(f_tread_in_wheelset) +
                         s_flange_from_wheel_centre_in_wheelset.cross(f_flange_in_wheelset);
  return w;
}

WheelsetWrench wheelsetCentreWrench(const WheelsetWrench& wheel_centre,
                                    const Eigen::Vector3d& s_wheel_centre_from_wheelset_centre_in_wheelset,
                                    const Eigen::Matrix3d& R_wheelset_to_world) noexcept {
  WheelsetWrench w;
  w.force_in_world = wheel_centre.force_in_world;
  const Eigen::Vector3d f_in_wheelset = R_wheelset_to_world.transpose() * wheel_centre.force_in_world;
  w.moment_in_wheelset =
      s_wheel_centre_from_wheelset_centre_in_wheelset.cross(f_in_wheelset) + wheel_centre.moment_in_wheelset;
  return w;
}

void accumulate(WheelsetWrench& sum, const WheelsetWrench& w) noexcept {
  sum.force_in_world += w.force_in_world;
  sum.moment_in_wheelset += w.moment_in_wheelset;
}

RailWrench railSectionWrench(const Eigen::Vector3d& f_tread_on_rail_in_world,
                             const Eigen::Vector3d& f_flange_on_rail_in_world,
                             const Eigen::Vector3d& s_tread_from_section_centre_in_world,
                             const Eigen::Vector3d& s_flange_from_section_centre_in_world) noexcept {
  RailWrench w;
  w.force_in_world = f_tread_on_rail_in_world + f_flange_on_rail_in_world;
  w.moment_in_world = s_tread_from_section_centre_in_world.cross(f_tread_on_rail_in_world) +
                      s_flange_from_section_centre_in_world.cross(f_flange_on_rail_in_world);
  return w;
}

}  // namespace rail::contact
