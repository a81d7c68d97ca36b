#include "rail_ros/replay_bag.hpp"

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <stdexcept>
#include <vector>

#include <rail_msgs/WheelStates.h>
#include <rail_contact/format.hpp>

namespace rail::ros_glue {

core::coupling::RecordedStates readRecordedStates(const std::string& bag_path, int wheel_count) {
  core::coupling::RecordedStates recording;
  recording.source = bag_path;
  rosbag::Bag bag;
  try {
    bag.open(bag_path, rosbag::bagmode::Read);
  } catch (const std::exception& e) {
    throw std::runtime_error(bag_path + ": cannot read the replay bag: " + e.what());
  }
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{"/wheel_states"}));
  for (const rosbag::MessageInstance& m : view) {
    const rail_msgs::WheelStates::ConstPtr msg = m.instantiate<rail_msgs::WheelStates>();
    if (!msg) continue;
    if (static_cast<int>(msg->wheels.size()) != wheel_count) {
      throw std::runtime_error(bag_path + ": /wheel_states at t = " + contact::formatNumber(msg->header.stamp.toSec()) +
                               " s has " + std::to_string(msg->wheels.size()) + " wheels, the scene's vehicle " +
                               std::to_string(wheel_count));
    }
    // The first output is stamped at the smallest time a bag takes: it is t = 0.
    const double t = msg->header.stamp.toSec() <= 1e-6 ? 0.0 : msg->header.stamp.toSec();
    if (!recording.times.empty() && t <= recording.times.back()) continue;  // repeated output instant
    core::coupling::WheelStateFrame frame(wheel_count);
    frame.count = static_cast<std::uint32_t>(wheel_count);
    for (int i = 0; i < wheel_count; ++i) {
      const rail_msgs::WheelState& w = msg->wheels[static_cast<std::size_t>(i)];
      core::coupling::WheelState& o = frame.wheels[static_cast<std::size_t>(i)];
      o.id = w.wheel_id;
      o.arc_length = w.arc_length;
      o.p_wheel_in_world = Eigen::Vector3d(w.position.x, w.position.y, w.position.z);
      o.R_wheelset_to_world = core::coupling::orientationFromWire(
          Eigen::Quaterniond(w.orientation.w, w.orientation.x, w.orientation.y, w.orientation.z));
      o.v_wheel_in_world = Eigen::Vector3d(w.linear_velocity.x, w.linear_velocity.y, w.linear_velocity.z);
      o.omega_wheelset_in_world = Eigen::Vector3d(w.angular_velocity.x, w.angular_velocity.y, w.angular_velocity.z);
    }
    recording.times.push_back(t);
    recording.frames.push_back(std::move(frame));
  }
  if (recording.frames.empty()) {
    throw std::runtime_error(bag_path + ": no /wheel_states in the bag (needed to replay a run)");
  }
  return recording;
}

}  // namespace rail::ros_glue
