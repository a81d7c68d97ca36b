// Standalone flexible track under prescribed moving loads (paper section 3.3 with f_c from the scene's
// moving_loads): the caller advances it with advanceTo(t); each Newmark step re-places the loads and
// does one solve. Rail deflections at chosen sections from the beam shape functions. ROS-free.
//
// Loads: load i sits at s_i(t) = start_arc_length + speed t - offset_i on the rails it names. Its vertical
// part (N, downward positive) acts along -b, b the track normal; its lateral part (N) along the track's
// lateral axis toward the field side (+n on the left rail, -n on the right one). Both act at the top of
// the rail head on the rail axis, i.e. on the rail centre line plus the moment of the head-to-centroid arm.
// A load off the meshed rails is not applied.
#pragma once

#include <Eigen/Core>

#include <array>
#include <chrono>
#include <functional>
#include <vector>

#include <rail_core/scene.hpp>

#include "rail_track_node/hanging_support.hpp"
#include "rail_track_node/newmark.hpp"
#include "rail_track_node/rail_probe.hpp"
#include "rail_track_node/track_mesh.hpp"
#include "rail_track_node/track_model.hpp"

namespace rail {
namespace track {

/// Progress of a run, for the caller to print.
struct SimulationProgress {
  double t = 0.0;                 ///< simulated time reached, s
  double t_end = 0.0;             ///< end of the run, s
  double percent = 0.0;           ///< 100 t / t_end
  double real_time_factor = 0.0;  ///< simulated seconds per wall-clock second so far
  double eta = 0.0;               ///< wall-clock seconds left at that rate
  long steps = 0;                 ///< Newmark steps done
};
using ProgressCallback = std::function<void(const SimulationProgress&)>;

/// Prescribed loads and integration settings of a run.
struct SimulatorSettings {
  double track_step = 2e-5;     ///< Newmark step h, s
  double t_end = 0.0;           ///< end of the run, s
  bool include_gravity = true;  ///< f_g in every step (and in the initial static equilibrium)
  double rail_height = 0.172;   ///< rail foot to head top, m (moment arm of the loads: height - centroid)
  rail::core::MovingLoads loads;
  /// Optional cost clock (must outlive the simulator): the Newmark integrator's parts and counts, and
  /// sectionDeflection() into kRailDeflection. null = no timing.
  rail::core::CostClock* cost = nullptr;
};

class TrackSimulator {
 public:
  /// model must outlive the simulator. Factorises K_eff and starts from the static equilibrium under
  /// gravity and the loads at t = 0 (K d0 = f_g + f(0), v0 = 0, a0 from the equation of motion).
  /// Allocates (set-up). Throws std::runtime_error on a bad step or end time.
  TrackSimulator(const TrackModel& model, const SimulatorSettings& settings);

  /// Reports progress through cb at most every interval_s wall-clock seconds while advancing (and once at
  /// the end of the run). Set-up only.
  void setProgressCallback(ProgressCallback cb, double interval_s = 2.0);

  /// Steps until time() reaches t (rounded to a whole number of steps), not beyond t_end. No allocation.
  void advanceTo(double t);
  /// Advances to t_end.
  void run() { advanceTo(settings_.t_end); }

  double time() const { return static_cast<double>(steps_) * settings_.track_step; }
  double endTime() const { return settings_.t_end; }
  bool finished() const { return steps_ >= end_steps_; }
  long steps() const { return steps_; }
  const NewmarkState& state() const { return state_; }
  const TrackModel& model() const { return model_; }

  /// Adds a deflection section at arc length s; frames gives the track frame there (set-up only).
  /// Returns its index, or throws std::runtime_error if s is not on the meshed rails.
  int addSection(double s, const TrackFrameFunction& frames);
  int sectionCount() const { return static_cast<int>(sections_.size()); }
  /// Deflection of both rails at section i from the current state. No allocation.
  void sectionDeflection(int i, RailSectionDeflection& out) const { sectionDeflection(i, state_.d, out); }
  /// Same for any displacement vector d over the free DOFs (e.g. a static solution).
  void sectionDeflection(int i, const Eigen::VectorXd& d, RailSectionDeflection& out) const;

  /// Nodal loads of the moving loads at time t (cleared first). No allocation.
  void loadsAt(double t, NodalLoads& loads) const;

 private:
  struct Section {
    double arc_length;  // s of the section [m]
    RailProbes rail;
  };
  void reportProgress();

  const TrackModel& model_;
  SimulatorSettings settings_;
  double head_arm_ = 0.0;
  NewmarkIntegrator integrator_;
  NewmarkState state_;
  HangingSupports hanging_;  // hanging sleepers of the mesh (their loads join loads_ in each step)
  NodalLoads loads_;
  long steps_ = 0, end_steps_ = 0;
  std::vector<Section> sections_;
  ProgressCallback progress_;
  double progress_interval_ = 2.0;
  std::chrono::steady_clock::time_point wall_start_, last_report_;
  long steps_at_start_ = 0;
};

/// Adds the equivalent nodal loads of a wheel-like load on rail `rail` (RailSide) at arc length s:
/// vertical (N, downward along -b of the track frame) and lateral (N, toward the field side), acting at
/// the top of the rail head, head_arm (m) above the rail centroid along the inclined rail axis.
/// inclination: rail inclination (rad) of the mesh. Returns false if s is off the rails (nothing added)
/// or the load vector is full. No allocation.
bool addRailHeadLoad(const TrackMesh& mesh, double inclination, double head_arm, int rail, double s, double vertical,
                     double lateral, NodalLoads& loads);

/// End time of a moving-load scene (s): solver.end.time, or the time the first load reaches
/// solver.end.arc_length at moving_loads.speed.
double movingLoadEndTime(const rail::core::Scene& scene);

}  // namespace track
}  // namespace rail
