#include "rail_ros/scene_param.hpp"

#include <ros/ros.h>

#include "rail_core/scene_loader.hpp"

namespace rail::ros_glue {

bool readScene(ros::NodeHandle& private_nh, core::Scene& scene) {
  const std::string ns = private_nh.param<std::string>("scene_ns", "/railsim");
  const std::string& node = ros::this_node::getName();
  std::string text, file;
  if (!ros::param::get(ns + "/scene_yaml", text)) {
    ROS_FATAL(
        "%s: parameter %s/scene_yaml is not set: start the node from a launch file that loads a scene "
        "(e.g. roslaunch launch/cosim.launch scene:=<file>)",
        node.c_str(), ns.c_str());
    return false;
  }
  ros::param::param<std::string>(ns + "/scene_file", file, ns + "/scene_yaml");
  // Overrides of the scene's keys (launch argument `overrides`), the same for both nodes.
  std::string overrides;
  ros::param::param<std::string>(ns + "/scene_overrides", overrides, "");
  try {
    scene = core::loadSceneHandedOver(text, file, core::splitOverrides(overrides));
  } catch (const core::SceneError& e) {
    ROS_FATAL("%s: scene refused: %s", node.c_str(), e.what());
    return false;
  }
  return true;
}

}  // namespace rail::ros_glue
