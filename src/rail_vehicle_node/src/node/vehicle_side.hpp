// The vehicle node's run: the VehicleSimulator alone on the rigid track, or the co-simulation's vehicle
// side (CosimVehicle) after the handshake with the track node, over the scene's transport; a VehicleRun
// owns the loop and the VehicleOutputs publish and record each output instant.
#pragma once

#include <rail_core/scene.hpp>

namespace rail::vehicle {

// Runs the vehicle side of `scene` (after ros_glue::startNode) to solver.end and returns the node's exit
// code (rail_core/exit_codes.hpp) after its closing lines.
int runVehicleSide(const core::Scene& scene);

}  // namespace rail::vehicle
