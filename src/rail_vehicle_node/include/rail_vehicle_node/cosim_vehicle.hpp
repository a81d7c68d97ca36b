// The vehicle side of the co-simulation (paper section 5.3): the vehicle of VehicleSimulator (same data
// file, placement and settling on the rigid contact) whose wheel-centre wrenches come from the track
// through a rail_core::coupling::VehicleCoupling over any FrameTransport.
//
// Loop (the caller owns it):
//   CosimVehicle v(scene, transport);   // or CosimVehicle v(scene); ... v.connect(transport);
//   v.Start();                       // step 0: initial wheel states at t = 0, wrenches of step 0
//   while (v.Step() == RunStatus::kRunning) {}   // integrate to t_{k+1}, interpolate, exchange
//   v.Close();
// Inside every right-hand side the wrench of each wheel is the coupling's linear extrapolation of the last
// two received frames at the right-hand side's time (VehicleCoupling::wrenchAt). CVODE's step is capped
// at solver.vehicle_max_step <= solver.track_step = h. World frame, SI units.
#pragma once

#include <rail_core/coupling/protocol.hpp>
#include <rail_core/coupling/transport.hpp>
#include <rail_core/scene.hpp>

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "rail_vehicle_node/vehicle_simulator.hpp"

namespace rail::vehicle {

// What the co-simulated vehicle is built from, resolved once from a scene (resolveCosimVehicle).
struct CosimVehicleSetup {
  VehicleSetup vehicle;
  core::coupling::CouplingConfig coupling;  // track step, exchange timeout, scene hash, wheel count
};

// Resolves a co-simulation scene's vehicle side: effects.track_model rigid_fe or flexible with
// 0 < solver.vehicle_max_step <= solver.track_step. Throws std::runtime_error naming the scene file and the
// field for a scene that does not qualify (and whatever resolveVehicle throws).
CosimVehicleSetup resolveCosimVehicle(const core::Scene& scene);

class CosimVehicle {
 public:
  // Builds the vehicle; the transport is bound later with connect(), so that a node can build first and
  // send the handshake what the model says (its wheel span). Throws std::runtime_error when the model's
  // wheels are not the frames' (and whatever VehicleSimulator throws).
  explicit CosimVehicle(CosimVehicleSetup setup, const SimulatorSettings& settings = {});
  // Builds and connects: transport is the vehicle end and must outlive this object.
  CosimVehicle(CosimVehicleSetup setup, core::coupling::FrameTransport& transport,
               const SimulatorSettings& settings = {});
  ~CosimVehicle();
  CosimVehicle(const CosimVehicle&) = delete;
  CosimVehicle& operator=(const CosimVehicle&) = delete;

  // Binds the transport (the vehicle end, must outlive this object); once, before start(). Until then the
  // wheels carry no wrench, as before the first exchange. Throws std::logic_error when called twice.
  void connect(core::coupling::FrameTransport& transport);
  bool connected() const { return coupling_ != nullptr; }

  // Replaces the state before Start() (e.g. an initial lateral offset); throws after Start().
  void resetState(const Eigen::VectorXd& y);

  // Step 0 at t = 0: sends the initial wheel states, receives the wrenches of step 0. kRunning on success,
  // kIntegratorFailed with message() naming the exchange failure (or a missing connect()) otherwise.
  RunStatus start();
  // One track step: integrates to t_{k} = k h (the next exchange), interpolates the wheel states there
  // (dense output), exchanges them for the wrenches of step k. Returns kRunning, kFinished once
  // solver.end is reached (that step is still exchanged), or why the run stopped (message()); an
  // exchange failure gives kIntegratorFailed and exchangeStatus() says which. No exception, no
  // allocation on the normal path. A step that reaches output_time (or ends the run) completes the
  // simulator's outputs before the exchange, with the wrenches it integrated with; the other steps
  // evaluate only the positions their checks read (default: every step completes them).
  RunStatus step(double output_time = -std::numeric_limits<double>::infinity());
  // Tells the track the run is over (its next receive() returns kPeerClosed).
  void close();

  const std::string& message() const { return message_; }
  core::coupling::Status exchangeStatus() const { return exchange_status_; }
  double time() const { return sim_->time(); }
  std::uint64_t stepsExchanged() const { return coupling_ ? coupling_->nextStep() : 0; }  // exchanges done so far
  double trackStep() const { return config_.track_step; }                                 // h [s]
  // Largest internal CVODE step seen after any advanceTo (last step of each call) [s].
  double maxInternalStep() const { return max_internal_step_; }

  // The wheel states sent last (stamped by the coupling).
  const core::coupling::WheelStateFrame& sentStates() const { return coupling_->states(); }
  const core::coupling::VehicleCoupling& coupling() const { return *coupling_; }
  // The vehicle: outputs (wheelsets(), wheels(), bodies()), model, counters. Its wheels() carry the
  // extrapolated wrenches at time().
  VehicleSimulator& simulator() { return *sim_; }
  const VehicleSimulator& simulator() const { return *sim_; }

  // Wheel-centre states of state vector y into frame.wheels[0 .. n_wheels): load point position and
  // velocity, wheelset orientation and angular velocity (world), arc length of the centre's projection
  // (warm-started from the previous call). No allocation.
  void fillWheelStates(const Eigen::Ref<const Eigen::VectorXd>& y, core::coupling::WheelStateFrame& frame);

 private:
  class CouplingSource;
  RunStatus exchange();

  core::coupling::CouplingConfig config_;
  std::unique_ptr<core::coupling::VehicleCoupling> coupling_;  // null until connect()
  std::unique_ptr<CouplingSource> source_;
  std::unique_ptr<VehicleSimulator> sim_;
  std::unique_ptr<VehicleData> data_;  // kinematics of the interpolated state
  Eigen::VectorXd y_interp_;           // state at the exchange time
  std::vector<double> wheel_s_;        // arc-length warm starts per wheel [m]
  double max_internal_step_ = 0.0;
  bool started_ = false;
  core::coupling::Status exchange_status_ = core::coupling::Status::kOk;
  std::string message_;
};

}  // namespace rail::vehicle
