// ROS glue shared by rail_vehicle and rail_track: one rail_contact contact result as a
// rail_msgs/ContactPoint (header-only; fills a message sized beforehand, no allocation).
#pragma once

#include <cstdint>

#include <rail_msgs/ContactPoint.h>
#include <rail_contact/wheel_contact.hpp>

namespace rail::ros_glue {

// One contact (kind: the surface it was detected on) of wheel `wheel_id` on rail `side` (WheelState::SIDE_*).
inline void toMessage(const rail::contact::ContactPointResult& c, int wheel_id, int side, rail_msgs::ContactPoint& p) {
  p.wheel_id = static_cast<std::uint8_t>(wheel_id);
  p.side = static_cast<std::uint8_t>(side);
  p.kind =
      c.surface == rail::contact::kTread ? rail_msgs::ContactPoint::KIND_TREAD : rail_msgs::ContactPoint::KIND_FLANGE;
  p.active = c.active;
  p.arc_length = c.s_r;
  p.position.x = c.p_contact_in_world.x();
  p.position.y = c.p_contact_in_world.y();
  p.position.z = c.p_contact_in_world.z();
  p.normal.x = c.normal_in_world.x();
  p.normal.y = c.normal_in_world.y();
  p.normal.z = c.normal_in_world.z();
  p.normal_force = c.N;
  p.creep_force_longitudinal = c.F_long;
  p.creep_force_lateral = c.F_lat;
  p.creepage_longitudinal = c.nu_x;
  p.creepage_lateral = c.nu_y;
  p.creepage_spin = c.phi;
  p.semi_axis_a = c.a;
  p.semi_axis_b = c.b;
  p.penetration = c.penetration;
  p.contact_angle = c.contact_angle;
}

}  // namespace rail::ros_glue
