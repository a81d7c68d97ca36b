// The track's outputs as rail_msgs, filled in place (no allocation): a rail section's deflection.
#pragma once

#include <ros/time.h>

#include <rail_msgs/RailDeflection.h>

#include "rail_track_node/track_simulator.hpp"

namespace rail::track {

inline void fill(geometry_msgs::Vector3& out, const Eigen::Vector3d& v) {
  out.x = v.x();
  out.y = v.y();
  out.z = v.z();
}

// Both rails' displacement and rotation at one section (track frame), stamped.
inline void fill(rail_msgs::RailDeflection& out, const RailSectionDeflection& deflection, const ros::Time& stamp) {
  out.header.stamp = stamp;
  out.arc_length = deflection.arc_length;
  fill(out.left_displacement, deflection.displacement[kLeftRail]);
  fill(out.left_rotation, deflection.rotation[kLeftRail]);
  fill(out.right_displacement, deflection.displacement[kRightRail]);
  fill(out.right_rotation, deflection.rotation[kRightRail]);
}

}  // namespace rail::track
