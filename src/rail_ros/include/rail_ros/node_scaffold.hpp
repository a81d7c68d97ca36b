// What both railsim nodes do around their run loop, the same way: the stop flag that SIGINT, SIGTERM and a
// lost master set, and the co-simulation handshake over /railsim/handshake (rail_msgs/Handshake), in which
// the vehicle node calls and the track node answers.
#pragma once

#include <ros/node_handle.h>

#include <atomic>
#include <string>

#include "rail_core/scene.hpp"
#include "rail_core/scene_loader.hpp"

namespace rail::ros_glue {

// The process's stop request: set from a signal handler, read by the run loop, the transports' waits and
// MasterWatch.
struct NodeStop {
  std::atomic<bool> requested{false};
  std::atomic<int> signal{0};  // the signal that set `requested` (0: ROS shutdown or a lost master)

  // "SIGINT", "SIGTERM" or "ROS shutdown", for the run's closing line.
  const char* reason() const;
};

// The one NodeStop of this process.
NodeStop& nodeStop();

// SIGINT and SIGTERM set nodeStop() (the run loop then closes the bags and exits 5).
void installStopSignals();

// The start both nodes share: answers -h/--help; ros::init without roscpp's SIGINT handler (the stop flag
// takes the signals); umask 077 (bags and cost profiles are the user's alone); the stop signals; the
// master wait; ros::start(); the scene from the parameter server, validated, and the "will simulate"
// report for `role`. Returns -1 when the node goes on with `scene`, else the exit code to return: 0 after
// --help, with ~validate_only, and when the scene has nothing for `role` (no track side with the rigid
// track, no vehicle side without a vehicle), which the node says.
int startNode(int argc, char** argv, const char* name, const char* what, core::Role role, core::Scene& scene);

// A node's main: startNode, then run(scene) for its exit code (kExitInternal after one FATAL line when it
// throws), then ros::shutdown().
int nodeMain(int argc, char** argv, const char* name, const char* what, core::Role role,
             int (*run)(const core::Scene& scene));

// The vehicle's side: waits for the track's service (up to solver.handshake_timeout; a track node that died
// meanwhile is reported at once with its exit code) and calls it. Returns 0 and the track node's name in
// `peer`, else the exit code (4 no or dead peer, 3 refused, 5 stopped) after a FATAL line saying why.
// wheel_span: the vehicle's first to last wheel centre at rest (m), which the track sizes its window by.
int handshakeAsVehicle(const core::Scene& scene, double wheel_span, std::string& peer);

// The track's side: serves /railsim/handshake until the vehicle has called (same timeout and dead-peer
// check). Returns 0, the vehicle node's name in `peer` and its wheel span (m) in `wheel_span`, else the exit
// code after a FATAL line.
int handshakeAsTrack(ros::NodeHandle& nh, const core::Scene& scene, std::string& peer, double& wheel_span);

}  // namespace rail::ros_glue
