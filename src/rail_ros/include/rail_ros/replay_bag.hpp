// Reads the wheel states a run recorded (/wheel_states of its bag, rail_msgs/WheelStates) for a replay of
// the track side (rail_core/coupling/replay_transport.hpp). The bag is read directly rather than played:
// the track may run far slower than real time and a played topic would drop frames.
#pragma once

#include <string>

#include <rail_core/coupling/replay_transport.hpp>

namespace rail::ros_glue {

// Every /wheel_states message of `bag_path`, a repeated instant once (the first). Throws std::runtime_error
// naming the bag when it cannot be read, holds no /wheel_states, or a message's wheel count is not
// `wheel_count` (the scene's vehicle).
core::coupling::RecordedStates readRecordedStates(const std::string& bag_path, int wheel_count);

}  // namespace rail::ros_glue
