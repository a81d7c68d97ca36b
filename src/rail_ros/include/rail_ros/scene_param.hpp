// ROS glue (library rail_ros, not the ROS-free core): reads the scene a launch file put on the
// parameter server.
#pragma once

#include <ros/node_handle.h>

#include <string>

#include "rail_core/scene.hpp"

namespace rail::ros_glue {

// The launch file hands the scene over as its file's text (<ns>/scene_yaml, via `textfile`) and its path
// (<ns>/scene_file); ns is ~scene_ns, default /railsim (tests give nodes different scenes this way).
// On failure logs one fatal message naming the node, the parameter or the scene's file and field, and
// returns false.
bool readScene(ros::NodeHandle& private_nh, core::Scene& scene);

}  // namespace rail::ros_glue
