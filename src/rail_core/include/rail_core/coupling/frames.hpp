// The two frames exchanged once per track step (paper section 5.1, Figure 12): wheel-centre states from
// the vehicle to the track, equivalent contact wrenches from the track to the vehicle. World frame, SI
// units. A frame's wheel capacity is fixed at construction; nothing is allocated per step.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rail::core::coupling {

// State of one wheel centre at the exchange instant (as rail_msgs/WheelState).
struct WheelState {
  std::uint32_t id = 0;                                        // wheel index: 2 * wheelset + side
  double arc_length = 0.0;                                     // track arc length s of the centre's projection [m]
  Eigen::Vector3d p_wheel_in_world = Eigen::Vector3d::Zero();  // centre position q_w [m]
  Eigen::Quaterniond q_wheelset_to_world = Eigen::Quaterniond::Identity();  // R_wheelset_to_world
  Eigen::Vector3d v_wheel_in_world = Eigen::Vector3d::Zero();               // centre velocity q_w dot [m/s]
  Eigen::Vector3d omega_wheelset_in_world = Eigen::Vector3d::Zero();        // angular velocity, spin included [rad/s]
};

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
