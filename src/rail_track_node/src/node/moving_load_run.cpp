#include "moving_load_run.hpp"

#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include <rail_msgs/RailDeflection.h>
#include <rail_core/exit_codes.hpp>
#include <rail_core/run_settings.hpp>
#include <rail_ros/node_scaffold.hpp>
#include <rail_ros/run_output.hpp>

#include "rail_track_node/scene_track.hpp"
#include "rail_track_node/track_simulator.hpp"
#include "track_markers.hpp"
#include "track_messages.hpp"

namespace rail::track {

using namespace rail::core;
namespace ros_glue = rail::ros_glue;

int runMovingLoads(ros::NodeHandle& nh, ros::NodeHandle& pnh, const Scene& scene) {
  ros_glue::NodeRun node_run(ros::this_node::getName());  // no cost profile: the track simulator reports its own
  const std::string& me = node_run.node();
  ros_glue::NodeStop& stop = node_run.stop();
  // ---- build ----
  std::unique_ptr<SceneTrack> track;
  SimulatorSettings settings;
  try {
    track = std::make_unique<SceneTrack>(buildSceneTrack(scene));
    settings.t_end = movingLoadEndTime(scene);
  } catch (const std::exception& e) {
    ROS_FATAL("%s: %s", me.c_str(), e.what());
    return kExitBadInput;
  }
  settings.track_step = scene.solver.track_step;
  settings.loads = scene.moving_loads;
  settings.rail_height = track->rail_height;
  const TrackModel& model = track->model;
  ROS_INFO(
      "%s: flexible track built: %d free DOFs, %d sleepers; running to t = %.4g s with track step %.3g s (%ld steps)",
      me.c_str(), model.system.size(), model.mesh.n_sleepers, settings.t_end, settings.track_step,
      std::lround(settings.t_end / settings.track_step));
  // Factorising K_eff and the static solve fail on non-physical track data (e.g. a matrix that is not
  // positive definite): a refused input, named with the scene and its track data file.
  std::unique_ptr<TrackSimulator> sim_ptr;
  try {
    sim_ptr = std::make_unique<TrackSimulator>(model, settings);
  } catch (const std::exception& e) {
    ROS_FATAL("%s: %s: track.data %s: the track cannot be solved: %s", me.c_str(), scene.file.c_str(),
              scene.track.data.path.c_str(), e.what());
    return kExitBadInput;
  }
  TrackSimulator& sim = *sim_ptr;
  sim.setProgressCallback(
      [&me](const SimulationProgress& p) { ros_glue::logProgress(me, p.t, p.t_end, p.real_time_factor, p.eta); },
      pnh.param("progress_interval", 2.0));

  const bool deflections = scene.effects.rail_deflection_output && !scene.output.deflection_sections.empty();
  if (deflections) {
    const TrackFrameFunction frames = seatPlaneFrames(track->geometry, track->seat_below_centre);
    for (std::size_t i = 0; i < scene.output.deflection_sections.size(); ++i) {
      try {
        sim.addSection(scene.output.deflection_sections[i], frames);
      } catch (const std::exception& e) {
        ROS_FATAL("%s: %s: output.deflection_sections[%zu]: %s", me.c_str(), scene.file.c_str(), i, e.what());
        return kExitBadInput;
      }
    }
  }

  // ---- ROS wiring ----
  ros::Publisher clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  ros::Publisher deflection_pub, marker_pub;
  if (deflections) deflection_pub = nh.advertise<rail_msgs::RailDeflection>("/rail_deflection", 100);
  std::unique_ptr<TrackMarkers> markers;
  double marker_period = 0.0;
  if (scene.effects.rviz_markers) {
    marker_pub = nh.advertise<visualization_msgs::MarkerArray>("/markers", 2, true);
    const ros_glue::MarkerParams m = ros_glue::markerParams(pnh);
    markers = std::make_unique<TrackMarkers>(model, m.frame_id, m.scale, m.colour_range);
    marker_period = m.period(scene.output.rate);
  }

  ros_glue::OutputBag bag;
  bool bag_deflection = false, bag_markers = false, bag_clock = false;
  const core::OutputSettings outputs = core::outputSettings(scene);
  if (!outputs.output.bag.empty()) {
    if (!bag.open(me, outputs.source, ros_glue::bagPath(pnh, outputs.output.bag))) return kExitBadInput;
    bag_deflection = deflections && outputs.records("rail_deflection");
    bag_markers = markers && outputs.records("markers");
    bag_clock = outputs.records("clock");
    for (const std::string& t : outputs.output.topics)
      if (t != "rail_deflection" && t != "markers" && t != "clock")
        ROS_WARN("%s: output.topics: %s has no source in a moving-load run; not recorded", me.c_str(), t.c_str());
    ROS_INFO("%s: recording to %s", me.c_str(), bag.path().c_str());
  }

  // Optionally wait (wall clock) for subscribers to connect, so that they see the run from t = 0.
  const double wait = pnh.param("wait_for_subscribers", 0.0);
  if (wait > 0.0) {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(wait);
    while (
        !stop.requested && ros::ok() && ros::WallTime::now() < until &&
        ((deflections && deflection_pub.getNumSubscribers() == 0) || (markers && marker_pub.getNumSubscribers() == 0)))
      ros::WallDuration(0.02).sleep();
  }

  // ---- loop: advance to each output time, publish ----
  std::vector<rail_msgs::RailDeflection> deflection_msgs(static_cast<std::size_t>(sim.sectionCount()));
  for (rail_msgs::RailDeflection& m : deflection_msgs) m.header.frame_id = "track";
  RailSectionDeflection deflection;
  rosgraph_msgs::Clock clock_msg;
  const double period = 1.0 / scene.output.rate;
  double next_marker = 0.0;
  int exit_code = kExitOk;
  bool stop_logged = false;
  for (long k = 0;; ++k) {
    if (stop.requested || !ros::ok()) {
      ROS_WARN("%s: stopped at t = %.4f s (%s)", me.c_str(), sim.time(), stop.reason());
      stop_logged = true;
      exit_code = kExitInterrupted;
      break;
    }
    sim.advanceTo(std::min(static_cast<double>(k) * period, settings.t_end));
    const ros::Time stamp(sim.time());
    clock_msg.clock = stamp;
    clock_pub.publish(clock_msg);
    if (bag_clock) bag.write("/clock", stamp, clock_msg);
    for (std::size_t i = 0; i < deflection_msgs.size(); ++i) {
      sim.sectionDeflection(static_cast<int>(i), deflection);
      fill(deflection_msgs[i], deflection, stamp);
      deflection_pub.publish(deflection_msgs[i]);
      if (bag_deflection) bag.write("/rail_deflection", stamp, deflection_msgs[i]);
    }
    if (markers && (sim.time() + 1e-12 >= next_marker || sim.finished())) {
      next_marker += marker_period;
      const visualization_msgs::MarkerArray& ma = markers->update(sim.state().d, stamp);
      marker_pub.publish(ma);
      if (bag_markers) bag.write("/markers", stamp, ma);
    }
    if (bag.failed()) {
      exit_code = node_run.writeFailed(bag, sim.time());
      stop_logged = true;
      break;
    }
    if (sim.finished()) break;
  }
  exit_code = node_run.endLoop(sim.time(), stop_logged, exit_code);
  bag.close(me);
  if (exit_code == kExitOk) {
    ROS_INFO("%s: finished at t = %.4f s (%ld steps)", me.c_str(), sim.time(), sim.steps());
    ros::WallDuration(0.3).sleep();  // let subscribers receive the last messages
  }
  return exit_code;
}

}  // namespace rail::track
