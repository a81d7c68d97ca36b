// ROS glue (library rail_ros): the settings shared by the ROS service and topic transports.
#pragma once

#include <atomic>
#include <string>

#include "rail_core/coupling/transport.hpp"

namespace rail::ros_glue {

namespace coupling = rail::core::coupling;

struct RosTransportOptions {
  coupling::Role role = coupling::Role::kVehicle;
  double track_step = 0.0;       // h [s], > 0: a received frame's time is rebuilt as t_k = k h (exact)
  int wheel_capacity = 0;        // wheels per frame (Scene::wheel_count()), 1..256
  double attach_timeout = 30.0;  // longest wait for the peer while constructing [s] (solver.handshake_timeout)
  std::string peer_node;         // the peer's node name when known (handshake); empty = learned from its traffic
  const std::atomic<bool>* interrupt = nullptr;  // optional: ends any wait with kInterrupted
};

// Throws std::runtime_error naming the field and value when an option is out of range; `what` names the
// transport ("service transport").
void checkOptions(const RosTransportOptions& o, const char* what);

}  // namespace rail::ros_glue
