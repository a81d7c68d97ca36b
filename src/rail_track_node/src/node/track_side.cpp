#include "track_side.hpp"

#include <ros/ros.h>

#include <chrono>
#include <memory>
#include <string>

#include <rail_core/cost_profile.hpp>
#include <rail_core/coupling/replay_transport.hpp>
#include <rail_core/exit_codes.hpp>
#include <rail_core/run_settings.hpp>
#include <rail_ros/cosim_transport.hpp>
#include <rail_ros/node_scaffold.hpp>
#include <rail_ros/replay_bag.hpp>
#include <rail_ros/run_output.hpp>

#include "cosim_outputs.hpp"
#include "moving_load_run.hpp"
#include "rail_track_node/cosim_track.hpp"
#include "rail_track_node/cosim_track_run.hpp"

namespace rail::track {

using namespace rail::core;
namespace cc = rail::core::coupling;
namespace ros_glue = rail::ros_glue;

namespace {

// The track side of a co-simulation after the handshake (peer: the vehicle node; wheel_span: its first to
// last wheel, m), or of a replay of `replay_bag`. Returns the exit code.
int runCosim(ros::NodeHandle& nh, ros::NodeHandle& pnh, const Scene& scene, const std::string& peer, double wheel_span,
             const std::string& replay_bag = "") {
  ros_glue::NodeRun node_run(ros::this_node::getName());
  const std::string& me = node_run.node();
  ros_glue::NodeStop& stop = node_run.stop();
  CostProfile& cost = node_run.cost();
  CostClock& clock = node_run.clock();  // the finer split, filled by the track core (cost_profile.hpp)
  std::unique_ptr<cc::FrameTransport> transport;
  if (!replay_bag.empty()) {
    try {
      const double t_end = scene.solver.end.kind == EndKind::kTime ? scene.solver.end.value : 0.0;
      auto replay = std::make_unique<cc::ReplayTransport>(ros_glue::readRecordedStates(replay_bag, scene.wheelCount()),
                                                          scene.solver.track_step, scene.hash, t_end);
      ROS_INFO("%s: replaying the wheel states of %s (t = 0 .. %.4f s)", me.c_str(), replay_bag.c_str(),
               replay->endTime());
      wheel_span = replay->wheelSpan();
      transport = std::move(replay);
    } catch (const std::exception& e) {
      ROS_FATAL("%s: %s", me.c_str(), e.what());
      return kExitBadInput;
    }
  }
  CosimTrackOptions track_options;
  track_options.cost = &clock;
  track_options.window.vehicle_length = wheel_span;
  std::unique_ptr<CosimTrack> track;
  try {
    track = std::make_unique<CosimTrack>(resolveCosimTrack(scene), track_options);
  } catch (const std::exception& e) {
    ROS_FATAL("%s: cannot build the track: %s", me.c_str(), e.what());
    return kExitBadInput;
  }
  if (scene.effects.rail_deflection_output) {
    for (std::size_t i = 0; i < scene.output.deflection_sections.size(); ++i) {
      try {
        track->addSection(scene.output.deflection_sections[i]);
      } catch (const std::exception& e) {
        ROS_FATAL("%s: %s: output.deflection_sections[%zu]: %s", me.c_str(), scene.file.c_str(), i, e.what());
        return kExitBadInput;
      }
    }
  }
  if (!transport) {
    if (const int rc = ros_glue::openTransport(scene, cc::Role::kTrack, nh, pnh, peer, &stop.requested, transport);
        rc != kExitOk)
      return rc;
  }
  ROS_INFO("%s: %s track built (%d wheels); serving the %s transport, track step %g s", me.c_str(),
           track->flexible() ? "flexible" : "rigid", track->wheelCount(), toString(scene.solver.transport),
           scene.solver.track_step);
  CosimTrackOutputs outputs(nh, pnh, outputSettings(scene), *track, cost, clock);
  if (!outputs.openBag(me, pnh)) return kExitBadInput;

  CosimTrackRun run(runSettings(scene), *track, *transport, {peer, !replay_bag.empty(), &cost});
  node_run.startLoop();
  int exit_code = kExitOk;
  bool stop_logged = false;  // the run loop said why it stopped
  for (TrackRunStatus status; (status = run.step()) != TrackRunStatus::kFinished;) {
    if (status == TrackRunStatus::kFailed) {
      ROS_FATAL("%s: %s", me.c_str(), run.message().c_str());
      exit_code = run.exitCode();
      break;
    }
    if (run.outputDue()) {
      outputs.publish(ros::Time(std::max(run.time(), 1e-9)), run.states());
      if (outputs.bag().failed()) {
        exit_code = node_run.writeFailed(outputs.bag(), run.time());
        stop_logged = true;
        break;
      }
    }
    if (stop.requested || !ros::ok()) {
      ROS_WARN("%s: stopped at t = %.4f s (%s)", me.c_str(), run.time(), stop.reason());
      stop_logged = true;
      exit_code = kExitInterrupted;
      break;
    }
  }
  run.close();
  exit_code = node_run.endLoop(run.time(), stop_logged, exit_code);
  outputs.close(me, run, exit_code, node_run.loopSeconds());
  return exit_code == kExitOk && outputs.bag().failed() ? kExitWriteFailed : exit_code;
}

}  // namespace

int runTrackSide(const Scene& scene) {
  ros::NodeHandle nh, pnh("~");
  const std::string me = ros::this_node::getName();
  const std::string replay_bag = pnh.param<std::string>("replay_bag", "");
  if (!replay_bag.empty()) {
    if (!scene.has_vehicle) {
      ROS_FATAL("%s: ~replay_bag: the scene has no vehicle to replay", me.c_str());
      return kExitBadInput;
    }
    return runCosim(nh, pnh, scene, "(replay)", 0.0, replay_bag);
  }
  if (!scene.has_vehicle) return runMovingLoads(nh, pnh, scene);
  std::string peer;
  double wheel_span = 0.0;
  const int rc = ros_glue::handshakeAsTrack(nh, scene, peer, wheel_span);
  return rc != kExitOk ? rc : runCosim(nh, pnh, scene, peer, wheel_span);
}

}  // namespace rail::track
