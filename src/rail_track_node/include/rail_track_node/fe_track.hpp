// The integrated FE track of a co-simulation behind one interface: the full-length track of the scene
// (FullLengthTrack, below) or the moving window (TrackWindow, track_window.hpp). The caller steps it
// through integrator() and mutableState() (a coupling that corrects the solved displacement before the step
// completes), then calls finishStep(). The displacement of the track is d = d_s + x with x the integrated
// state(): d_s is the window's self-weight state (selfWeightState()); the full-length track integrates the
// total displacement (d_s = 0, selfWeightState() null). ROS-free.
#pragma once

#include <Eigen/Core>

#include <memory>
#include <vector>

#include <rail_contact/track_geometry.hpp>
#include <rail_core/cost_profile.hpp>
#include <rail_core/scene.hpp>

#include "rail_track_node/hanging_support.hpp"
#include "rail_track_node/newmark.hpp"
#include "rail_track_node/rail_probe.hpp"
#include "rail_track_node/scene_track.hpp"
#include "rail_track_node/sparse_cholesky.hpp"
#include "rail_track_node/track_data.hpp"
#include "rail_track_node/track_mesh.hpp"

namespace rail {
namespace track {

class FeTrack {
 public:
  virtual ~FeTrack() = default;

  /// The line's geometry and the track data (scene applied).
  virtual const rail::contact::TrackGeometry& geometry() const = 0;
  virtual const TrackData& data() const = 0;
  /// The integrated mesh (DOF numbering of state(); a window's changes at a move).
  virtual const TrackMesh& mesh() const = 0;
  /// The Newmark integrator of the integrated mesh and the state x it advances.
  virtual NewmarkIntegrator& integrator() = 0;
  virtual const NewmarkState& state() const = 0;
  virtual NewmarkState& mutableState() = 0;
  /// d_s over the free DOFs of mesh() (the total displacement is d_s + state().d), or null when the state is
  /// the total displacement.
  virtual const Eigen::VectorXd* selfWeightState() const = 0;
  /// The hanging sleepers of the integrated mesh (their loads relative to selfWeightState()), or null.
  virtual const HangingSupports* hanging() const = 0;
  virtual double trackStep() const = 0;
  /// The clock of the Newmark integrator(s) (a window's later ones too); null: none.
  virtual void setCostClock(rail::core::CostClock* cost) = 0;

  /// Keeping the loads from s_rear to s_front (m) on the integrated mesh: holds() says whether follow()
  /// would leave everything as it is; follow() moves the mesh if needed (true when it moved: mesh, DOF
  /// numbering and state changed; allocates) and covers() whether they then lie on its rails. The
  /// full-length track never moves.
  virtual bool holds(double s_rear, double s_front) const = 0;
  virtual bool follow(double s_rear, double s_front) = 0;
  virtual bool covers(double s_min, double s_max) const = 0;
  /// After a step done through integrator(). No allocation.
  virtual void finishStep() noexcept = 0;

  /// Rail deflection sections (set-up; throws std::runtime_error when s is not on the meshable rails) and
  /// their displacement and rotation from the current state (total displacement). No allocation.
  virtual int addSection(double s) = 0;
  virtual int sectionCount() const = 0;
  virtual void sectionDeflection(int i, RailSectionDeflection& out) const = 0;
  /// Kinetic 1/2 x'^T M x' and potential 1/2 (d - d_g)^T K (d - d_g) energy (J) relative to the self-weight
  /// equilibrium d_g. No allocation.
  virtual void energy(double& kinetic, double& potential) const = 0;
};

/// What the full-length track takes besides its line (constant after building).
struct FullLengthTrackSettings {
  double track_step = 0.0;      ///< Newmark step h, s (trackStepRule)
  bool include_gravity = true;  ///< self-weight f_g in every step and in the initial state
  rail::core::CostClock* cost = nullptr;
  CholeskyLayout factor_layout = CholeskyLayout::kSimplicial;
};

/// The line's whole FE track (buildSceneTrack) integrated by Newmark from its static equilibrium under its
/// own weight (with hanging sleepers: that of the piecewise-linear track).
class FullLengthTrack final : public FeTrack {
 public:
  /// Throws rail::core::SceneError on the line's data, std::runtime_error on settings. Allocates (set-up).
  FullLengthTrack(TrackLine line, const FullLengthTrackSettings& settings);

  const SceneTrack& sceneTrack() const { return track_; }
  /// A section's deflection for any displacement vector d over the free DOFs (e.g. a static solution).
  void sectionDeflection(int i, const Eigen::VectorXd& d, RailSectionDeflection& out) const;

  const rail::contact::TrackGeometry& geometry() const override { return track_.geometry; }
  const TrackData& data() const override { return track_.model.data; }
  const TrackMesh& mesh() const override { return track_.model.mesh; }
  NewmarkIntegrator& integrator() override { return *integrator_; }
  const NewmarkState& state() const override { return state_; }
  NewmarkState& mutableState() override { return state_; }
  const Eigen::VectorXd* selfWeightState() const override { return nullptr; }
  const HangingSupports* hanging() const override { return hanging_.get(); }
  double trackStep() const override { return integrator_->dt(); }
  void setCostClock(rail::core::CostClock* cost) override { integrator_->setCostClock(cost); }
  bool holds(double, double) const override { return true; }
  bool follow(double, double) override { return false; }
  bool covers(double, double) const override { return true; }
  void finishStep() noexcept override {}
  int addSection(double s) override;
  int sectionCount() const override { return static_cast<int>(sections_.size()); }
  void sectionDeflection(int i, RailSectionDeflection& out) const override;
  void energy(double& kinetic, double& potential) const override;

 private:
  struct Section {
    double arc_length;  // s of the section [m]
    RailProbes rail;
  };
  SceneTrack track_;
  std::unique_ptr<NewmarkIntegrator> integrator_;
  NewmarkState state_;
  std::unique_ptr<HangingSupports> hanging_;  // null without hanging sleepers
  Eigen::VectorXd d_static_;                  // self-weight equilibrium (the zero of energy())
  mutable Eigen::VectorXd energy_scratch_, energy_dd_;
  std::vector<Section> sections_;
};

}  // namespace track
}  // namespace rail
