// The state of one wheel at an instant: what the contact evaluates, what the vehicle sends the track at
// each exchange (rail_core coupling frames) and what rail_msgs/WheelState publishes. World frame, SI units.
#pragma once

#include <Eigen/Core>
#include <cstdint>

namespace rail {
namespace contact {

/// Kinematic state of one wheel centre (the axle point in the wheel's taping-line plane).
/// The message and the shared-memory record carry R_wheelset_to_world as a unit quaternion; it is
/// converted at the transport, so the contact and the vehicle share this one matrix form.
struct WheelState {
  std::uint32_t id = 0;  ///< wheel index: 2 * wheelset + side
  double arc_length =
      0.0;  ///< track arc length s at the wheel (its centre's projection), m; the contact search starts there
  Eigen::Vector3d p_wheel_in_world = Eigen::Vector3d::Zero();         ///< wheel centre q_w, m
  Eigen::Matrix3d R_wheelset_to_world = Eigen::Matrix3d::Identity();  ///< A_ws
  Eigen::Vector3d v_wheel_in_world = Eigen::Vector3d::Zero();         ///< velocity of the centre, m/s
  Eigen::Vector3d omega_wheelset_in_world = Eigen::Vector3d::Zero();  ///< angular velocity, spin included, rad/s
};

}  // namespace contact
}  // namespace rail
