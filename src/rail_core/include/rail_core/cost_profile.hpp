// Where a run's wall time goes: a fixed set of components, each with its accumulated wall time and call
// count, filled by the nodes around the calls they make (ROS-free; no allocation or lookup by name while
// timing). Printed at the end of every run and written beside its bag (<bag stem>.cost.yaml).
#pragma once

#include <array>
#include <chrono>
#include <string>
#include <vector>

#include "rail_core/scene.hpp"

namespace rail::core {

class CostProfile {
 public:
  // What the time is spent on. The vehicle node fills the first two and the shared ones, the track node
  // kTrackStep and the shared ones.
  enum Component {
    kVehicleIntegration,  // CVODE steps: right-hand sides, Jacobians, contact on the rigid track (standalone)
    kTrackStep,           // contact on the (deformed) rails + the FE step (flexible) of each track step
    kTransportWait,       // send and receive of frames, waiting for the peer included
    kPublish,             // building and publishing messages, tf, markers
    kBagWrite,            // writing the bag
    kSetUp,               // building models, settling, factorising, opening transports
    kComponentCount
  };
  static const char* name(Component c);

  void add(Component c, double seconds) {
    seconds_[c] += seconds;
    ++calls_[c];
  }
  double seconds(Component c) const { return seconds_[c]; }
  long calls(Component c) const { return calls_[c]; }

  // Scoped timer: adds the time from construction to destruction to one component.
  class Scope {
   public:
    Scope(CostProfile& p, Component c) : p_(p), c_(c), t0_(std::chrono::steady_clock::now()) {}
    ~Scope() { p_.add(c_, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count()); }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    CostProfile& p_;
    Component c_;
    std::chrono::steady_clock::time_point t0_;
  };

  // Counts to report beside the times (e.g. "CVODE steps", "Newmark steps"), set at the end.
  void set_count(const std::string& what, double value) { counts_.emplace_back(what, value); }

  // The profile as YAML: node, wall time of the run loop, simulated time, each component's time, share
  // of the loop's wall time and calls (components never used show 0), the counts, and the scene's
  // effects (what was on).
  std::string to_yaml(const std::string& node, const Scene& scene, double loop_wall, double simulated) const;
  // The same as a few console lines.
  std::string to_text(const std::string& node, double loop_wall, double simulated) const;

 private:
  std::array<double, kComponentCount> seconds_{};
  std::array<long, kComponentCount> calls_{};
  std::vector<std::pair<std::string, double>> counts_;
};

}  // namespace rail::core
