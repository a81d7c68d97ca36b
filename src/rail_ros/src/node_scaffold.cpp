#include "rail_ros/node_scaffold.hpp"

#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sys/stat.h>

#include <csignal>

#include <rail_msgs/Handshake.h>

#include "rail_core/exit_codes.hpp"
#include "rail_core/handshake.hpp"
#include "rail_ros/master_watch.hpp"
#include "rail_ros/scene_param.hpp"

namespace rail::ros_glue {

namespace {

const char* const kHandshakeService = "/railsim/handshake";

void onStopSignal(int s) {
  nodeStop().signal = s;
  nodeStop().requested = true;
}

bool stopRequested() { return nodeStop().requested || !ros::ok(); }

// Answers the vehicle's handshake; remembers whether it was accepted.
struct HandshakeServer {
  core::HandshakeInfo mine;
  bool answered = false;
  bool accepted = false;
  std::string refusal;
  std::string peer;         // the vehicle node's name
  double wheel_span = 0.0;  // the vehicle's, m

  bool onRequest(rail_msgs::Handshake::Request& req, rail_msgs::Handshake::Response& res) {
    core::HandshakeInfo theirs;
    theirs.node = req.node_name;
    theirs.scene_file = req.scene_file;
    theirs.scene_hash = req.scene_hash;
    theirs.wheel_count = req.wheel_count;
    theirs.track_step = req.track_step;
    theirs.transport = req.transport;
    theirs.wheel_span = req.wheel_span;
    refusal = core::compareHandshake(mine, theirs);
    res.accepted = refusal.empty();
    res.message = refusal;
    res.peer_name = mine.node;
    answered = true;
    accepted = res.accepted;
    peer = req.node_name;
    wheel_span = req.wheel_span;
    return true;
  }
};

}  // namespace

const char* NodeStop::reason() const {
  const int s = signal;
  return s == SIGINT ? "SIGINT" : s == SIGTERM ? "SIGTERM" : "ROS shutdown";
}

NodeStop& nodeStop() {
  static NodeStop stop;
  return stop;
}

void installStopSignals() {
  nodeStop();  // constructed before a signal can arrive
  std::signal(SIGINT, onStopSignal);
  std::signal(SIGTERM, onStopSignal);
}

int startNode(int argc, char** argv, const char* name, const char* what, core::Role role, core::Scene& scene) {
  if (nodeHelpRequested(argc, argv, name, what)) return core::kExitOk;
  ros::init(argc, argv, name, ros::init_options::NoSigintHandler);
  ::umask(077);  // the shm region is 0600 already
  installStopSignals();
  const std::string& me = ros::this_node::getName();
  if (const int rc = waitForMaster(me, nodeStop().signal); rc != 0) return rc;
  // Started here rather than by the first NodeHandle, so that the node outlives this function's handle.
  ros::start();
  ros::NodeHandle pnh("~");
  if (!readScene(pnh, scene)) return core::kExitBadInput;
  ROS_INFO_STREAM(me << ": will simulate\n" << core::describe(scene, role));
  if (role == core::Role::kTrack && !scene.needsTrackNode()) {
    ROS_INFO("%s: track_model is rigid: the vehicle runs alone, nothing to do here", me.c_str());
    return core::kExitOk;
  }
  if (role == core::Role::kVehicle && !scene.has_vehicle) {
    ROS_INFO("%s: the scene has no vehicle (moving loads on the track alone): nothing to do", me.c_str());
    return core::kExitOk;
  }
  if (pnh.param("validate_only", false)) return core::kExitOk;
  return -1;
}

int nodeMain(int argc, char** argv, const char* name, const char* what, core::Role role,
             int (*run)(const core::Scene& scene)) {
  core::Scene scene;
  if (const int rc = startNode(argc, argv, name, what, role, scene); rc >= 0) return rc;
  int rc = core::kExitInternal;
  try {
    rc = run(scene);
  } catch (const std::exception& e) {
    ROS_FATAL("%s: internal error: %s", ros::this_node::getName().c_str(), e.what());
  }
  ros::shutdown();
  return rc;
}

int handshakeAsVehicle(const core::Scene& scene, double wheel_span, std::string& peer) {
  const std::string& me = ros::this_node::getName();
  // Waits in short slices so that a track node that died (its guard's record, master_watch.hpp) is
  // reported at once, with its exit code, not after the whole timeout.
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(scene.solver.handshake_timeout);
  while (!ros::service::waitForService(kHandshakeService, ros::Duration(0.2))) {
    const std::string dead = exitedPeer(me);
    if (!dead.empty()) {
      ROS_FATAL("%s: the track node died before the handshake: %s (its log says why)", me.c_str(), dead.c_str());
      return core::kExitPeerTimeout;
    }
    if (stopRequested()) return core::kExitInterrupted;
    if (ros::WallTime::now() >= deadline) {
      ROS_FATAL(
          "%s: the track node did not offer %s within %.1f s (solver.handshake_timeout): is rail_track "
          "running?",
          me.c_str(), kHandshakeService, scene.solver.handshake_timeout);
      return core::kExitPeerTimeout;
    }
  }
  const core::HandshakeInfo mine = core::handshakeInfo(scene, me);
  rail_msgs::Handshake srv;
  srv.request.node_name = mine.node;
  srv.request.scene_file = mine.scene_file;
  srv.request.scene_hash = mine.scene_hash;
  srv.request.wheel_count = mine.wheel_count;
  srv.request.track_step = mine.track_step;
  srv.request.transport = mine.transport;
  srv.request.wheel_span = wheel_span;
  if (!ros::service::call(kHandshakeService, srv)) {
    ROS_FATAL("%s: the call to %s failed: the track node went away", me.c_str(), kHandshakeService);
    return core::kExitPeerTimeout;
  }
  if (!srv.response.accepted) {
    ROS_FATAL("%s: %s refused the handshake: %s", me.c_str(), srv.response.peer_name.c_str(),
              srv.response.message.c_str());
    return core::kExitPeerRefused;
  }
  peer = srv.response.peer_name;
  ROS_INFO("%s: handshake with %s complete", me.c_str(), peer.c_str());
  return core::kExitOk;
}

int handshakeAsTrack(ros::NodeHandle& nh, const core::Scene& scene, std::string& peer, double& wheel_span) {
  const std::string& me = ros::this_node::getName();
  HandshakeServer server;
  server.mine = core::handshakeInfo(scene, me);
  ros::ServiceServer srv = nh.advertiseService(kHandshakeService, &HandshakeServer::onRequest, &server);
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(scene.solver.handshake_timeout);
  // A vehicle node that died before calling (its guard's record, master_watch.hpp) is reported at once.
  std::string dead;
  ros::WallTime next_check = ros::WallTime::now();
  while (!stopRequested() && !server.answered && ros::WallTime::now() < deadline) {
    ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.05));
    if (!server.answered && ros::WallTime::now() >= next_check) {
      dead = exitedPeer(me);
      if (!dead.empty()) break;
      next_check = ros::WallTime::now() + ros::WallDuration(0.2);
    }
  }
  if (stopRequested()) return core::kExitInterrupted;
  if (!dead.empty()) {
    ROS_FATAL("%s: the vehicle node died before the handshake: %s (its log says why)", me.c_str(), dead.c_str());
    return core::kExitPeerTimeout;
  }
  if (!server.answered) {
    ROS_FATAL("%s: no vehicle node called %s within %.1f s (solver.handshake_timeout): is rail_vehicle running?",
              me.c_str(), kHandshakeService, scene.solver.handshake_timeout);
    return core::kExitPeerTimeout;
  }
  if (!server.accepted) {
    ROS_FATAL("%s: handshake refused: %s", me.c_str(), server.refusal.c_str());
    return core::kExitPeerRefused;
  }
  ROS_INFO("%s: handshake with %s complete", me.c_str(), server.peer.c_str());
  peer = server.peer;
  wheel_span = server.wheel_span;
  // Let the service response reach the caller before the server goes away.
  ros::WallDuration(0.1).sleep();
  return core::kExitOk;
}

}  // namespace rail::ros_glue
