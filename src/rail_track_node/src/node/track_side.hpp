// The track node's run in a scene with a vehicle or a recorded one: the co-simulation's track side after
// the handshake with the vehicle node (CosimTrackRun over the scene's transport), or the same run driven by
// the wheel states of a bag (~replay_bag); a scene without a vehicle goes to runMovingLoads.
#pragma once

#include <rail_core/scene.hpp>

namespace rail::track {

// Runs the track side of `scene` (after ros_glue::startNode) and returns the node's exit code
// (rail_core/exit_codes.hpp) after its closing lines.
int runTrackSide(const core::Scene& scene);

}  // namespace rail::track
