// The track node's moving-load run (a scene without a vehicle): builds the flexible track, runs it to
// solver.end and publishes /clock (simulated time), /rail_deflection and the rviz markers at output.rate,
// recording output.topics to output.bag.
#pragma once

#include <ros/node_handle.h>

#include <rail_core/scene.hpp>

namespace rail::track {

// Returns the node's exit code (rail_core/exit_codes.hpp) after its closing lines.
int runMovingLoads(ros::NodeHandle& nh, ros::NodeHandle& pnh, const core::Scene& scene);

}  // namespace rail::track
