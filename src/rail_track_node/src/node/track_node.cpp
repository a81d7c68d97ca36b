// rail_track node: ROS wiring of the track side. Reads the scene from the parameter server, validates it,
// reports what it will simulate and, in a co-simulation, waits for the vehicle node's handshake. Physics
// lives in the ROS-free core.
#include <ros/callback_queue.h>
#include <ros/ros.h>

#include <rail_core/exit_codes.hpp>
#include <rail_core/handshake.hpp>
#include <rail_core/ros/scene_param.hpp>
#include <rail_core/scene_loader.hpp>
#include <rail_msgs/Handshake.h>

using namespace rail::core;

namespace {

// Answers the vehicle's handshake; remembers whether it was accepted.
struct HandshakeServer {
  HandshakeInfo mine;
  bool answered = false;
  bool accepted = false;
  std::string refusal;

  bool on_request(rail_msgs::Handshake::Request& req, rail_msgs::Handshake::Response& res) {
    HandshakeInfo theirs;
    theirs.node = req.node_name;
    theirs.scene_file = req.scene_file;
    theirs.scene_hash = req.scene_hash;
    theirs.wheel_count = req.wheel_count;
    theirs.track_step = req.track_step;
    theirs.transport = req.transport;
    refusal = compare_handshake(mine, theirs);
    res.accepted = refusal.empty();
    res.message = refusal;
    res.peer_name = mine.node;
    answered = true;
    accepted = res.accepted;
    return true;
  }
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "rail_track");
  ros::NodeHandle nh, pnh("~");
  Scene scene;
  if (!ros_glue::read_scene(pnh, scene)) return kExitBadInput;
  ROS_INFO_STREAM(ros::this_node::getName() << ": will simulate\n" << describe(scene, Role::kTrack));
  if (!scene.needs_track_node()) {
    ROS_INFO("%s: track_model is rigid: the vehicle runs alone, nothing to do here",
             ros::this_node::getName().c_str());
    return kExitOk;
  }
  if (pnh.param("validate_only", false)) return kExitOk;

  if (scene.has_vehicle) {
    HandshakeServer server;
    server.mine = handshake_info(scene, ros::this_node::getName());
    ros::ServiceServer srv = nh.advertiseService("/railsim/handshake", &HandshakeServer::on_request, &server);
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(scene.solver.handshake_timeout);
    while (ros::ok() && !server.answered && ros::WallTime::now() < deadline) {
      ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(0.05));
    }
    if (!ros::ok()) return kExitInterrupted;
    if (!server.answered) {
      ROS_FATAL("%s: no vehicle node called /railsim/handshake within %.1f s (solver.handshake_timeout): is "
                "rail_vehicle running?", ros::this_node::getName().c_str(), scene.solver.handshake_timeout);
      return kExitPeerTimeout;
    }
    if (!server.accepted) {
      ROS_FATAL("%s: handshake refused: %s", ros::this_node::getName().c_str(), server.refusal.c_str());
      return kExitPeerRefused;
    }
    ROS_INFO("%s: handshake complete", ros::this_node::getName().c_str());
    // Let the service response reach the caller before the node goes away.
    ros::WallDuration(0.2).sleep();
  }
  ROS_WARN("%s: scene validated; this build has no track time integration yet, exiting",
           ros::this_node::getName().c_str());
  return kExitOk;
}
