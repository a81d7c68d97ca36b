// The two frames exchanged once per track step (paper section 5.1, Figure 12): wheel-centre states from
// the vehicle to the track, equivalent contact wrenches from the track to the vehicle. World frame, SI
// units. A frame's wheel capacity is fixed at construction; nothing is allocated per step.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <rail_contact/wheel_state.hpp>

namespace rail::core::coupling {

// State of one wheel centre at the exchange instant: the contact's own WheelState (rail_contact), one type
// from the vehicle's integrator through the transports to the track's contact.
using rail::contact::WheelState;

// R_wheelset_to_world on the wire (rail_msgs/WheelState, the shared-memory record) is a unit quaternion.
inline Eigen::Quaterniond wireOrientation(const Eigen::Matrix3d& R_wheelset_to_world) {
  return Eigen::Quaterniond(R_wheelset_to_world).normalized();
}
inline Eigen::Matrix3d orientationFromWire(const Eigen::Quaterniond& q_wheelset_to_world) {
  return q_wheelset_to_world.normalized().toRotationMatrix();
}
// Equivalent contact wrench at one wheel centre (paper eq. 13, as rail_msgs/ContactWrench).
struct WheelWrench {
  std::uint32_t id = 0;                                        // as in WheelState
  Eigen::Vector3d f_wheel_in_world = Eigen::Vector3d::Zero();  // force on the wheel f_e,w [N]
  Eigen::Vector3d n_wheel_in_world = Eigen::Vector3d::Zero();  // moment about the wheel centre n'_e,w [N m]
};

// Common stamp of both frames.
struct FrameStamp {
  std::uint64_t step = 0;        // track step index k; the frame belongs to t_k = k h
  double time = 0.0;             // t_k [s]
  std::uint64_t scene_hash = 0;  // hash of the resolved scene; the peer refuses another
};

// Vehicle -> track: the wheel-centre states interpolated at t_k. wheels.size() is the capacity (fixed);
// the first `count` entries are in use.
struct WheelStateFrame : FrameStamp {
  explicit WheelStateFrame(int capacity = 0);
  int capacity() const { return static_cast<int>(wheels.size()); }
  std::uint32_t count = 0;
  std::vector<WheelState> wheels;
};

// Track -> vehicle: the wrenches evaluated at t_k, same layout as WheelStateFrame.
struct WrenchFrame : FrameStamp {
  explicit WrenchFrame(int capacity = 0);
  int capacity() const { return static_cast<int>(wheels.size()); }
  std::uint32_t count = 0;
  std::vector<WheelWrench> wheels;
};

// Copy src into dst without allocating. False (dst unchanged) when src.count exceeds dst's capacity.
bool copyFrame(const WheelStateFrame& src, WheelStateFrame& dst);
bool copyFrame(const WrenchFrame& src, WrenchFrame& dst);

}  // namespace rail::core::coupling
