// What the run loop of each side (the track's CosimTrackRun, the vehicle's VehicleRun) takes from a scene,
// resolved once from the validated scene (the loader checked each value's rule), so that the loops hold
// typed settings rather than the Scene.
#pragma once

#include <limits>

#include "rail_core/coupling/protocol.hpp"
#include "rail_core/scene.hpp"

namespace rail::core {

struct RunSettings {
  coupling::CouplingConfig coupling;  // track step, exchange timeout, scene hash, wheel count
  double handshake_timeout = 30.0;    // s: the first exchange waits this long for the vehicle's set-up
  double output_period = 0.0;         // s, 1 / output.rate
  // s: solver.end's time; infinity when the run ends at an arc length (the vehicle's simulator tells).
  double end_time = std::numeric_limits<double>::infinity();
};

inline RunSettings runSettings(const Scene& scene) {
  RunSettings r;
  r.coupling = coupling::couplingConfig(scene);
  r.handshake_timeout = scene.solver.handshake_timeout;
  r.output_period = 1.0 / scene.output.rate;
  if (scene.solver.end.kind == EndKind::kTime) r.end_time = scene.solver.end.value;
  return r;
}

}  // namespace rail::core
