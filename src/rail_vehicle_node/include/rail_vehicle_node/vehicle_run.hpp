// The vehicle side's run loop, alone on the rigid track (VehicleSimulator) or co-simulated (CosimVehicle):
// next() runs to the next output instant n / output.rate, or to the run's end, and says which; the node
// publishes at each kOutput. ROS-free.
//
//   VehicleRun run(core::runSettings(scene), simulator_or_cosim_vehicle, {&stop_flag, &cost});
//   while (run.next() == VehicleRun::Event::kOutput) publish(run.outputIndex());
//   switch (run.end()) ...   // exitCode(), message()
//
// Alone, every output instant is an advanceTo (a time end stops exactly there, an arc-length end when the
// leading wheelset passes it); the state where the run stopped (finished, derailed, ...) is still output.
// Co-simulated, every step is one track step h (one exchange); the output is at the exchange that reaches
// each output instant, and at the last one.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include <rail_core/cost_profile.hpp>
#include <rail_core/run_settings.hpp>

#include "rail_vehicle_node/cosim_vehicle.hpp"
#include "rail_vehicle_node/vehicle_simulator.hpp"

namespace rail::vehicle {

// "finished", "derailed", "non-finite state", ...
const char* toString(RunStatus status);
// The exit code (rail_core/exit_codes.hpp) of a run that stopped with `status`: 0 for kFinished, 7 derailed
// or off the track, 8 non-finite or integrator failure.
int exitCodeOf(RunStatus status);

struct VehicleRunOptions {
  const std::atomic<bool>* stop = nullptr;  // checked between steps: a raised flag ends the run (exit 5)
  core::CostProfile* cost = nullptr;        // when set: the integration is timed into it
};

class VehicleRun {
 public:
  enum class Event { kOutput, kEnd };
  enum class End {
    kFinished,        // solver.end reached
    kStopped,         // the stop flag was raised
    kFailed,          // the vehicle's run stopped: derailed, non-finite state, integrator failure
    kExchangeFailed,  // co-simulation: an exchange with the track failed
  };

  // The simulator, or the co-simulated vehicle, must outlive the run.
  VehicleRun(const core::RunSettings& settings, VehicleSimulator& alone, VehicleRunOptions options = {});
  VehicleRun(const core::RunSettings& settings, CosimVehicle& cosim, VehicleRunOptions options = {});

  // Runs to the next output instant (kOutput) or to the end (kEnd). After kEnd it keeps returning kEnd.
  Event next();

  std::uint64_t outputIndex() const { return output_index_; }  // of the last kOutput
  double time() const { return sim_.time(); }
  // After kEnd: how the run ended, its exit code and (kFailed, kExchangeFailed) what happened. The
  // message names the status, the time and the simulator's or the exchange's reason.
  End end() const { return end_; }
  int exitCode() const { return exit_code_; }
  const std::string& message() const { return message_; }

 private:
  Event nextAlone();
  Event nextCosim();
  Event finish(End end, int exit_code);
  Event checkFailure();
  template <class F>
  RunStatus timed(F&& f);

  VehicleSimulator& sim_;
  CosimVehicle* cosim_ = nullptr;
  VehicleRunOptions options_;
  double output_period_;
  double t_limit_;  // a time end stops exactly there
  bool started_ = false;
  bool ended_ = false;
  RunStatus status_ = RunStatus::kRunning;
  std::uint64_t next_output_ = 0;
  std::uint64_t output_index_ = 0;
  End end_ = End::kFinished;
  int exit_code_ = 0;
  std::string message_;
};

}  // namespace rail::vehicle
