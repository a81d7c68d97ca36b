// Where a run's wall time goes: a fixed set of components, each with its accumulated wall time and call
// count, filled by the nodes around the calls they make (ROS-free; no allocation or lookup by name while
// timing). Printed at the end of every run and written beside its bag (<bag stem>.cost.yaml).
#pragma once

#include <array>
#include <chrono>
#include <string>
#include <vector>

#include <rail_contact/contact_cost.hpp>

#include "rail_core/scene.hpp"

namespace rail::core {

// The finer split of a run's cost, filled by the cores (VehicleSimulator, CosimTrack, TrackWindow,
// TrackSimulator, NewmarkIntegrator) when the caller passes one at construction; null = no timing and no
// cost. Owned by the caller; plain arrays, no allocation; a steady-clock read around each timed part.
// Nesting in the coarse components of CostProfile (the node prints it):
//   vehicle_integration > vehicle_rhs, vehicle_jacobian (> contact_detection, contact_forces), floor_accelerations,
//                         energy_output (vehicle side)
//   track_step          > contact_detection, contact_forces, track_rhs, track_solve, track_solve_wait,
//                         window_moves (track_rhs and track_solve beside it when run on a second thread)
//   publish             > rail_deflection, pad_forces, contact_point_output, markers, energy_output (track side)
struct CostClock {
  enum Part {
    kVehicleRhs,          // vehicle right-hand sides for the integrator's steps (contact on the rigid track inside)
    kVehicleJacobian,     // right-hand sides of CVODE's difference-quotient Jacobians (BDF)
    kTrackRhs,            // Newmark right-hand side M x1 + C x2 + f and the step's completion (vector work; on the
                          // second thread with the semi-implicit coupling's column loads, the completion shared
                          // with the loop's thread, whose share is also part of track_step)
    kTrackSolve,          // Newmark K_eff solve (CHOLMOD), one per step
    kTrackSolveWait,      // the step waiting for its right-hand side and solve done beside it (second thread)
    kWindowMoves,         // track window moves (model build or reuse, state carry-over, rail arrays)
    kFloorAccelerations,  // effects.floor_acceleration_output: accelerometer readings
    kPadForces,           // effects.pad_force_output: pad forces under the train
    kMarkers,             // effects.rviz_markers: building and publishing markers
    kRailDeflection,      // effects.rail_deflection_output: section deflections
    kContactPointOutput,  // effects.contact_point_output: building and publishing contact points
    kEnergyOutput,        // effects.energy_output: vehicle (in its outputs) or FE track (publish) energy
    kPartCount
  };
  enum Count {
    kDampingProducts,          // C v products in the Newmark right-hand side (effects.track_damping, end dashpots)
    kEndDashpotForces,         // end-dashpot forces inside those products (effects.absorbing_ends), per dashpot
    kIrregularityEvaluations,  // irregularity stations evaluated during the run loop (set by the caller)
    kCountCount
  };
  static const char* name(Part p);
  static const char* name(Count c);

  void add(Part p, double s) {
    seconds[p] += s;
    ++calls[p];
  }

  // Adds the time from construction to destruction to part p of *clock; nothing (no clock read) when
  // clock is null.
  class Scope {
   public:
    Scope(CostClock* clock, Part p) : clock_(clock), p_(p) {
      if (clock_ != nullptr) t0_ = std::chrono::steady_clock::now();
    }
    ~Scope() {
      if (clock_ != nullptr)
        clock_->add(p_, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count());
    }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    CostClock* clock_;
    Part p_;
    std::chrono::steady_clock::time_point t0_;
  };

  std::array<double, kPartCount> seconds{};  // [s]
  std::array<long, kPartCount> calls{};
  std::array<long long, kCountCount> counts{};
  // True when track_rhs and track_solve ran on a second thread beside the loop (not inside its wall time);
  // the loop's share of them is then track_solve_wait.
  bool track_solve_beside = false;
  // contact_detection (detection_seconds) and contact_forces (forces_seconds), flange searches, creep
  // evaluations with spin: filled by the per-wheel contact evaluation.
  rail::contact::ContactCost contact;
};

// An optional output of the nodes: runs produce() under part's clock when the effect is on; does nothing
// (no call, no clock read) when it is off. Returns on.
template <class F>
bool timedOutput(CostClock* clock, CostClock::Part part, bool on, F&& produce) {
  if (!on) return false;
  CostClock::Scope scope(clock, part);
  produce();
  return true;
}

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
  // More time for a call already counted (a part of it done later, e.g. a step finished after the send).
  void addSeconds(Component c, double seconds) { seconds_[c] += seconds; }
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
  void setCount(const std::string& what, double value) { counts_.emplace_back(what, value); }

  // The profile as YAML: node, wall time of the run loop, simulated time, each component's time, share
  // of the loop's wall time and calls (components never used show 0), the counts, and the scene's file
  // and effects (what was on).
  // clock: the finer split (nested in the components as CostClock says), with per parent "other" =
  // parent - its parts, so that the shares add up at each level; null: none.
  std::string toYaml(const std::string& node, const std::string& scene_file, const Effects& effects, double loop_wall,
                     double simulated, const CostClock* clock = nullptr) const;
  // The same as a few console lines.
  std::string toText(const std::string& node, double loop_wall, double simulated,
                     const CostClock* clock = nullptr) const;

  // One line of the finer split: name, seconds, calls and the coarse component it is part of.
  struct FinerLine {
    const char* name;
    double seconds;
    long calls;
    Component parent;  ///< kComponentCount: beside the loop, on a second thread
  };
  // The finer split of clock in this profile (contact under track_step if the profile has track steps,
  // else under vehicle_integration), fixed order, at most kMaxFinerLines lines.
  static constexpr int kMaxFinerLines = 14;
  int finerLines(const CostClock& clock, std::array<FinerLine, kMaxFinerLines>& lines) const;

 private:
  std::array<double, kComponentCount> seconds_{};
  std::array<long, kComponentCount> calls_{};
  std::vector<std::pair<std::string, double>> counts_;
};

}  // namespace rail::core
