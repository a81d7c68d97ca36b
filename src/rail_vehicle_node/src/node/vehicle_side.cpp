#include "vehicle_side.hpp"

#include <ros/ros.h>

#include <chrono>
#include <memory>
#include <string>

#include <rail_contact/format.hpp>
#include <rail_core/cost_profile.hpp>
#include <rail_core/coupling/timed_transport.hpp>
#include <rail_core/exit_codes.hpp>
#include <rail_core/geometry_builder.hpp>
#include <rail_core/run_settings.hpp>
#include <rail_ros/cosim_transport.hpp>
#include <rail_ros/node_scaffold.hpp>
#include <rail_ros/run_output.hpp>
#include <rail_vehicle_node/cosim_vehicle.hpp>
#include <rail_vehicle_node/vehicle_run.hpp>
#include <rail_vehicle_node/vehicle_simulator.hpp>

#include "vehicle_outputs.hpp"

namespace rail::vehicle {

using namespace rail::core;
namespace cc = rail::core::coupling;
namespace ros_glue = rail::ros_glue;

int runVehicleSide(const Scene& scene) {
  ros::NodeHandle nh, pnh("~");
  ros_glue::NodeRun node_run(ros::this_node::getName());
  const std::string& node = node_run.node();
  const bool cosim = scene.cosimulation();
  ros_glue::NodeStop& stop = node_run.stop();
  CostProfile& cost = node_run.cost();
  CostClock& clock = node_run.clock();  // the finer split, filled by the simulator (cost_profile.hpp)
  SimulatorSettings settings;
  settings.cost = &clock;
  std::unique_ptr<cc::FrameTransport> transport;
  std::unique_ptr<cc::TimedTransport> timed_transport;  // adds exchange waits to `cost`
  std::unique_ptr<CosimVehicle> cosim_vehicle;
  std::unique_ptr<VehicleSimulator> alone;
  try {
    if (cosim) {
      cosim_vehicle = std::make_unique<CosimVehicle>(resolveCosimVehicle(scene), settings);
    } else {
      alone = std::make_unique<VehicleSimulator>(resolveVehicle(scene), settings);
    }
  } catch (const std::exception& e) {
    ROS_FATAL("%s: cannot build the %svehicle: %s", node.c_str(), cosim ? "co-simulated " : "", e.what());
    return kExitBadInput;
  }
  VehicleSimulator& sim = cosim ? cosim_vehicle->simulator() : *alone;
  std::string peer;
  if (cosim) {
    const auto wait0 = std::chrono::steady_clock::now();
    const int rc = ros_glue::handshakeAsVehicle(scene, sim.model().wheelSpan(), peer);
    if (rc != kExitOk) return rc;
    // The handshake waits for the track node: not the vehicle's set-up.
    node_run.excludeFromSetUp(std::chrono::duration<double>(std::chrono::steady_clock::now() - wait0).count());
    if (const int rc = ros_glue::openTransport(scene, cc::Role::kVehicle, nh, pnh, peer, &stop.requested, transport);
        rc != kExitOk)
      return rc;
    timed_transport = std::make_unique<cc::TimedTransport>(*transport, cost);
    cosim_vehicle->connect(*timed_transport);
  }
  ROS_INFO(
      "%s: vehicle settled on the rails (lowered %.4f mm, wheel loads %.1f N of %.1f N); integrating with "
      "%s, rtol %g, atol %g, max step %g s (0: none)%s",
      node.c_str(), -sim.settleLift() * 1e3, sim.settledWheelLoadSum(), sim.staticLoad(),
      sim.method() == IntegrationMethod::kBdf ? "BDF" : "Adams", scene.solver.vehicle_rtol, scene.solver.vehicle_atol,
      sim.maxStep(),
      cosim ? (std::string("; co-simulation with the track over ") + toString(scene.solver.transport) +
               ", track step " + rail::contact::formatNumber(scene.solver.track_step) + " s")
                  .c_str()
            : "");
  VehicleOutputs outputs(nh, pnh, outputSettings(scene), defectOutlines(scene, sim.track()), sim, cosim, cost, clock);
  const auto viewer0 = std::chrono::steady_clock::now();  // a wait for viewers is not the vehicle's set-up
  if (!outputs.waitForSubscribers(node, nh, pnh, stop.requested)) return kExitBadInput;
  node_run.excludeFromSetUp(std::chrono::duration<double>(std::chrono::steady_clock::now() - viewer0).count());
  if (!outputs.openBag(node, pnh)) return kExitBadInput;

  const VehicleRunOptions options{&stop.requested, &cost};
  const RunSettings run_settings = runSettings(scene);
  VehicleRun run = cosim ? VehicleRun(run_settings, *cosim_vehicle, options) : VehicleRun(run_settings, sim, options);
  node_run.startLoop();
  ros_glue::ProgressLine progress(node, sim.endTimeEstimate());
  char where[64];
  bool write_failed = false;
  try {
    while (run.next() == VehicleRun::Event::kOutput) {
      outputs.publish(run.outputIndex());
      if (outputs.bag().failed()) {
        node_run.writeFailed(outputs.bag(), sim.time());
        write_failed = true;
        break;
      }
      if (progress.due()) {
        std::snprintf(where, sizeof(where), "leading wheelset at s = %.2f m", sim.leadingArcLength());
        progress.print(sim.time(), where);
      }
      if (!ros::ok()) stop.requested = true;
    }
  } catch (const std::exception& e) {
    ROS_FATAL("%s: internal error at t = %.4f s: %s", node.c_str(), sim.time(), e.what());
    if (cosim_vehicle) cosim_vehicle->close();
    return kExitInternal;  // the outputs close their bag
  }
  // A write failure has said its one line (NodeRun::writeFailed); the run's own end is reported otherwise.
  if (!write_failed) {
    switch (run.end()) {
      case VehicleRun::End::kFinished:
        break;
      case VehicleRun::End::kStopped:
        ROS_WARN("%s: stopped at t = %.4f s (%s); closing the bag", node.c_str(), sim.time(), stop.reason());
        break;
      case VehicleRun::End::kFailed:
        ROS_ERROR("%s: %s", node.c_str(), run.message().c_str());
        break;
      case VehicleRun::End::kExchangeFailed:
        ROS_FATAL("%s: %s (track node %s)", node.c_str(), run.message().c_str(), peer.c_str());
        break;
    }
  }
  if (cosim_vehicle) {
    cosim_vehicle->close();
    ROS_INFO("%s: %llu steps exchanged with the track node, largest CVODE step %.3g s", node.c_str(),
             static_cast<unsigned long long>(cosim_vehicle->stepsExchanged()), cosim_vehicle->maxInternalStep());
  }
  const int rc = node_run.endLoop(sim.time(), run.end() == VehicleRun::End::kStopped,
                                  write_failed ? kExitWriteFailed : run.exitCode(), "; closing the bag");
  outputs.close(node, cosim_vehicle.get(), node_run.loopSeconds(), rc);
  return rc == kExitOk && outputs.bag().failed() ? kExitWriteFailed : rc;
}

}  // namespace rail::vehicle
