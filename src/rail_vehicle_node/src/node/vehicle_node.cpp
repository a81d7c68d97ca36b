// rail_vehicle node: ROS wiring of the vehicle side. Reads the scene from the parameter server, validates
// it, reports what it will simulate and, in a co-simulation, checks with the track node that both run the
// same scene. Physics lives in the ROS-free core.
#include <ros/ros.h>

#include <rail_core/exit_codes.hpp>
#include <rail_core/handshake.hpp>
#include <rail_core/ros/scene_param.hpp>
#include <rail_core/scene_loader.hpp>
#include <rail_msgs/Handshake.h>

using namespace rail::core;

namespace {

int handshake(const Scene& scene) {
  const std::string service = "/railsim/handshake";
  const ros::Duration timeout(scene.solver.handshake_timeout);
  if (!ros::service::waitForService(service, timeout)) {
    ROS_FATAL("%s: the track node did not offer %s within %.1f s (solver.handshake_timeout): is rail_track "
              "running?", ros::this_node::getName().c_str(), service.c_str(), scene.solver.handshake_timeout);
    return kExitPeerTimeout;
  }
  const HandshakeInfo mine = handshake_info(scene, ros::this_node::getName());
  rail_msgs::Handshake srv;
  srv.request.node_name = mine.node;
  srv.request.scene_file = mine.scene_file;
  srv.request.scene_hash = mine.scene_hash;
  srv.request.wheel_count = mine.wheel_count;
  srv.request.track_step = mine.track_step;
  srv.request.transport = mine.transport;
  if (!ros::service::call(service, srv)) {
    ROS_FATAL("%s: the call to %s failed: the track node went away", ros::this_node::getName().c_str(),
              service.c_str());
    return kExitPeerTimeout;
  }
  if (!srv.response.accepted) {
    ROS_FATAL("%s: %s refused the handshake: %s", ros::this_node::getName().c_str(),
              srv.response.peer_name.c_str(), srv.response.message.c_str());
    return kExitPeerRefused;
  }
  ROS_INFO("%s: handshake with %s complete", ros::this_node::getName().c_str(), srv.response.peer_name.c_str());
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "rail_vehicle");
  ros::NodeHandle pnh("~");
  Scene scene;
  if (!ros_glue::read_scene(pnh, scene)) return kExitBadInput;
  ROS_INFO_STREAM(ros::this_node::getName() << ": will simulate\n" << describe(scene, Role::kVehicle));
  if (!scene.has_vehicle) {
    ROS_INFO("%s: the scene has no vehicle (moving loads on the track alone): nothing to do",
             ros::this_node::getName().c_str());
    return kExitOk;
  }
  if (pnh.param("validate_only", false)) return kExitOk;
  if (scene.cosimulation()) {
    const int rc = handshake(scene);
    if (rc != kExitOk) return rc;
  }
  ROS_WARN("%s: scene validated; this build has no vehicle time integration yet, exiting",
           ros::this_node::getName().c_str());
  return kExitOk;
}
