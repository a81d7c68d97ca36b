#include "rail_ros/frame_messages.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <rail_contact/format.hpp>

namespace rail::ros_glue {

namespace coupling = rail::core::coupling;

using contact::formatNumber;
using coupling::Result;
using coupling::Status;

namespace {

// The stamp of time t [s] (the frames' times are >= 0), or false when t is no valid ros::Time.
bool stampOf(double t, ros::Time& stamp) {
  if (!(t >= 0.0) || !(t < static_cast<double>(std::numeric_limits<std::uint32_t>::max()))) return false;
  stamp.fromSec(t);
  return true;
}

Result badTime(double t) {
  return {Status::kError, "frame time " + formatNumber(t) + " s is not a valid ROS stamp (0 .. 2^32 s)"};
}

Result badId(std::uint32_t id) {
  return {Status::kError, "wheel id " + std::to_string(id) + " does not fit the message's uint8 wheel_id"};
}

void put(const Eigen::Vector3d& v, geometry_msgs::Vector3& m) {
  m.x = v.x();
  m.y = v.y();
  m.z = v.z();
}
void get(const geometry_msgs::Vector3& m, Eigen::Vector3d& v) { v = Eigen::Vector3d(m.x, m.y, m.z); }

// The checks shared by both message kinds: wheel count against the capacity, stamp against k h.
Result checkIncoming(std::uint64_t step, const ros::Time& stamp, std::size_t count, int capacity, double track_step,
                     const char* source) {
  if (count > static_cast<std::size_t>(capacity))
    return {Status::kRefused, std::string(source) + ": " + std::to_string(count) + " wheels in step " +
                                  std::to_string(step) + ", more than the capacity " + std::to_string(capacity)};
  const double t = static_cast<double>(step) * track_step;
  ros::Time expected;
  const bool valid = stampOf(t, expected);
  const std::int64_t diff = static_cast<std::int64_t>(stamp.toNSec()) - static_cast<std::int64_t>(expected.toNSec());
  if (!valid || diff > 1 || diff < -1) {
    char when[40];
    std::snprintf(when, sizeof(when), "%u.%09u", stamp.sec, stamp.nsec);
    return {Status::kRefused, std::string(source) + ": stamp " + when + " s of step " + std::to_string(step) +
                                  " differs from step x track_step = " + formatNumber(t) + " s"};
  }
  return {};
}

// The message's header from a frame whose time and ids fit the wire, then each wheel through
// fill(frame.wheels[i], items[i]); items are resized within their reserved capacity (no allocation).
template <class Frame, class Msg, class Items, class Fill>
Result writeFrame(const Frame& frame, Msg& msg, Items& items, Fill fill) {
  ros::Time stamp;
  if (!stampOf(frame.time, stamp)) return badTime(frame.time);
  for (std::uint32_t i = 0; i < frame.count; ++i)
    if (frame.wheels[i].id > 255u) return badId(frame.wheels[i].id);
  msg.header.stamp = stamp;
  msg.step = frame.step;
  msg.scene_hash = frame.scene_hash;
  items.resize(frame.count);
  for (std::uint32_t i = 0; i < frame.count; ++i) fill(frame.wheels[i], items[i]);
  return {};
}

}  // namespace

void reserveMessage(rail_msgs::WheelStates& msg, int capacity) {
  msg.header.frame_id = kWorldFrameId;
  msg.wheels.reserve(static_cast<std::size_t>(capacity > 0 ? capacity : 0));
}

void reserveMessage(rail_msgs::ContactWrenches& msg, int capacity) {
  msg.header.frame_id = kWorldFrameId;
  msg.wrenches.reserve(static_cast<std::size_t>(capacity > 0 ? capacity : 0));
}

Result toMessage(const coupling::WheelStateFrame& frame, rail_msgs::WheelStates& msg) {
  return writeFrame(frame, msg, msg.wheels, [](const coupling::WheelState& w, rail_msgs::WheelState& m) {
    m.wheel_id = static_cast<std::uint8_t>(w.id);
    m.wheelset = static_cast<std::uint8_t>(w.id / 2);
    m.side = static_cast<std::uint8_t>(w.id % 2 ? rail_msgs::WheelState::SIDE_RIGHT : rail_msgs::WheelState::SIDE_LEFT);
    m.arc_length = w.arc_length;
    m.position.x = w.p_wheel_in_world.x();
    m.position.y = w.p_wheel_in_world.y();
    m.position.z = w.p_wheel_in_world.z();
    const Eigen::Quaterniond q = coupling::wireOrientation(w.R_wheelset_to_world);
    m.orientation.x = q.x();
    m.orientation.y = q.y();
    m.orientation.z = q.z();
    m.orientation.w = q.w();
    put(w.v_wheel_in_world, m.linear_velocity);
    put(w.omega_wheelset_in_world, m.angular_velocity);
  });
}

Result toMessage(const coupling::WrenchFrame& frame, rail_msgs::ContactWrenches& msg) {
  return writeFrame(frame, msg, msg.wrenches, [](const coupling::WheelWrench& w, rail_msgs::ContactWrench& m) {
    m.wheel_id = static_cast<std::uint8_t>(w.id);
    put(w.f_wheel_in_world, m.force);
    put(w.n_wheel_in_world, m.moment);
  });
}

void makeCloseMarker(rail_msgs::WheelStates& msg) {
  msg.step = kCloseStep;
  msg.wheels.clear();  // keeps the capacity
}

void makeCloseMarker(rail_msgs::ContactWrenches& msg) {
  msg.step = kCloseStep;
  msg.wrenches.clear();
}

namespace {

// The frame's header from a checked message, then each item through fill(item, frame.wheels[i]).
template <class Msg, class Items, class Frame, class Fill>
Result readFrame(const Msg& msg, const Items& items, double track_step, Frame& frame, const char* source, Fill fill) {
  Result r = checkIncoming(msg.step, msg.header.stamp, items.size(), frame.capacity(), track_step, source);
  if (!r) return r;
  frame.step = msg.step;
  frame.time = static_cast<double>(msg.step) * track_step;
  frame.scene_hash = msg.scene_hash;
  frame.count = static_cast<std::uint32_t>(items.size());
  for (std::uint32_t i = 0; i < frame.count; ++i) fill(items[i], frame.wheels[i]);
  return {};
}

}  // namespace

Result fromMessage(const rail_msgs::WheelStates& msg, double track_step, coupling::WheelStateFrame& frame,
                   const char* source) {
  return readFrame(msg, msg.wheels, track_step, frame, source,
                   [](const rail_msgs::WheelState& m, coupling::WheelState& w) {
                     w.id = m.wheel_id;
                     w.arc_length = m.arc_length;
                     w.p_wheel_in_world = Eigen::Vector3d(m.position.x, m.position.y, m.position.z);
                     // Eigen's (w, x, y, z) constructor; stored as given (no normalisation), so the bits survive.
                     w.R_wheelset_to_world = coupling::orientationFromWire(
                         Eigen::Quaterniond(m.orientation.w, m.orientation.x, m.orientation.y, m.orientation.z));
                     get(m.linear_velocity, w.v_wheel_in_world);
                     get(m.angular_velocity, w.omega_wheelset_in_world);
                   });
}

Result fromMessage(const rail_msgs::ContactWrenches& msg, double track_step, coupling::WrenchFrame& frame,
                   const char* source) {
  return readFrame(msg, msg.wrenches, track_step, frame, source,
                   [](const rail_msgs::ContactWrench& m, coupling::WheelWrench& w) {
                     w.id = m.wheel_id;
                     get(m.force, w.f_wheel_in_world);
                     get(m.moment, w.n_wheel_in_world);
                   });
}

}  // namespace rail::ros_glue
