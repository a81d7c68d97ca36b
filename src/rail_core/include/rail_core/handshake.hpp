// The co-simulation handshake: before the first step the vehicle and track nodes check that they run the
// same scene. ROS-free; the nodes carry these fields in rail_msgs/Handshake.
#pragma once

#include <cstdint>
#include <string>

#include "rail_core/scene.hpp"

namespace rail::core {

struct HandshakeInfo {
  std::string node;        // ROS node name
  std::string scene_file;  // scene file it loaded
  std::uint64_t scene_hash = 0;
  std::uint32_t wheel_count = 0;
  double track_step = 0.0;  // [s]
  std::string transport;
  // The vehicle's first to last wheel centre at rest, from its model [m]: how long the track window must be.
  // Not compared; 0 from the track side.
  double wheel_span = 0.0;
};

HandshakeInfo handshakeInfo(const Scene& scene, const std::string& node);

// Empty when the two agree; otherwise one message naming each field that differs and both values, e.g.
// "scene differs from /rail_vehicle's: wheel_count 8 here, 4 there; scene_hash ... ".
std::string compareHandshake(const HandshakeInfo& mine, const HandshakeInfo& theirs);

}  // namespace rail::core
