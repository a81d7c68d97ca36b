#include "rail_core/cost_profile.hpp"

#include <cstdio>
#include <iterator>
#include <sstream>

namespace rail::core {

namespace {

// Each name at its enumerator's index (cost_profile.hpp); the sizes are checked against the enums.
constexpr const char* kComponentNames[] = {"vehicle_integration", "track_step", "transport_wait", "publish",
                                           "bag_write",           "set_up"};
constexpr const char* kPartNames[] = {
    "vehicle_rhs",         "vehicle_jacobian", "track_rhs", "track_solve",     "track_solve_wait",     "window_moves",
    "floor_accelerations", "pad_forces",       "markers",   "rail_deflection", "contact_point_output", "energy_output"};
constexpr const char* kCountNames[] = {"damping_products", "end_dashpot_forces", "irregularity_evaluations"};
static_assert(std::size(kComponentNames) == CostProfile::kComponentCount);
static_assert(std::size(kPartNames) == CostClock::kPartCount);
static_assert(std::size(kCountNames) == CostClock::kCountCount);

template <std::size_t N>
const char* nameAt(const char* const (&names)[N], int i) {
  return i >= 0 && i < static_cast<int>(N) ? names[i] : "?";
}

}  // namespace

const char* CostProfile::name(Component c) { return nameAt(kComponentNames, c); }
const char* CostClock::name(Part p) { return nameAt(kPartNames, p); }
const char* CostClock::name(Count c) { return nameAt(kCountNames, c); }

int CostProfile::finerLines(const CostClock& k, std::array<FinerLine, kMaxFinerLines>& lines) const {
  const bool track_side = calls_[kTrackStep] > 0;
  const Component contact_parent = track_side ? kTrackStep : kVehicleIntegration;
  int n = 0;
  auto part = [&](CostClock::Part p, Component parent) {
    lines[static_cast<std::size_t>(n++)] = FinerLine{CostClock::name(p), k.seconds[p], k.calls[p], parent};
  };
  part(CostClock::kVehicleRhs, kVehicleIntegration);
  part(CostClock::kVehicleJacobian, kVehicleIntegration);
  lines[static_cast<std::size_t>(n++)] =
      FinerLine{"contact_detection", k.contact.detection_seconds, k.contact.evaluations, contact_parent};
  lines[static_cast<std::size_t>(n++)] =
      FinerLine{"contact_forces", k.contact.forces_seconds, k.contact.evaluations, contact_parent};
  const Component solve_parent = k.track_solve_beside ? kComponentCount : kTrackStep;
  part(CostClock::kTrackRhs, solve_parent);
  part(CostClock::kTrackSolve, solve_parent);
  part(CostClock::kTrackSolveWait, kTrackStep);
  part(CostClock::kWindowMoves, kTrackStep);
  part(CostClock::kFloorAccelerations, kVehicleIntegration);
  part(CostClock::kRailDeflection, kPublish);
  part(CostClock::kPadForces, kPublish);
  part(CostClock::kContactPointOutput, kPublish);
  part(CostClock::kMarkers, kPublish);
  part(CostClock::kEnergyOutput, track_side ? kPublish : kVehicleIntegration);
  return n;
}

namespace {
const char* onOff(bool b) { return b ? "on" : "off"; }

// Within a coarse component: its finer parts that are not nested in other parts. The contact parts are
// inside vehicle_rhs + vehicle_jacobian on the vehicle side, so they are not subtracted there again.
bool directChild(const CostProfile::FinerLine& l, bool track_side) {
  const bool contact = std::string(l.name).rfind("contact_", 0) == 0 && std::string(l.name) != "contact_point_output";
  return !(contact && !track_side);
}
}  // namespace

std::string CostProfile::toYaml(const std::string& node, const std::string& scene_file, const Effects& effects,
                                double loop_wall, double simulated, const CostClock* clock) const {
  std::ostringstream o;
  o.precision(6);
  o << "# Where the wall time of " << node << " went (s; share of the run loop's wall time)\n";
  o << "node: " << node << "\n";
  o << "scene: " << scene_file << "\n";
  o << "simulated_time: " << simulated << "   # s\n";
  o << "loop_wall_time: " << loop_wall << "   # s, the run loop (set-up excluded)\n";
  o << "wall_per_simulated_second: " << (simulated > 0 ? loop_wall / simulated : 0.0) << "\n";
  o << "components:\n";
  for (int c = 0; c < kComponentCount; ++c) {
    const Component k = static_cast<Component>(c);
    o << "  " << name(k) << ": {seconds: " << seconds_[c]
      << ", share: " << (loop_wall > 0 && k != kSetUp ? seconds_[c] / loop_wall : 0.0) << ", calls: " << calls_[c]
      << "}\n";
  }
  double accounted = 0.0;
  for (int c = 0; c < kComponentCount; ++c)
    if (c != kSetUp) accounted += seconds_[c];
  o << "  other: {seconds: " << (loop_wall - accounted) << "}\n";
  if (clock != nullptr) {
    // Each finer part: seconds, share of the run loop, calls, the component it is part of; then per
    // component the rest ("other") so that the shares add up within it.
    std::array<FinerLine, kMaxFinerLines> lines;
    const int n = finerLines(*clock, lines);
    const bool track_side = calls_[kTrackStep] > 0;
    o << "finer:   # nested in the components above (vehicle side: contact_* inside vehicle_rhs + vehicle_jacobian)\n";
    for (int i = 0; i < n; ++i) {
      const FinerLine& l = lines[static_cast<std::size_t>(i)];
      o << "  " << l.name << ": {seconds: " << l.seconds << ", share: " << (loop_wall > 0 ? l.seconds / loop_wall : 0.0)
        << ", calls: " << l.calls
        << ", within: " << (l.parent == kComponentCount ? "beside_track_step" : name(l.parent)) << "}\n";
    }
    for (int c = 0; c < kComponentCount; ++c) {
      double parts = 0.0;
      bool any = false;
      for (int i = 0; i < n; ++i) {
        const FinerLine& l = lines[static_cast<std::size_t>(i)];
        if (l.parent != c || !directChild(l, track_side)) continue;
        parts += l.seconds;
        any = any || l.calls > 0;
      }
      if (!any) continue;
      o << "  " << name(static_cast<Component>(c)) << "_other: {seconds: " << (seconds_[c] - parts)
        << ", share: " << (loop_wall > 0 ? (seconds_[c] - parts) / loop_wall : 0.0) << "}\n";
    }
  }
  o << "counts:\n";
  for (const auto& kv : counts_) o << "  " << kv.first << ": " << kv.second << "\n";
  if (clock != nullptr) {
    o << "  flange_searches: " << clock->contact.flange_searches << "\n"
      << "  creep_evaluations: " << clock->contact.creep_evaluations << "\n"
      << "  creep_evaluations_with_spin: " << clock->contact.spin_evaluations << "\n";
    for (int c = 0; c < CostClock::kCountCount; ++c)
      o << "  " << CostClock::name(static_cast<CostClock::Count>(c)) << ": "
        << clock->counts[static_cast<std::size_t>(c)] << "\n";
  }
  o << "effects:\n"
    << "  track_model: " << toString(effects.track_model) << "\n"
    << "  creep_law: " << toString(effects.creep_law) << "\n";
  for (const EffectSwitch& sw : kEffectSwitches) o << "  " << sw.key << ": " << onOff(effects.*sw.on) << "\n";
  return o.str();
}

std::string CostProfile::toText(const std::string& node, double loop_wall, double simulated,
                                const CostClock* clock) const {
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
    if (clock == nullptr) continue;
    std::array<FinerLine, kMaxFinerLines> lines;
    const int n = finerLines(*clock, lines);
    for (int i = 0; i < n; ++i) {
      const FinerLine& l = lines[static_cast<std::size_t>(i)];
      if (l.parent != k || l.calls == 0) continue;
      std::snprintf(line, sizeof line, "    %-18s %9.3f s %6.1f %%  %ld calls\n", l.name, l.seconds,
                    loop_wall > 0 ? 100.0 * l.seconds / loop_wall : 0.0, l.calls);
      o << line;
    }
  }
  if (clock != nullptr && clock->track_solve_beside) {
    std::array<FinerLine, kMaxFinerLines> lines;
    const int n = finerLines(*clock, lines);
    for (int i = 0; i < n; ++i) {
      const FinerLine& l = lines[static_cast<std::size_t>(i)];
      if (l.parent != kComponentCount || l.calls == 0) continue;
      std::snprintf(line, sizeof line, "  beside: %-12s %9.3f s %6.1f %%  %ld calls (second thread)\n", l.name,
                    l.seconds, loop_wall > 0 ? 100.0 * l.seconds / loop_wall : 0.0, l.calls);
      o << line;
    }
  }
  if (clock != nullptr) {
    std::snprintf(line, sizeof line,
                  "  flange searches %lld, creep evaluations %ld (with spin %ld), damping products %lld\n",
                  static_cast<long long>(clock->contact.flange_searches), clock->contact.creep_evaluations,
                  clock->contact.spin_evaluations, clock->counts[CostClock::kDampingProducts]);
    o << line;
  }
  for (const auto& kv : counts_) {
    std::snprintf(line, sizeof line, "  %-20s %.0f\n", kv.first.c_str(), kv.second);
    o << line;
  }
  return o.str();
}

}  // namespace rail::core
