#include "rail_core/cost_profile.hpp"

#include <cstdio>
#include <sstream>

namespace rail::core {

const char* CostProfile::name(Component c) {
  switch (c) {
    case kVehicleIntegration: return "vehicle_integration";
    case kTrackStep: return "track_step";
    case kTransportWait: return "transport_wait";
    case kPublish: return "publish";
    case kBagWrite: return "bag_write";
    case kSetUp: return "set_up";
    case kComponentCount: break;
  }
  return "?";
}

namespace {
const char* on_off(bool b) { return b ? "on" : "off"; }
}  // namespace

std::string CostProfile::to_yaml(const std::string& node, const Scene& scene, double loop_wall,
                                 double simulated) const {
  std::ostringstream o;
  o.precision(6);
  o << "# Where the wall time of " << node << " went (s; share of the run loop's wall time)\n";
  o << "node: " << node << "\n";
  o << "scene: " << scene.file << "\n";
  o << "simulated_time: " << simulated << "   # s\n";
  o << "loop_wall_time: " << loop_wall << "   # s, the run loop (set-up excluded)\n";
  o << "wall_per_simulated_second: " << (simulated > 0 ? loop_wall / simulated : 0.0) << "\n";
  o << "components:\n";
  for (int c = 0; c < kComponentCount; ++c) {
    const Component k = static_cast<Component>(c);
    o << "  " << name(k) << ": {seconds: " << seconds_[c] << ", share: "
      << (loop_wall > 0 && k != kSetUp ? seconds_[c] / loop_wall : 0.0) << ", calls: " << calls_[c] << "}\n";
  }
  double accounted = 0.0;
  for (int c = 0; c < kComponentCount; ++c)
    if (c != kSetUp) accounted += seconds_[c];
  o << "  other: {seconds: " << (loop_wall - accounted) << "}\n";
  o << "counts:\n";
  for (const auto& kv : counts_) o << "  " << kv.first << ": " << kv.second << "\n";
  const Effects& e = scene.effects;
  o << "effects:\n"
    << "  track_model: " << to_string(e.track_model) << "\n"
    << "  irregularities: " << on_off(e.irregularities) << "\n"
    << "  flange_contact: " << on_off(e.flange_contact) << "\n"
    << "  spin_creepage: " << on_off(e.spin_creepage) << "\n"
    << "  creep_law: " << to_string(e.creep_law) << "\n"
    << "  track_damping: " << on_off(e.track_damping) << "\n"
    << "  absorbing_ends: " << on_off(e.absorbing_ends) << "\n"
    << "  rail_deflection_output: " << on_off(e.rail_deflection_output) << "\n"
    << "  contact_point_output: " << on_off(e.contact_point_output) << "\n"
    << "  rviz_markers: " << on_off(e.rviz_markers) << "\n"
    << "  floor_acceleration_output: " << on_off(e.floor_acceleration_output) << "\n"
    << "  pad_force_output: " << on_off(e.pad_force_output) << "\n";
  return o.str();
}

std::string CostProfile::to_text(const std::string& node, double loop_wall, double simulated) const {
  std::ostringstream o;
  char line[160];
  std::snprintf(line, sizeof line, "%s: cost profile, %.2f s wall for %.4f s simulated (%.2f s per simulated s)\n",
                node.c_str(), loop_wall, simulated, simulated > 0 ? loop_wall / simulated : 0.0);
  o << line;
  for (int c = 0; c < kComponentCount; ++c) {
    if (calls_[c] == 0) continue;
    const Component k = static_cast<Component>(c);
    std::snprintf(line, sizeof line, "  %-20s %9.3f s %6.1f %%  %ld calls\n", name(k), seconds_[c],
                  k != kSetUp && loop_wall > 0 ? 100.0 * seconds_[c] / loop_wall : 0.0, calls_[c]);
    o << line;
  }
  for (const auto& kv : counts_) {
    std::snprintf(line, sizeof line, "  %-20s %.0f\n", kv.first.c_str(), kv.second);
    o << line;
  }
  return o.str();
}

}  // namespace rail::core
