// The track side of the co-simulation (paper section 5): the track receives the wheel-centre states of
// each track step, evaluates every wheel's contact on its rails and returns the equivalent wrench at each
// wheel centre (eq. 13); with effects.track_model flexible it also loads the FE rails with the rail-side
// wrenches (eq. 15 through the beam shape functions, eq. 16) and advances Newmark by one step.
//
//  - rigid_fe: only the track geometry is built (no FE mesh, no matrices, no factor, no integration);
//    the contact is evaluated on the rigid rails (RigidRailDeformation), as the vehicle alone does.
//  - flexible: the scene's FE track (buildSceneTrack) and a Newmark integrator at solver.track_step,
//    started from the static equilibrium under the track's own weight. The contact of step k (wheel
//    states at t_k) loads the rails at the end of the Newmark step t_{k-1} -> t_k. Default coupling
//    (kSemiImplicit): the contact geometry is found on the rails predicted at t_k, and the contact forces
//    are solved together with the step, so that they are the contact law's at the rails' state of t_k and
//    exactly the loads the rails carry. kExplicit: the contact on the rails of t_{k-1}, loads as computed
//    (section 5.3 read literally; unstable with contact damping, see doc/cosim_track.md). Step 0
//    evaluates the contact on the initial state and does not integrate. With the semi-implicit coupling
//    the step's load-free right-hand side and K_eff solve depend on the track's state only: they run on a
//    second thread from the end of one step (CosimTrackOptions::solve_beside) while the vehicle integrates
//    and the next frame's contacts are found, and the contact loads enter through the influence columns.
//  - the FE track is an FeTrack (fe_track.hpp): the full-length FullLengthTrack, or with
//    solver.track_window.enabled the moving TrackWindow; the contact, the coupling and the outputs go
//    through that one interface, only the window's moves below are the window's own.
//  - flexible with solver.track_window.enabled: the FE track is a TrackWindow (track_window.hpp) that
//    follows the wheels (follow() before each step from the frame's wheel arc lengths); d = d_g + w with
//    only w integrated; the contact sees d_g + w. A window move renumbers the DOFs: the influence
//    columns of the semi-implicit coupling are dropped when the move refactorised K_eff and kept when it
//    reused it (same matrices and numbering); the rail arrays are rebuilt. A move allocates.
//
// Wheel centre: WheelState::p_wheel_in_world is taken as the contact code's wheel centre, the axle point
// in the plane of the taping line (rail_contact/contact_detection.hpp); the returned moment is about that
// point, world axes. Wheel id = 2 * wheelset + side (0 left, 1 right). The contact model is built as the
// vehicle side builds it on the rigid track: wheel profile per vehicle.wheel_profile, nominal radius from
// the scene, the scene's rail profile, the scene's effects as the contact options. ROS-free.
#pragma once

#include <Eigen/Core>

#include <array>
#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <rail_contact/profile.hpp>
#include <rail_contact/rail_deformation.hpp>
#include <rail_contact/track_geometry.hpp>
#include <rail_contact/wheel_contact.hpp>
#include <rail_core/coupling/frames.hpp>
#include <rail_core/geometry_builder.hpp>
#include <rail_core/scene.hpp>

#include "rail_track_node/fe_track.hpp"
#include "rail_track_node/hanging_support.hpp"
#include "rail_track_node/newmark.hpp"
#include "rail_track_node/pad_forces.hpp"
#include "rail_track_node/rail_probe.hpp"
#include "rail_track_node/scene_track.hpp"
#include "rail_track_node/track_simulator.hpp"
#include "rail_track_node/track_window.hpp"

namespace rail {
namespace track {

/// How the contact of track step k is coupled to the FE rails (flexible only).
enum class CosimCoupling {
  /// Contact evaluated on the rails of t_{k-1}; its loads end the Newmark step (one solve, no iteration).
  /// Unstable with the default contact damping and at low speed: the normal damper and the creep forces
  /// act on a one-step-old rail velocity (doc/cosim_track.md). Kept as the reference of section 5.3.
  kExplicit,
  /// Contact geometry evaluated on the rails predicted at t_k (d + h v); the contact forces then solved
  /// with the Newmark step: the law (eq. 9, creepages, Polach) along the rail contact point's motion at
  /// t_k, Newton on 3 force components per contact through a low-rank update of the K_eff solve
  /// (influence columns of the existing factor, cached per rail node). One sparse solve per step.
  kSemiImplicit,
};

/// What the track side is built from, resolved once from a scene (resolveCosimTrack) and constant
/// afterwards: what CosimTrack takes instead of the Scene.
struct CosimTrackSetup {
  std::string source;              ///< the scene file; build errors start with it
  int wheel_count = 0;             ///< 2 x vehicle.wheelsets, > 0
  double start_arc_length = 0.0;   ///< m, the leading wheelset's at t = 0 (vehicle.start_arc_length)
  double track_step = 0.0;         ///< s, solver.track_step (flexible)
  rail::core::TrackWindow window;  ///< solver.track_window (flexible)
  std::optional<TrackLine> line;   ///< flexible: the FE track's line; rigid_fe: empty
  std::optional<rail::contact::TrackGeometry> rigid_geometry;  ///< rigid_fe: the rails' geometry alone
  rail::contact::WheelProfile wheel_profile;                   ///< vehicle.wheel_profile
  rail::contact::ProfileCurve rail_profile;                    ///< the scene's rail profile
  double nominal_radius = 0.0;                                 ///< m, vehicle.nominal_radius
  rail::core::SceneContact contact;                            ///< the scene's effects and contact section
};

/// Resolves the track side of a co-simulated scene; track: rail height and gravity of the FE track
/// (flexible only). Throws rail::core::SceneError naming the scene file when the scene has no vehicle or
/// runs the rigid track alone, or its data are not physical.
CosimTrackSetup resolveCosimTrack(const rail::core::Scene& scene, const SceneTrackOptions& track = {});

/// What the scene does not say (constant after building).
struct CosimTrackOptions {
  /// Contact data without a scene key (materials, Polach, detection); the setup's contact (the scene's
  /// effects and contact section) overrides the fields it has, as on the vehicle side.
  rail::contact::WheelContactOptions contact;
  bool include_gravity = true;  ///< track self-weight f_g in every Newmark step and in the initial state
  CosimCoupling coupling = CosimCoupling::kSemiImplicit;  ///< flexible only
  /// kSemiImplicit: the right-hand side and K_eff solve of the next step, which depend on the track's own
  /// state only, run on a second thread as soon as a step ends (while the vehicle integrates and the
  /// contacts of the next frame are evaluated); the contact loads enter through the influence columns. The
  /// results equal the one-thread path's to rounding. false: the solve runs inside step().
  bool solve_beside = true;
  /// How K_eff is factorised and solved (SparseCholesky); the supernodal CHOLMOD solve is the reference.
  /// kBlockedTwoParts or kSimplicialTwoParts with solve_beside: the loop's thread, once its contacts are
  /// found, solves the second part of each triangular pass of the base solve while the worker solves the
  /// first.
  CholeskyLayout factor_layout = CholeskyLayout::kBlockedTwoParts;
  /// kSemiImplicit: an influence column K_eff^{-1} e_j is stored over the DOF window where it exceeds this
  /// fraction of its largest entry (the DOFs are numbered plane by plane along the track).
  double influence_tolerance = 1e-12;
  /// A wheel surface whose last search found it far from its rail skips its searches while the wheel
  /// cannot have come near (rail_contact's DetectionWork::skip_far_searches): the same forces; its
  /// out-of-contact gap is then a lower bound, so exact gaps are asked for where they are published
  /// (setExactGaps, CosimTrackRun at the output steps).
  bool skip_far_searches = true;
  /// With solver.track_window.enabled: the window settings the scene does not hold (entering_static,
  /// condensed_ends, boundary_length, end_dashpots). behind, ahead, shift and length come from the setup's
  /// window, dt from its track_step, include_gravity from the field above. vehicle_length (m, first
  /// to last wheel) is the vehicle's wheel span, required with a window: the vehicle node sends it in the
  /// handshake (VehicleModel::wheelSpan()); a replay takes it from the recorded run's first frame.
  TrackWindowSettings window;
  /// Optional cost clock (must outlive the track; its window.cost is set from this one): contact
  /// evaluations (contact_detection, contact_forces including the semi-implicit Newton, flange searches,
  /// spin evaluations), the Newmark parts (track_rhs, track_solve, damping products), window moves, and
  /// padForces() / sectionDeflection() (pad_forces, rail_deflection). null = no timing.
  rail::core::CostClock* cost = nullptr;
};

/// Why step() refused a frame (nothing was evaluated or integrated; with a track window, the window may have
/// moved, carrying its state).
enum class CosimStepStatus {
  kOk,
  kWrongWheelCount,
  kBadWheelId,
  kWheelOutsideWindow,  ///< track window: a wheel's arc length is off the window (or not finite) after follow()
  kWindowMoveFailed,    ///< track window: building the moved window threw (out of memory, factorisation)
};

/// Track side of the co-simulation: built once from a resolved scene, then advanced by step().
class CosimTrack {
 public:
  /// Throws std::runtime_error (rail::core::SceneError for the line's data) when the options or the
  /// model's data are not physical. Allocates (set-up).
  explicit CosimTrack(CosimTrackSetup setup, const CosimTrackOptions& options = {});
  ~CosimTrack();
  CosimTrack(const CosimTrack&) = delete;
  CosimTrack& operator=(const CosimTrack&) = delete;

  /// Track step k = states.step (t_k): evaluates each wheel's contact on the rails (flexible: see
  /// CosimCoupling), loads the FE rails and advances Newmark to t_k (flexible, k > 0), writes the
  /// wheel-centre wrenches (N, N m about p_wheel_in_world, world axes) into out (ids, count; step, time
  /// and hash copied from states). out must hold states.count wheels. Refuses (and changes nothing) when
  /// states.count differs from the scene's wheel count or a wheel id is out of range or repeated.
  /// No allocation, no exception, no logging.
  CosimStepStatus step(const rail::core::coupling::WheelStateFrame& states,
                       rail::core::coupling::WrenchFrame& out) noexcept;
  /// step() in two parts, so that a caller can hand the wrenches on before the track finishes its step:
  /// stepForces writes `out` exactly as step() does; finishStep then loads the rails with the step's
  /// forces, completes the Newmark step and starts the next base solve. Until finishStep, state(),
  /// railDeformation(), sectionDeflection(), padForces() and energy() still describe t_{k-1}; the next
  /// stepForces finishes a pending step first. Same results as step(). No allocation, no exception.
  CosimStepStatus stepForces(const rail::core::coupling::WheelStateFrame& states,
                             rail::core::coupling::WrenchFrame& out) noexcept;
  void finishStep() noexcept;
  /// true: the next steps search every wheel surface, so that the gaps of surfaces out of contact are the
  /// searched ones (for a step whose contacts are published); false: far surfaces skip their searches
  /// again (with CosimTrackOptions::skip_far_searches). The forces are the same either way.
  void setExactGaps(bool exact) noexcept;

  /// FE track integrated (flexible; full-length or windowed).
  bool flexible() const { return fe_ != nullptr; }
  /// The moving window (flexible with solver.track_window.enabled), or nullptr.
  const TrackWindow* trackWindow() const { return window_; }
  /// Track window: moves, moves that refactorised K_eff (the others reused it), influence-column caches
  /// dropped (one per refactorising move, semi-implicit), wall time of all moves including the rail and
  /// cache updates of this object (s). 0 without a window.
  int windowMoves() const;
  int windowRebuilds() const;
  int influenceCacheDrops() const { return cache_drops_; }
  double windowMoveSeconds() const { return window_move_s_; }
  int wheelCount() const { return static_cast<int>(result_.size()); }
  /// Newmark steps done since construction (always 0 with rigid_fe).
  long newmarkSteps() const { return newmark_steps_; }
  /// Frames stepped since construction.
  long framesStepped() const { return frames_; }
  CosimCoupling coupling() const { return coupling_; }
  /// kSemiImplicit: influence columns solved so far (6 per rail node a wheel reaches), columns cut to the
  /// window capacity (0 unless the window estimate of the build was short), window capacity (DOFs).
  long influenceSolves() const;
  long influenceClipped() const;
  int influenceWindow() const;
  /// kSemiImplicit: Newton iterations of the contact forces summed over the steps, and steps that ended
  /// without reaching the tolerance (contact points within 1e-12 m, forces within 1e-9 relative).
  long newtonIterations() const;
  long newtonUnconverged() const;
  /// kSemiImplicit with the solve beside and a factor in two parts: steps whose Newton started once the
  /// base solve's backward rows it reads were done, before the rest of that pass.
  long firstRowsSteps() const { return first_rows_steps_; }

  const rail::contact::TrackGeometry& geometry() const { return *geometry_; }
  const rail::contact::WheelContactModel& contactModel() const { return *contact_model_; }
  /// The full-length FE track (flexible without a window), or nullptr (rigid_fe, or a track window: see
  /// trackWindow()).
  const SceneTrack* sceneTrack() const { return full_ != nullptr ? &full_->sceneTrack() : nullptr; }
  /// Newmark state (flexible only; d, v, a over the free DOFs); nullptr with rigid_fe. With a track
  /// window: w, w', w'' over the current window (the total displacement is trackWindow()->staticState() + d).
  const NewmarkState* state() const;
  /// Rail nodal displacements and velocities of the FE state after the last step (t_k; the initial state
  /// before the first), for a contact evaluation on the current rails; nullptr with rigid_fe. Filled when
  /// read (not at every step). No allocation.
  const rail::contact::BeamRailDeformation* railDeformation() const;

  /// Contact results of wheel `id` from the last step (contact points, forces, rail wrenches). With
  /// kSemiImplicit the geometry is that found on the predicted rails; the normal and creep forces, the
  /// ellipse, creepages and penetration (rate) are those solved at t_k.
  const rail::contact::WheelContactResult& contact(int id) const { return result_[static_cast<std::size_t>(id)]; }
  /// Caller-visible detection counters and impact memories of wheel `id`.
  const rail::contact::WheelContactWork& contactWork(int id) const { return work_[static_cast<std::size_t>(id)]; }

  /// Adds a rail deflection section at track arc length s (m) (set-up only); returns its index. Throws
  /// std::runtime_error when s is off the meshed rails (flexible) or off the track (rigid_fe). With a
  /// track window the section is the window's (TrackWindow::addSection: anywhere on the line).
  int addSection(double s);
  int sectionCount() const;
  /// Displacement (m) and small rotation (rad) of both rails' centre lines at section i from the current
  /// state, track-frame components (x along, y left, z up). Zero with rigid_fe. With a track window:
  /// TrackWindow::sectionDeflection (self-weight static value + w). No allocation.
  void sectionDeflection(int i, RailSectionDeflection& out) const;
  /// Pad forces and rail displacements at the sleepers with s in [s_from, s_to] (m) from the current
  /// state (flexible; with a track window the sleepers inside it, total displacement d_g + w), at most
  /// capacity of them into out; returns how many (0 with rigid_fe). The pads are indexed on the first call
  /// and again after a window move (allocates; rare); otherwise no allocation.
  int padForces(double s_from, double s_to, PadForceSample* out, int capacity) const;
  /// Mechanical energy of the FE track (J) relative to its self-weight equilibrium d_s (K d_s = f_g): kinetic
  /// 1/2 v' M v and potential 1/2 (d - d_s)' K (d - d_s), which is the strain energy plus the work of gravity
  /// counted from d_s. With a track window: over the window, w being already relative to d_s
  /// (TrackWindow::dynamicEnergy). With hanging sleepers K holds their ballast as closed, so where a void is
  /// open the potential is not the track's (indicative only). Returns false (zeros) with rigid_fe. No
  /// allocation.
  bool energy(double& kinetic, double& potential) const noexcept;
  /// The hanging sleepers of the integrated mesh (full track or current window), or nullptr when it has
  /// none (rigid_fe, no hanging zone).
  const HangingSupports* hanging() const;
  /// Sleepers of the integrated mesh (full track or window; 0 with rigid_fe): enough capacity for padForces.
  int sleeperCount() const;
  /// Same for any displacement vector d over the FE free DOFs (flexible full-length; e.g. a static
  /// solution). Throws std::runtime_error with a track window (its DOFs change at every move).
  void sectionDeflection(int i, const Eigen::VectorXd& d, RailSectionDeflection& out) const;

 private:
  struct Section {
    double arc_length;  // s of the section [m]
    RailProbes rail;
  };
  struct Implicit;  // semi-implicit coupling: influence cache and this step's contact links
  NewmarkIntegrator& integ() noexcept { return fe_->integrator(); }
  NewmarkState& st() noexcept { return fe_->mutableState(); }
  const NewmarkState& st() const noexcept { return fe_->state(); }
  const TrackMesh& feMesh() const noexcept { return fe_->mesh(); }
  void buildRails();                   // deformation_ and rail_dofs_ on feMesh() (set-up, window move)
  void onWindowMove();                 // after a move: rails, influence cache (allocates)
  void refreshRails() const noexcept;  // the rails at the current state unless they hold it already
  void fillPredictedDeformation() noexcept;
  void predictRail(int g, double& d_p, double& v_p) const noexcept;
  void evaluateContacts(const rail::core::coupling::WheelStateFrame& states,
                        rail::core::coupling::WrenchFrame& out) noexcept;
  void writeWrench(int i, const rail::contact::WheelState& ws, const rail::contact::WheelContactResult& res,
                   rail::core::coupling::WrenchFrame& out) const noexcept;
  void implicitCorrection(const rail::core::coupling::WheelStateFrame& states,
                          rail::core::coupling::WrenchFrame& out) noexcept;
  // The phases of implicitCorrection: the contacts in contact at the prediction (links), their influence
  // system G, the points' displacement under the base solve, the Newton solve of their forces, and the
  // contact results; the step's displacement follows in finishStep (addColumnLoads).
  void gatherLinks(const rail::core::coupling::WheelStateFrame& states) noexcept;
  void buildInfluence() noexcept;
  void baseDisplacement() noexcept;
  void solveLinkForces() noexcept;
  void applyLinkForces(const rail::core::coupling::WheelStateFrame& states,
                       rail::core::coupling::WrenchFrame& out) noexcept;
  // finishStep: d = x_b + K_eff^{-1} W f over the DOFs [begin, end), then the loads cleared once.
  void addColumnLoads(int begin, int end) noexcept;
  void clearColumnLoads() noexcept;
  // The load-free right-hand side and solve of the next step (stepDisplacement() = K_eff^{-1} rhs_0): on
  // the second thread (startBaseSolve, then awaitBaseSolve) or here (solveBase). With finish, the two
  // threads first complete the step (column loads, Newmark completion), each over half of the DOFs
  // (completionSplit()); the second thread solves once both halves are done, finishStep awaits its half
  // (awaitCompletion). shared (the worker's call): with a factor in two parts the loop's thread, waiting in
  // awaitBaseSolve, takes the second part of each triangular solve (helpBaseSolve).
  void solveBase(bool shared = false) noexcept;
  bool claimSecondPart(int phase) noexcept;
  void sharePart(int phase) noexcept;
  bool helpBaseSolve() noexcept;
  bool awaitHelping(const std::atomic<bool>& flag) noexcept;
  // The loop's thread completes the DOFs below, the worker the rest (the DOF count changes only at a move).
  int completionSplit() const noexcept { return static_cast<int>(st().d.size()) / 2; }
  void startBaseSolve(bool finish) noexcept;
  void awaitCompletion() noexcept;
  void awaitBaseSolve() noexcept;
  // The Newton reads the base solve at its links' DOFs only. With a factor in two parts, the worker solves
  // first the backward rows those DOFs read (marked by markFirstRows() from the last step's links and their
  // neighbouring rail nodes), says so (first_ready_), then the other rows; awaitFirstRows() waits for the
  // first ones when they cover every link DOF (false: the caller waits for the whole solve), and finishStep
  // for the rest before the completion.
  void markFirstRows() noexcept;
  bool awaitFirstRows() noexcept;
  void takeWorkerCost() noexcept;
  void fillHangingLoads() noexcept;
  void sizeHangingLoads();  // set-up and window moves
  void workerLoop() noexcept;
  void claimNodeColumns(int rail, int node) noexcept;  // a slot for the node's columns (queued if new)
  void solveSlotColumns(int slot, int lane) noexcept;
  void solvePendingColumns() noexcept;  // the queued slots, on both threads when the worker is free
  void helpPendingColumns() noexcept;   // the worker's side
  void solveColumn(int dof, int& lo, int& len) noexcept;
  void trimColumn(int dof, const double* x, int& lo, int& len) noexcept;

  std::unique_ptr<rail::contact::TrackGeometry> rigid_geometry_;  // rigid_fe: the geometry alone
  std::unique_ptr<FeTrack> fe_;                                   // flexible: the integrated FE track
  TrackWindow* window_ = nullptr;                                 // fe_ when it is the moving window
  FullLengthTrack* full_ = nullptr;                               // fe_ when it is the full-length track
  mutable std::unique_ptr<PadForceProbe> pad_probe_;              // padForces(): pads of the current mesh
  mutable int pad_probe_moves_ = -1;                              // window moves when it was built
  const rail::contact::TrackGeometry* geometry_ = nullptr;
  rail::contact::WheelProfile wheel_profile_;
  rail::contact::ProfileCurve rail_profile_;
  std::unique_ptr<rail::contact::WheelContactModel> contact_model_;
  std::vector<rail::contact::WheelContactWork> work_;      // per wheel id
  std::vector<rail::contact::WheelContactResult> result_;  // per wheel id, last step
  std::vector<unsigned char> seen_;                        // per wheel id, step() scratch
  // Flexible only.
  std::unique_ptr<NodalLoads> loads_;
  std::unique_ptr<rail::contact::BeamRailDeformation> deformation_;
  mutable bool rails_current_ = false;         // deformation_ holds the current state (else a prediction or stale)
  std::array<std::vector<int>, 2> rail_dofs_;  // per rail: free DOF of (node k, dof j) at 6 k + j
  std::vector<Section> sections_;              // rigid_fe (flexible: the FE track's)
  CosimCoupling coupling_ = CosimCoupling::kSemiImplicit;
  std::unique_ptr<Implicit> implicit_;
  long newmark_steps_ = 0;
  long frames_ = 0;
  // What finishStep still has to do for the last accepted frame: nothing, only start the next base solve
  // (no integration: rigid_fe, step 0), or the Newmark step too.
  enum class Finish { kNone, kFrameOnly, kIntegrate };
  Finish finish_ = Finish::kNone;
  int seen_rebuilds_ = 0;  // window rebuilds already handled by onWindowMove
  int cache_drops_ = 0;
  double window_move_s_ = 0.0;
  rail::core::CostClock* cost_ = nullptr;               // CosimTrackOptions::cost
  rail::contact::ContactCost* contact_cost_ = nullptr;  // &cost_->contact, or null
  // The base solve: its state (none, running beside, done for the current state and window), the second
  // thread and its own cost clock (added to cost_ by the loop's thread when the result is taken).
  enum class BaseSolve { kNone, kRunning, kReady };
  BaseSolve base_ = BaseSolve::kNone;
  bool solve_beside_ = false;
  bool skip_far_searches_ = false;
  bool exact_gaps_ = false;      // setExactGaps: every surface searched
  bool columns_beside_ = false;  // influence columns may be solved while the base solve runs (own scratch)
  std::thread worker_;
  std::mutex worker_mutex_;
  std::condition_variable worker_cv_;
  bool worker_job_ = false, worker_done_ = false, worker_stop_ = false;
  bool worker_finish_ = false;                // the job first completes the step (column loads, Newmark completion)
  bool worker_completed_ = false;             // ... and has done so
  std::atomic<bool> lower_completed_{false};  // the loop's thread has completed its DOFs (the worker spins)
  // worker_job_, worker_completed_ and worker_done_ as each side spins on them before it sleeps (no lock).
  std::atomic<bool> worker_posted_{false}, worker_completed_flag_{false}, worker_done_flag_{false};
  rail::core::CostClock worker_cost_;
  // A base solve shared by both threads (factor in two parts): the worker opens phase 0 (forward) after the
  // right-hand side and phase 1 (backward, or its first rows) after the separator (solve_stage_ = 1, 2), and
  // with first rows phase 2 (the other rows) once they are done (3); the second part of each phase goes to
  // whichever thread claims it first.
  bool split_solve_ = false;
  std::atomic<int> solve_stage_{0};
  std::atomic<bool> part_claimed_[3] = {false, false, false}, part_done_[3] = {false, false, false};
  std::vector<int> first_dofs_, first_candidate_;  // marked in the factor; this step's (both preallocated)
  bool first_marked_ = false;                      // first_dofs_ are marked in the current factor
  bool solve_first_ = false;                       // the posted base solve solves the marked rows first
  std::atomic<bool> first_ready_{false};
  long first_rows_steps_ = 0;
  rail::core::CostClock completion_cost_;  // the worker's completion of a step (awaitCompletion takes it)
  // Influence columns of the rail nodes the links reached (Implicit::pending), solved by both threads: each
  // takes the next slot (column_next_) until none is left; the worker joins once its base solve is done.
  std::atomic<bool> columns_posted_{false}, worker_in_columns_{false};
  std::atomic<int> column_next_{0}, column_done_{0};
  // The loads of the hanging sleepers in the step being solved (the base solve's, or the explicit step's
  // beside the contact loads).
  NodalLoads hanging_loads_{0};
};

}  // namespace track
}  // namespace rail
