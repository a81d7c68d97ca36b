// Moving active window of the flexible track (paper section 3 on a part of the line only): the FE track
// is meshed and integrated over [s_begin, s_end], a whole number of sleeper bays that follows the vehicle
// (from `behind` metres behind its last wheel to at least `ahead` metres ahead of its first one). The cost
// of a step depends on the window length, not on the length of the line. ROS-free. Design, figures and
// commands: doc/track_window.md.
//
// State by superposition (the model is linear): the displacement of the track is
//   d = d_g + w
// with d_g the static state under the track's own weight (K d_g = f_g on the current window) and w the
// motion caused by the external (wheel) loads, integrated by Newmark from M w'' + C w' + K w = f_c.
//
// Window ends: at each artificial end the line beyond it (boundary_length metres of straight track with the
// end's cant) is statically condensed onto the end plane (Guyan: K, C, M and the self-weight load of the
// track outside, which so follows the end plane quasi-statically instead of being cut off), plus grounded
// absorbing dashpots at the rail ends (absorbingEndDashpots). At the line's own ends the scene's
// effects.absorbing_ends decides, as for the full model.
//
// Move: when [s_rear - behind, s_front + ahead] leaves the window, the window moves by a whole number of
// shift distances. The model over the new range is built (mesh, M, C, K, f_g, K_eff factor, d_g); when it
// is a translated copy of the current one (straight line) the current matrices, factor and d_g are kept.
// (w, w', w'') of every node in both windows (same sleeper / rail node index along the line, world-axis
// DOFs) is copied; the entering nodes get the static continuation of the carried field (K_ee x_e =
// -K_ec x_c), which is what the condensed end held them at. A move allocates; step() does not.
#pragma once

#include <Eigen/Core>

#include <array>
#include <memory>
#include <vector>

#include <rail_contact/rail_deformation.hpp>
#include <rail_contact/track_geometry.hpp>
#include <rail_core/scene.hpp>

#include "rail_track_node/fe_track.hpp"
#include "rail_track_node/hanging_support.hpp"
#include "rail_track_node/newmark.hpp"
#include "rail_track_node/scene_track.hpp"
#include "rail_track_node/track_model.hpp"
#include "rail_track_node/track_simulator.hpp"

namespace rail {
namespace track {

/// Settings of a window (constant after building). Lengths in m.
struct TrackWindowSettings {
  double behind = 5.0;          ///< kept behind the last wheel (load), m
  double ahead = 5.0;           ///< kept ahead of the first wheel (load), m
  double shift = 3.0;           ///< distance of one move, m; rounded up to whole sleeper bays
  double vehicle_length = 0.0;  ///< first to last wheel (load), m
  /// Window length, m, rounded up to whole sleeper bays; 0 = the minimum,
  /// vehicle_length + behind + ahead + shift. A shorter window is refused.
  double length = 0.0;
  double track_step = 0.0;  ///< Newmark step h, s (trackStepRule); the co-simulation sets solver.track_step
  /// Entering nodes start at the static continuation of the carried-over w, w', w'' (K_ee x_e = -K_ec x_c);
  /// false: at rest (x_e = 0).
  bool entering_static = true;
  /// Artificial window ends carry the line beyond them statically condensed (Guyan) onto the end plane:
  /// K, C, M and the self-weight load of boundary_length metres of track, so that the track outside
  /// follows the end plane quasi-statically instead of being cut off. false: the window ends are free.
  bool condensed_ends = true;
  double boundary_length = 120.0;  ///< m of track condensed at each artificial end
  bool end_dashpots = true;        ///< absorbing dashpots at the rail ends of every artificial end
  bool include_gravity = true;     ///< d_g (self-weight static state) in the rails' and sections' output
  /// Optional cost clock of the window's Newmark integrators (NewmarkIntegrator); must outlive the window.
  rail::core::CostClock* cost = nullptr;
  CholeskyLayout factor_layout = CholeskyLayout::kSimplicial;  ///< how each window's K_eff is solved
};

/// Figures of the window since construction.
struct TrackWindowStats {
  long steps = 0;              ///< Newmark steps
  int shifts = 0;              ///< moves of the window
  int rebuilds = 0;            ///< moves that built new matrices and factors (the others reused them)
  double last_shift_s = 0.0;   ///< wall time of the last move, s
  double total_shift_s = 0.0;  ///< wall time of all moves, s
};

class TrackWindow final : public FeTrack {
 public:
  /// Builds the first window on the line around the vehicle whose last and first wheels are at arc lengths
  /// s_rear <= s_front (m); w = 0. Throws std::runtime_error (rail::core::SceneError for the line's data)
  /// on non-physical settings, e.g. a window shorter than vehicle_length + behind + ahead + shift (the
  /// message names line.source and states the minimum length). Allocates (set-up).
  TrackWindow(TrackLine line, const TrackWindowSettings& settings, double s_rear, double s_front);
  ~TrackWindow();
  TrackWindow(const TrackWindow&) = delete;
  TrackWindow& operator=(const TrackWindow&) = delete;

  /// Keeps [s_rear - behind, s_front + ahead] (m) inside the window: moves it (forward or backward, by
  /// whole shift distances, never beyond the line's ends) when that range leaves it. Returns true when it
  /// moved; then mesh(), model(), the state's DOF numbering and the rail element frames are those of the
  /// new window (loads must be built on mesh() after this call). No allocation unless it moves; a move
  /// builds a model and may throw what building throws (std::bad_alloc, a factorisation failure).
  bool follow(double s_rear, double s_front) override;
  /// True when follow(s_rear, s_front) would not move the window (nothing changes). No allocation.
  bool holds(double s_rear, double s_front) const override;
  /// The clock of the Newmark integrators of this window and of the windows built at later moves.
  void setCostClock(rail::core::CostClock* cost) override;

  /// One Newmark step t -> t + dt of w with the external loads (built on mesh(), at t + dt) and the loads of
  /// the window's hanging sleepers (hanging()); then railDeformation() holds d_g + w and w' of the new state.
  /// No allocation, no exception.
  void step(const NodalLoads& loads) noexcept;
  /// The hanging sleepers of the current window (their loads relative to staticState()), or nullptr when it
  /// has none. Changes at a move. A caller stepping through integrator() adds their loads itself.
  const HangingSupports* hanging() const override;

  /// For a coupling that splits the step (e.g. a semi-implicit contact correcting the solved displacement
  /// before the step completes): the current window's integrator over w and the state it advances. The
  /// caller advances state() with it and then calls finishStep(). Both change at a move.
  NewmarkIntegrator& integrator() override;
  NewmarkState& mutableState() override { return state_; }
  /// After a step done through integrator(): counts the step (the rail arrays are filled when
  /// railDeformation() is next read). No allocation.
  void finishStep() noexcept override;

  /// Sets w to the static solution K w = f_c (w' = w'' = 0) under loads built on mesh(): a start at
  /// static equilibrium under the initial wheel loads. Factorises K (set-up; allocates).
  void setStaticState(const NodalLoads& loads);

  /// Window range on the centre line (first and last sleeper), m.
  double sBegin() const;
  double sEnd() const;
  /// True when [s_min, s_max] (m) lies on the window's rails.
  bool covers(double s_min, double s_max) const override { return s_min >= sBegin() && s_max <= sEnd(); }
  /// Index (from the line's first sleeper) of the window's first sleeper, and the number of sleeper bays.
  int firstSleeper() const;
  int bays() const { return window_bays_; }
  /// Sleeper bays of one move, and the minimum window length for the settings (m, whole bays).
  int shiftBays() const { return shift_bays_; }
  double minimumLength() const { return min_length_; }

  /// The current window's FE model and mesh (DOF numbering of state()); changes at a move.
  const TrackModel& model() const;
  const TrackMesh& mesh() const override { return model().mesh; }
  /// Dynamic part w (m, rad; m/s, ...) over the current window's free DOFs; t is the time since set-up.
  const NewmarkState& state() const override { return state_; }
  /// Self-weight static state d_g over the current window's free DOFs (zero when include_gravity is off);
  /// with hanging sleepers that of the piecewise-linear track.
  const Eigen::VectorXd& staticState() const;
  const Eigen::VectorXd* selfWeightState() const override { return &staticState(); }
  /// The rails for the contact search over the current window: nodal d_g + w and w' (world axes). The
  /// object stays the same across moves (its layout is rebuilt in place at a move).
  const rail::contact::BeamRailDeformation& railDeformation() const {
    if (!rails_current_) fillRails();
    return *deformation_;
  }
  /// The line's geometry (the whole line) and the track data (scene applied; its absorbing_ends flag is
  /// off because the window places its end dashpots itself).
  const rail::contact::TrackGeometry& geometry() const override { return geometry_; }
  const TrackData& data() const override { return data_; }
  double trackStep() const override { return track_step_; }
  const TrackWindowSettings& settings() const { return settings_; }
  const TrackWindowStats& stats() const { return stats_; }

  /// Mechanical energy of w, 1/2 w'^T M w' + 1/2 w^T K w (J), over the current window. No allocation.
  double dynamicEnergy() const;
  /// The same split into kinetic 1/2 w'^T M w' and potential 1/2 w^T K w (J). No allocation.
  void dynamicEnergy(double& kinetic, double& potential) const;
  void energy(double& kinetic, double& potential) const override { dynamicEnergy(kinetic, potential); }

  /// Adds a rail deflection section at arc length s (m) on the line (set-up only); returns its index. Its
  /// self-weight static value is solved once on a line piece of 2 * static_half_length around s.
  /// Throws std::runtime_error when s is off the line's meshable range.
  int addSection(double s, double static_half_length);
  int addSection(double s) override { return addSection(s, 10.0); }
  int sectionCount() const override { return static_cast<int>(sections_.size()); }
  /// Displacement (m) and small rotation (rad) of both rails' centre lines at section i, track-frame
  /// components (x along, y left, z up): the section's static value (if include_gravity) + w, where w is
  /// interpolated in the window, taken from the condensed end's static shapes beyond a condensed end
  /// (within boundary_length), and 0 farther away. No allocation.
  void sectionDeflection(int i, RailSectionDeflection& out) const override;
  /// The same without the static value (w only).
  void sectionDynamicDeflection(int i, RailSectionDeflection& out) const;

 private:
  struct Window;
  /// Track beyond an end statically condensed onto the end plane's 8 nodes (6 sleeper nodes right to left,
  /// then the left and right rail node; 6 DOFs each), track-frame axes.
  struct CondensedEnd {
    Eigen::MatrixXd K, C, M;  ///< 48 x 48
    Eigen::MatrixXd G;        ///< 48 x 3: condensed self-weight load per unit gravity along track x, y, z
    TrackMesh piece;          ///< the condensed piece (straight, track axes), for sections beyond the end
    std::vector<int> pos;     ///< piece free DOF -> row of X
    Eigen::MatrixXd X;        ///< piece DOFs (rows by pos) per end-plane DOF: the static shapes [I; Phi]
  };
  static CondensedEnd condenseEnd(const TrackData& data, int bays, bool front);
  void addCondensedEnd(Window& w, bool front) const;
  struct Section {
    double arc_length = 0.0;  // s of the section [m]
    bool inside = false;      // on the current window's rails
    RailProbes rail;
    // Beyond a condensed window end (within boundary_length): end-plane DOFs and the maps from their
    // values to the section's track-frame displacement / rotation through the static shapes.
    bool beyond = false;
    std::array<int, 48> plane_dofs;
    std::array<Eigen::Matrix<double, 3, 48>, 2> Q_u, Q_theta;
    RailSectionDeflection static_value;  // self-weight static state at s
  };

  std::unique_ptr<Window> buildWindow(int first_sleeper) const;
  void moveTo(int first_sleeper);
  void extrapolateEntering(const std::vector<char>& carried, NewmarkState& st) const;
  void setRails();
  void fillRails() const noexcept;
  void placeSections();
  void sizeHangingLoads();  // hanging_loads_ capacity for the current window (set-up, moves)
  void placeSection(Section& sec) const;

  TrackWindowSettings settings_;
  rail::contact::TrackGeometry geometry_;
  TrackData data_;                                        // scene applied, absorbing ends off (the window adds its own)
  Eigen::Vector3d g_in_world_ = Eigen::Vector3d::Zero();  // gravity, m/s^2
  bool line_ends_absorb_ = false;
  Vector6d c_end_;                         // window-end dashpots (rail local frame)
  std::array<CondensedEnd, 2> condensed_;  // [0] rear end (line behind), [1] front end (line ahead)
  double seat_below_centre_ = 0.0;
  double track_step_ = 0.0;
  double s_line_ = 0.0;  // arc length of the line's first sleeper, m
  int line_bays_ = 0;    // sleeper bays of the whole line
  int window_bays_ = 0;
  int shift_bays_ = 0;
  double min_length_ = 0.0;
  std::unique_ptr<Window> window_;
  NewmarkState state_;                         // w, w', w''
  mutable Eigen::VectorXd energy_scratch_;     // dynamicEnergy(): M w', K w
  std::array<std::vector<int>, 2> rail_dofs_;  // per rail: free DOF of (node k, dof j) at 6 k + j
  std::unique_ptr<rail::contact::BeamRailDeformation> deformation_;
  mutable bool rails_current_ = false;  // deformation_ holds d_g + w of the current state
  std::vector<Section> sections_;
  TrackWindowStats stats_;
  NodalLoads hanging_loads_{0};  // step(): the hanging sleepers' loads
};

/// Distance (m) from the first to the last load of a moving-load set (largest minus smallest offset).
double movingLoadsLength(const rail::core::MovingLoads& loads);

/// The rails of `mesh` as the contact search sees them: one BeamRailDeformation element per FE rail beam
/// and, per rail, the free DOF of (rail node k, dof j) at 6 k + j. An existing deformation object is kept
/// and its layout rebuilt in place (set-up and window moves; allocates). Shared by TrackWindow and
/// CosimTrack.
void buildRailLayout(const TrackMesh& mesh, std::array<std::vector<int>, 2>& rail_dofs,
                     std::unique_ptr<rail::contact::BeamRailDeformation>& deformation);

/// The rails' nodal arrays from a state (d, v) laid out by buildRailLayout: displacements d + dt v (plus
/// d_static when not null: a window's self-weight state), velocities v; a node without a free DOF stays at
/// 0. dt = 0 gives the state itself, dt = h the prediction of the next step's contact geometry. No allocation.
void fillRailArrays(const std::array<std::vector<int>, 2>& rail_dofs, const Eigen::VectorXd& d,
                    const Eigen::VectorXd& v, const Eigen::VectorXd* d_static, double dt,
                    rail::contact::BeamRailDeformation& deformation) noexcept;

}  // namespace track
}  // namespace rail
