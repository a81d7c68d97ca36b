#include "rail_vehicle_node/cosim_vehicle.hpp"

#include <rail_contact/track_geometry.hpp>
#include <rail_core/scene_loader.hpp>

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "rail_vehicle_node/multibody_dynamics.hpp"

namespace rail::vehicle {

namespace cc = rail::core::coupling;

// The coupling's extrapolated wrench as the simulator's wheel-wrench source; zero until connected, as the
// coupling gives before its first exchange.
class CosimVehicle::CouplingSource : public WheelWrenchSource {
 public:
  void bind(const cc::VehicleCoupling& coupling) { coupling_ = &coupling; }
  void wheelWrenchAt(double t, int wheel, Vector3& force_in_world, Vector3& moment_in_world) const noexcept override {
    if (coupling_ == nullptr) {
      force_in_world.setZero();
      moment_in_world.setZero();
      return;
    }
    coupling_->wrenchAt(t, wheel, force_in_world, moment_in_world);
  }

 private:
  const cc::VehicleCoupling* coupling_ = nullptr;
};

CosimVehicleSetup resolveCosimVehicle(const core::Scene& scene) {
  std::ostringstream os;
  if (!scene.has_vehicle) {
    os << scene.file << ": the scene has no vehicle";
  } else if (scene.effects.track_model == core::TrackModel::kRigid) {
    os << scene.file << ": effects.track_model: rigid runs the vehicle alone; the co-simulated vehicle needs "
       << "rigid_fe or flexible";
  } else if (const std::string why = core::trackStepRule(scene.solver.track_step); !why.empty()) {
    os << scene.file << ": solver.track_step: " << why;
  } else if (const std::string why_max =
                 core::vehicleMaxStepRule(scene.solver.vehicle_max_step, scene.solver.track_step);
             !why_max.empty()) {
    os << scene.file << ": solver.vehicle_max_step: " << why_max;
  } else {
    return CosimVehicleSetup{resolveVehicle(scene), cc::couplingConfig(scene)};
  }
  throw std::runtime_error(os.str());
}

CosimVehicle::CosimVehicle(CosimVehicleSetup setup, const SimulatorSettings& settings) : config_(setup.coupling) {
  source_ = std::make_unique<CouplingSource>();
  SimulatorSettings s = settings;
  s.wheel_wrench_source = source_.get();
  const std::string source = setup.vehicle.source;
  sim_ = std::make_unique<VehicleSimulator>(std::move(setup.vehicle), s);
  const int n_wheels = sim_->contactModel().nWheels();
  if (n_wheels != config_.wheel_count) {
    std::ostringstream os;
    os << source << ": the vehicle has " << n_wheels << " wheels, the scene's frames carry " << config_.wheel_count;
    throw std::runtime_error(os.str());
  }
  data_ = std::make_unique<VehicleData>(sim_->model());
  y_interp_ = Eigen::VectorXd::Zero(sim_->model().stateSize());
  wheel_s_.assign(static_cast<std::size_t>(n_wheels), 0.0);
  for (std::size_t i = 0; i < wheel_s_.size(); ++i) wheel_s_[i] = sim_->wheels()[i].arc_length;
}

CosimVehicle::CosimVehicle(CosimVehicleSetup setup, cc::FrameTransport& transport, const SimulatorSettings& settings)
    : CosimVehicle(std::move(setup), settings) {
  connect(transport);
}

CosimVehicle::~CosimVehicle() = default;

void CosimVehicle::connect(cc::FrameTransport& transport) {
  if (coupling_) throw std::logic_error("cosim vehicle: connect() called twice");
  coupling_ = std::make_unique<cc::VehicleCoupling>(config_, transport);
  source_->bind(*coupling_);
}

void CosimVehicle::resetState(const Eigen::VectorXd& y) {
  if (started_) throw std::runtime_error("cosim vehicle: ResetState after Start()");
  sim_->resetState(y);
  for (std::size_t i = 0; i < wheel_s_.size(); ++i) wheel_s_[i] = sim_->wheels()[i].arc_length;
}

void CosimVehicle::fillWheelStates(const Eigen::Ref<const Eigen::VectorXd>& y, cc::WheelStateFrame& frame) {
  const VehicleModel& model = sim_->model();
  computeKinematics(model, y, *data_);
  const auto& wheels = sim_->contactModel().wheels();
  contact::TrackPoint tp;
  for (std::size_t i = 0; i < wheels.size(); ++i) {
    const WheelDefinition& wd = wheels[i];
    const BodyKinematics& b = data_->bodies[static_cast<std::size_t>(wd.body)];
    // The frames' wheel centre is the contact's wheel centre: the axle point in the taping-line plane
    // (CosimTrack evaluates the contact about it and returns the moment about it).
    const Vector3 arm = b.A * wd.s_taping_in_body;
    cc::WheelState& w = frame.wheels[i];
    w.id = static_cast<std::uint32_t>(i);
    w.p_wheel_in_world = b.r + arm;
    w.R_wheelset_to_world = b.A;
    w.v_wheel_in_world = b.r_dot + b.omega_world.cross(arm);
    w.omega_wheelset_in_world = b.omega_world;
    wheel_s_[i] = projectOnTrack(sim_->track(), w.p_wheel_in_world, wheel_s_[i], tp);
    w.arc_length = wheel_s_[i];
  }
}

RunStatus CosimVehicle::exchange() {
  const cc::Result r = coupling_->exchange();
  exchange_status_ = r.status;
  if (!r.ok()) {
    message_ = r.message;
    return RunStatus::kIntegratorFailed;
  }
  return RunStatus::kRunning;
}

RunStatus CosimVehicle::start() {
  if (started_) {
    message_ = "cosim vehicle: Start() called twice";
    return RunStatus::kIntegratorFailed;
  }
  if (!coupling_) {
    message_ = "cosim vehicle: Start() before connect()";
    return RunStatus::kIntegratorFailed;
  }
  started_ = true;
  fillWheelStates(sim_->state(), coupling_->states());
  const RunStatus s = exchange();
  if (s == RunStatus::kRunning) sim_->updateOutputs();  // outputs with the step-0 wrenches
  return s;
}

RunStatus CosimVehicle::step(double output_time) {
  if (!started_) {
    message_ = "cosim vehicle: Step() before Start()";
    return RunStatus::kIntegratorFailed;
  }
  const double t_next = coupling_->nextExchangeTime();
  // CV_NORMAL: CVODE may take its last internal step beyond t_next (by less than one step <= h) using the
  // extrapolation of W_{k-2}, W_{k-1}; the state at t_next is interpolated from that step, and the part
  // beyond is kept (see doc/cosim_vehicle.md).
  const RunStatus run = sim_->advanceTo(t_next);
  double t0 = 0.0, t1 = 0.0;
  sim_->lastStepInterval(t0, t1);
  max_internal_step_ = std::max(max_internal_step_, std::max(t1 - t0, sim_->counters().last_step));
  if (run != RunStatus::kRunning && run != RunStatus::kFinished) {
    message_ = sim_->message();
    return run;
  }
  // The integrator's time is t_next (CV_NORMAL returns the interpolated state at the output time); the dense
  // output at t_next is that same state, and stays valid after a projection re-initialised there.
  if (run != RunStatus::kRunning || t_next + 1e-9 * config_.track_step >= output_time) sim_->completeOutputs();
  sim_->interpolateAt(t_next, y_interp_);
  fillWheelStates(y_interp_, coupling_->states());
  const RunStatus ex = exchange();
  if (ex != RunStatus::kRunning) return ex;
  return run;
}

void CosimVehicle::close() {
  if (coupling_) coupling_->close();
}

}  // namespace rail::vehicle
