// What the run loop of each side (the track's CosimTrackRun, the vehicle's VehicleRun) and the nodes'
// outputs take from a scene, resolved once from the validated scene (the loader checked each value's
// rule), so that they hold typed settings rather than the Scene.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

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

// What a node's outputs take from a scene, resolved once: which outputs the effects call for, the output
// section (bag, rate, recorded topics, deflection sections, pad-force margin), the scene's file and hash
// for messages and frames, and what the vehicle's pictures draw.
struct OutputSettings {
  std::string source;            // the scene file; messages about the outputs name it
  std::uint64_t scene_hash = 0;  // stamped on the published frames
  Effects effects;
  Output output;
  double nominal_radius = 0.0;                            // m, the wheels drawn (with a vehicle)
  std::vector<rail::contact::WheelDefect> wheel_defects;  // with effects.wheel_defects on, else empty

  // True when output.topics names `topic` (without its leading slash).
  bool records(const std::string& topic) const {
    return std::find(output.topics.begin(), output.topics.end(), topic) != output.topics.end();
  }
};

inline OutputSettings outputSettings(const Scene& scene) {
  OutputSettings o;
  o.source = scene.file;
  o.scene_hash = scene.hash;
  o.effects = scene.effects;
  o.output = scene.output;
  if (scene.has_vehicle) {
    o.nominal_radius = scene.vehicle.nominal_radius;
    if (scene.effects.wheel_defects) o.wheel_defects = scene.vehicle.wheel_defects;
  }
  return o;
}

}  // namespace rail::core
