// The vehicle running alone on the rigid track (effects.track_model: rigid): paper sections 2 and 4.2.
//
// Built once from a resolved scene (VehicleSetup): the vehicle data file (VehicleModel), the rigid track geometry, the
// wheel and rail profiles and the wheel-rail contact of every wheel evaluated inside each right-hand side
// (WheelRailContactElement). The vehicle is placed on the track (placeOnTrack below), lowered onto the
// rails until the contact carries its weight (static vertical solve), and handed to a VehicleIntegrator
// (CVODE) that the caller advances with advanceTo. Outputs (wheel states, contact points, wheel-centre
// wrenches, wheelset kinematics relative to the track, body poses) are computed on demand by
// updateOutputs into preallocated buffers.
//
// Frames: world x forward at the track start, y left, z up (rail_contact/track_geometry.hpp); the vehicle
// data file's reference pose is on straight level track, x forward, y left, z up from the rail top.
#pragma once

#include <rail_contact/profile.hpp>
#include <rail_contact/track_geometry.hpp>
#include <rail_contact/wheel_contact.hpp>
#include <rail_core/geometry_builder.hpp>
#include <rail_core/scene.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rail_vehicle_node/vehicle_data.hpp"
#include "rail_vehicle_node/vehicle_integrator.hpp"
#include "rail_vehicle_node/vehicle_model.hpp"
#include "rail_vehicle_node/wheel_rail_contact.hpp"

namespace rail::vehicle {

// Source of the wheel-centre wrenches when they come from outside the vehicle (the co-simulation,
// cosim_vehicle.hpp) instead of the built-in rigid contact. Called inside every right-hand side.
class WheelWrenchSource {
 public:
  virtual ~WheelWrenchSource() = default;
  // Wrench on wheel `wheel` (2 * wheelset + side) at time t [s]: force [N] and moment about the wheel
  // centre (the axle point in the taping-line plane, the contact's wheel centre) [N m], both in the world
  // frame. No allocation, no exception.
  virtual void wheelWrenchAt(double t, int wheel, Vector3& force_in_world, Vector3& moment_in_world) const noexcept = 0;
};

// rail_contact's defaults, whose wheel surfaces continue 5 mm across the tread/flange split
// (DetectionOptions::split_overlap): a flange-root contact crossing the split stays a converged point.
// Without it the root contact of a flanging wheel falls back to the search's grid estimate and back every
// few evaluations, and the integrator's step collapses to ~1e-7 s (doc/simulator.md).
contact::WheelContactOptions defaultVehicleContactOptions();

// Revision of the vehicle-alone results: raised by every change that moves them (a cached reference run,
// such as bench_vehicle_accuracy's, carries it and is refused under another). 2: warm starts held at
// accepted steps; 3: the contact search seeds yawed flange contacts and end samples; 4: a surface takes a
// penetrating point past its end (a second contact beside its neighbour's); 5: each surface carries a
// second contact separated from the wheel's others (WheelContactOptions::second_contacts).
constexpr int kResultsRevision = 5;

// What the scene does not say (constant after building).
struct SimulatorSettings {
  // Contact data the scene has no key for: materials, Polach parameters, detection settings. The scene's
  // effects (flange_contact, spin_creepage, creep_law) and contact section (friction mu0, restitution e,
  // impact-velocity floor) override those fields.
  contact::WheelContactOptions contact = defaultVehicleContactOptions();
  // Derailment: a wheel centre more than this above its settled height relative to the track plane [m];
  // 0 = the wheel profile's flange height.
  double derailment_lift = 0.0;
  // Derailment: a wheelset centre farther than this from the track centre line, laterally [m].
  double derailment_lateral = 0.05;
  // Co-simulation: when set, the built-in rigid contact still places and settles the vehicle, then it is
  // switched off and every right-hand side takes the wheel-centre wrenches from this source instead
  // (contacts() then keeps the settling evaluation). Must outlive the simulator.
  const WheelWrenchSource* wheel_wrench_source = nullptr;
  // BDF's Jacobian and linear solver (vehicle_integrator.hpp).
  JacobianKind jacobian = JacobianKind::kColoured;
  LinearSolverKind linear_solver = LinearSolverKind::kSparseKlu;
  bool direct_linear_system = true;  // IntegratorSettings::direct_linear_system
  // Carry BDF's Jacobian along with the wheelsets' spin between evaluations (IntegratorSettings::spin_bodies),
  // for every wheelset whose inertia is symmetric about its axle; false: CVODE's own Jacobian policy.
  bool carry_jacobian_with_spin = true;
  // A wheel surface far from its rail skips its search inside the integration (rail_contact
  // DetectionWork::skip_far_searches; its force is zero either way); the output evaluations always search,
  // so the published gaps are exact. false: every evaluation searches.
  bool skip_far_searches = true;
  // The contacts' impact memories (eq. 9's impact velocity, rail_contact ImpactMemory) take accepted steps
  // only (WheelContactWork::hold_impact_memory, IntegratorSettings::accept_steps), not every trial state of
  // BDF's Newton or of a rejected step; false: every evaluation updates them (the co-simulation's vehicle
  // has no contact of its own and ignores this).
  bool impact_memory_at_accepted_steps = true;
  // The contact detections start Newton from the contact point of the last accepted step (rail_contact
  // DetectionWork::hold_warm_start), not from the last trial evaluation's, which made the contact point and
  // so the run depend on where the integrator had evaluated; false: from the last evaluation (the former rule).
  bool warm_starts_at_accepted_steps = true;
  // Optional cost clock (must outlive the simulator): from the end of the build on, right-hand sides
  // (vehicle_rhs / vehicle_jacobian, including the one of each updateOutputs), the contact evaluations in
  // them (contact_detection / contact_forces, flange searches, spin evaluations) and floor accelerations.
  // null = no timing.
  core::CostClock* cost = nullptr;
};

// One wheel centre (rail_msgs/WheelState), world frame.
struct WheelOutput {
  int wheel_id = 0;                           // 2 * wheelset + side
  int wheelset = 0;                           // 0 = leading
  int side = 0;                               // 0 left, 1 right
  double arc_length = 0.0;                    // s of the wheel centre's projection on the track [m]
  Vector3 p_in_world = Vector3::Zero();       // wheel centre (the load point) [m]
  Vector4 orientation = Vector4(1, 0, 0, 0);  // R_wheelset_to_world as Euler parameters (w, x, y, z)
  Vector3 v_in_world = Vector3::Zero();       // [m/s]
  Vector3 omega_in_world = Vector3::Zero();   // wheelset angular velocity, spin included [rad/s]
  Vector3 force_in_world = Vector3::Zero();   // contact wrench on the wheel at its centre [N]
  Vector3 moment_in_world = Vector3::Zero();  // about the wheel centre [N m]
};

// One wheelset relative to the track frame at its arc length (rail_msgs/WheelsetTrackState).
struct WheelsetTrackOutput {
  int wheelset = 0;
  double arc_length = 0.0;       // s of the wheelset centre [m]
  double lateral = 0.0;          // along n (left) from the centre line [m]
  double vertical = 0.0;         // along b from the nominal height (nominal rolling radius above the rails) [m]
  double angle_of_attack = 0.0;  // yaw of the axle relative to the track frame [rad], > 0 turning left
  double roll = 0.0;             // roll relative to the canted track plane [rad], > 0 left side up
  double spin = 0.0;             // rate about the axle [rad/s]
};

// What an accelerometer fixed at a measurement point reads (rail_msgs/FloorAccelerations): the specific
// force a - g in the point's body frame (x forward, y left, z up) [m/s^2].
struct MeasurementOutput {
  Vector3 specific_force_in_body = Vector3::Zero();
};

// Mechanical energy of the vehicle (rail_msgs/Energy) [J]: kinetic (translation, rotation, spin) and
// potential (gravity from z = 0, suspension springs, bump stops; not the Hertz contact springs).
struct EnergyOutput {
  double kinetic = 0.0;
  double potential = 0.0;
};

// Pose of one body for tf.
struct BodyPose {
  std::string name;  // the data file's body name
  Vector3 p_in_world = Vector3::Zero();
  Vector4 orientation = Vector4(1, 0, 0, 0);  // body -> world, (w, x, y, z)
};

// Why a run stopped (or kRunning).
enum class RunStatus { kRunning, kFinished, kDerailed, kNonFinite, kLeftTrack, kIntegratorFailed };

// Start state of the vehicle on the track: each body's reference pose mapped through the track frame at
// its own arc length s_b = start_arc_length - (x_lead - x_b) (x_lead: the leading wheelset's reference x),
// r = c(s_b) + R_track(s_b) [0, y_b, z_b + lift], A = R_track(s_b) A_ref; velocities of a rigid motion
// along the track at `speed`: r_dot = speed t(s_b) + omega_track x (r - c(s_b)),
// omega = speed * axial(dR/ds R^T) (+ speed / rolling_radius about the axle for wheelsets).
// Throws std::runtime_error if a body falls outside the track.
Eigen::VectorXd placeOnTrack(const VehicleModel& model, const contact::TrackGeometry& track,
                             const std::vector<int>& wheelset_bodies, double start_arc_length, double speed,
                             double lift, const std::vector<double>& rolling_radius);

// Arc length of the point of the centre line closest to p (Newton from s_guess, clamped to the track);
// tp receives the centre line at that s. No allocation.
double projectOnTrack(const contact::TrackGeometry& track, const Vector3& p_in_world, double s_guess,
                      contact::TrackPoint& tp) noexcept;

// What the vehicle simulator is built from, resolved once from a scene (resolveVehicle) and constant
// afterwards: what VehicleSimulator takes instead of the Scene.
struct VehicleSetup {
  std::string source;                           // the scene file; build errors start with it
  std::string data_file;                        // vehicle.data: the vehicle data file
  int wheelsets = 0;                            // vehicle.wheelsets, as the data file must have them
  double start_arc_length = 0.0;                // leading wheelset's arc length at t = 0 [m]
  double speed = 0.0;                           // [m/s]
  double nominal_radius = 0.0;                  // [m]
  double back_to_back = 0.0;                    // wheel back-to-back distance [m]
  core::End end;                                // solver.end
  core::Solver solver;                          // the vehicle integrator's tolerances, step caps and method choice
  std::optional<contact::TrackGeometry> track;  // the rails' design geometry (+ irregularities when on)
  contact::WheelProfile wheel_profile;          // vehicle.wheel_profile
  contact::ProfileCurve rail_profile;           // the scene's rail profile
  core::SceneContact contact;                   // the scene's effects and contact section
  bool floor_acceleration_output = false;       // effects.floor_acceleration_output
  bool energy_output = false;                   // effects.energy_output
};

// Resolves the vehicle of a scene. Throws std::runtime_error (core::SceneError for scene data) naming the
// scene file when it has no vehicle, or a profile or the geometry cannot be built.
VehicleSetup resolveVehicle(const core::Scene& scene);

class VehicleSimulator {
 public:
  // Builds a model from the setup's vehicle data file.
  explicit VehicleSimulator(VehicleSetup setup, const SimulatorSettings& settings = {});
  // Builds the model with `build_model` instead (tests): it adds bodies, load points (two wheel centres per
  // wheelset body, nothing else), joints and force elements to an unfinalised model.
  VehicleSimulator(VehicleSetup setup, const std::function<void(VehicleModel&)>& build_model,
                   const SimulatorSettings& settings = {});
  ~VehicleSimulator();
  VehicleSimulator(const VehicleSimulator&) = delete;
  VehicleSimulator& operator=(const VehicleSimulator&) = delete;

  // Integrates to t (> time()); returns kRunning, kFinished once solver.end is reached, or why the run
  // stopped (message() says which wheel, where and when). No exception on the normal path.
  RunStatus advanceTo(double t);
  const std::string& message() const { return message_; }

  double time() const;
  double startTime() const { return 0.0; }
  // Leading wheelset's arc length [m] (from the last updateOutputs or advanceTo).
  double leadingArcLength() const { return leading_s_; }
  // Simulated time at which the run ends: solver.end.time, or an estimate from the arc length at speed.
  double endTimeEstimate() const;
  bool finished() const;

  // Evaluates kinematics and contact at the current state and fills the output buffers below. With external
  // wheel wrenches (co-simulation) advanceTo fills only the positions its checks read (wheels, wheelsets,
  // bodies); measurements() and energy() evaluate the derivatives they need on their first call after it,
  // or completeOutputs() does (the caller's timing then holds that evaluation).
  void updateOutputs();
  void completeOutputs() const;
  const std::vector<WheelOutput>& wheels() const { return wheel_out_; }
  const std::vector<contact::WheelContactResult>& contacts() const { return contact_data_->result; }
  const std::vector<WheelsetTrackOutput>& wheelsets() const { return wheelset_out_; }
  const std::vector<BodyPose>& bodies() const { return body_out_; }
  // One per model().measurement_points(), filled only when the scene's effects.floor_acceleration_output
  // is on (otherwise left at zero: no cost).
  const std::vector<MeasurementOutput>& measurements() const {
    completeOutputs();
    return measurement_out_;
  }
  // Filled only when the scene's effects.energy_output is on (otherwise zero: no cost).
  const EnergyOutput& energy() const {
    completeOutputs();
    return energy_out_;
  }

  // Replaces the state (e.g. a test's initial lateral offset); re-initialises the integrator.
  void resetState(const Eigen::VectorXd& y);
  Eigen::Map<const Eigen::VectorXd> state() const { return integrator_->state(); }
  // Dense output of the last internal step (VehicleIntegrator::interpolateAt / lastStepInterval).
  void interpolateAt(double t, Eigen::Ref<Eigen::VectorXd> y_out) const { integrator_->interpolateAt(t, y_out); }
  void lastStepInterval(double& t_begin, double& t_end) const { integrator_->lastStepInterval(t_begin, t_end); }
  // Whether the wheel wrenches come from SimulatorSettings::wheel_wrench_source.
  bool externalWheelWrenches() const { return external_active_; }

  const VehicleModel& model() const { return model_; }
  VehicleData& data() { return *data_; }
  const contact::TrackGeometry& track() const { return *track_; }
  const WheelRailContactModel& contactModel() const { return *contact_model_; }
  const WheelRailContactData& contactData() const { return *contact_data_; }
  const std::vector<int>& wheelsetBodies() const { return wheelset_bodies_; }
  IntegratorCounters counters() const { return integrator_->counters(); }
  IntegrationMethod method() const { return method_; }
  // The integrator's maximum step [s] (0 = none): the scene's solver.standalone_max_step when the vehicle
  // runs alone, its solver.vehicle_max_step (the track step's cap) in co-simulation.
  double maxStep() const { return max_step_; }
  // Settled lowering of the vehicle onto the rails (static vertical solve) [m], < 0 downward.
  double settleLift() const { return lift_; }
  // Total vertical load the rails carry at rest [N] and the sum of the wheel loads after settling [N].
  double staticLoad() const { return static_load_; }
  double settledWheelLoadSum() const { return settled_load_sum_; }

 private:
  void build(VehicleSetup setup, const std::function<void(VehicleModel&)>& build_model,
             const SimulatorSettings& settings);
  double sumWheelLoads(const Eigen::VectorXd& y);
  RunStatus check();
  void evaluateOutputs(bool derivatives);
  void fillPositionOutputs();

  // What the run's end needs from the setup (solver.end, the vehicle's start and speed).
  core::End end_;
  double start_arc_length_ = 0.0, speed_ = 0.0;
  SimulatorSettings settings_;
  std::unique_ptr<contact::TrackGeometry> track_;
  contact::WheelProfile wheel_profile_;
  contact::ProfileCurve rail_profile_;
  VehicleModel model_;
  std::unique_ptr<WheelRailContactModel> contact_model_;
  std::unique_ptr<WheelRailContactData> contact_data_;
  std::unique_ptr<VehicleData> data_;
  std::unique_ptr<VehicleIntegrator> integrator_;
  IntegrationMethod method_ = IntegrationMethod::kBdf;
  double max_step_ = 0.0;
  bool skip_far_searches_ = true;
  std::vector<int> wheelset_bodies_;    // body index per wheelset, leading first
  std::vector<double> rolling_radius_;  // per wheelset, at the settled centred position [m]
  std::vector<double> wheelset_s_;      // arc length per wheelset (projection warm start) [m]
  std::vector<double> wheel_s_;         // arc length per wheel centre [m]
  double lift_ = 0.0;
  double static_load_ = 0.0;
  double settled_load_sum_ = 0.0;
  double nominal_height_ = 0.0;  // nominal rolling radius [m]
  double derailment_lift_ = 0.0;
  double leading_s_ = 0.0;
  bool external_active_ = false;  // wheel wrenches from settings_.wheel_wrench_source
  std::string message_;
  Eigen::VectorXd y_scratch_;  // the state of the outputs, at t_outputs_
  mutable Eigen::VectorXd ydot_scratch_;
  double t_outputs_ = 0.0;
  mutable bool derivatives_current_ = false;  // measurement_out_ and energy_out_ are of y_scratch_
  std::vector<WheelOutput> wheel_out_;
  std::vector<WheelsetTrackOutput> wheelset_out_;
  std::vector<BodyPose> body_out_;
  mutable std::vector<MeasurementOutput> measurement_out_;
  bool measure_ = false;  // effects.floor_acceleration_output
  mutable EnergyOutput energy_out_;
  bool energy_ = false;              // effects.energy_output
  core::CostClock* cost_ = nullptr;  // settings.cost once built
};

// "bdf" / "adams" choice for solver.vehicle_method auto, given the step cap the run uses (the simulator passes its
// maxStep(), 0 for none): Adams (fixed-point, no Jacobian) at a cap of 5e-5 s or less, where the contact's fastest
// modes are resolved explicitly; BDF otherwise. Below kStiffCreepSpeed with the built-in contact BDF: the creep
// forces then act as a viscous law in the slip velocity with a time constant near 1e-5 s, stiff for Adams. With
// external wrenches (co-simulation) always Adams: the right-hand side holds the suspension only, not stiff at any
// cap the track step allows. doc/simulator.md, "Choosing the method", has the measurements behind each rule.
constexpr double kStiffCreepSpeed = 2.0;  // [m/s]
IntegrationMethod chooseMethod(const core::Solver& solver, double speed = 1e9, bool external_wrenches = false);

}  // namespace rail::vehicle
