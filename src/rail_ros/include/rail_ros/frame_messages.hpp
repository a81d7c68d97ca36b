// ROS glue (library rail_ros): conversions between the coupling frames (rail_core/coupling/frames.hpp)
// and the rail_msgs messages the ROS transports carry. World frame, SI units, field by field.
//
// The messages are reused: once a message's array has held `capacity` wheels (reserveMessage), a
// conversion copies without allocating. The header stamp carries the simulated time t_k rounded to the
// nanosecond (ros::Time); the receiving side rebuilds t_k = k h exactly from the step index and checks the
// stamp against it, so the frames' times stay bit for bit those of the sender.
#pragma once

#include <cstdint>

#include <rail_msgs/ContactWrenches.h>
#include <rail_msgs/WheelStates.h>

#include "rail_core/coupling/frames.hpp"
#include "rail_core/coupling/transport.hpp"

namespace rail::ros_glue {

namespace coupling = rail::core::coupling;

// Step index of the close marker: a message with this step and no wheels tells the receiver that the
// sender closed (the ROS transports send one from close()).
constexpr std::uint64_t kCloseStep = ~std::uint64_t{0};
// Frame id written into the headers (the frames are in the world frame).
constexpr const char* kWorldFrameId = "world";

// Reserve room for `capacity` wheels and set the header's frame id (the only allocations).
void reserveMessage(rail_msgs::WheelStates& msg, int capacity);
void reserveMessage(rail_msgs::ContactWrenches& msg, int capacity);

// Frame -> message: step, scene hash, stamp = frame.time, the first frame.count wheels. wheelset and side
// of a WheelState follow from the id (id = 2 * wheelset + side). kError (message unchanged) when a wheel
// id does not fit the message's uint8 or the time is not a valid ros::Time (negative or beyond 2^32 s).
coupling::Result toMessage(const coupling::WheelStateFrame& frame, rail_msgs::WheelStates& msg);
coupling::Result toMessage(const coupling::WrenchFrame& frame, rail_msgs::ContactWrenches& msg);

// The close marker (kCloseStep, no wheels; scene hash kept).
void makeCloseMarker(rail_msgs::WheelStates& msg);
void makeCloseMarker(rail_msgs::ContactWrenches& msg);
inline bool isCloseMarker(const rail_msgs::WheelStates& m) { return m.step == kCloseStep && m.wheels.empty(); }
inline bool isCloseMarker(const rail_msgs::ContactWrenches& m) { return m.step == kCloseStep && m.wrenches.empty(); }

// Message -> frame: step, scene hash, count and wheels; time = step * track_step [s] (track_step > 0).
// kRefused (frame unchanged) when the message has more wheels than the frame's capacity or its stamp
// differs from step * track_step by more than 1 ns (the stamp's rounding). `source` names the topic or
// service for the message.
coupling::Result fromMessage(const rail_msgs::WheelStates& msg, double track_step, coupling::WheelStateFrame& frame,
                             const char* source);
coupling::Result fromMessage(const rail_msgs::ContactWrenches& msg, double track_step, coupling::WrenchFrame& frame,
                             const char* source);

}  // namespace rail::ros_glue
