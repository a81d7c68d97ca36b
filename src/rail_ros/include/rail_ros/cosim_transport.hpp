// ROS glue shared by rail_vehicle and rail_track: opens the scene's co-simulation transport
// (solver.transport: service, topic or shm) for one end, and derives the shm run id both nodes agree on.
// Header-only, used at set-up only (allocates, may throw).
#pragma once

#include <ros/console.h>
#include <ros/node_handle.h>
#include <ros/this_node.h>

#include <rail_core/coupling/protocol.hpp>
#include <rail_core/coupling/shm_transport.hpp>
#include <rail_core/coupling/transport.hpp>
#include <rail_core/exit_codes.hpp>
#include <rail_core/scene.hpp>
#include <rail_ros/service_transport.hpp>
#include <rail_ros/topic_transport.hpp>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

namespace rail::ros_glue {

namespace coupling = rail::core::coupling;

// The run id of the shm regions: ~run_id, else /railsim/run_id (cosim.launch sets it with $(anon run)),
// else "run". A value that is not 1..48 characters of [A-Za-z0-9_.-] is replaced by its 64-bit FNV-1a
// hash in hex, so both nodes derive the same id from the same parameter.
inline std::string shmRunId(ros::NodeHandle& pnh) {
  std::string id;
  if (!pnh.getParam("run_id", id) && !ros::param::get("/railsim/run_id", id)) id = "run";
  bool ok = !id.empty() && id.size() <= 48;
  for (const char c : id) {
    const bool allowed =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-';
    ok = ok && allowed;
  }
  if (ok) return id;
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a 64-bit offset basis
  for (const char c : id) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;  // FNV-1a 64-bit prime
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

// The options both ROS transports take from the scene.
inline void setRosTransportOptions(const rail::core::Scene& scene, rail::core::coupling::Role role,
                                   const std::string& peer_node, const std::atomic<bool>* interrupt,
                                   ros_glue::RosTransportOptions& o) {
  o.role = role;
  o.track_step = scene.solver.track_step;
  o.wheel_capacity = scene.wheelCount();
  o.attach_timeout = scene.solver.handshake_timeout;
  o.peer_node = peer_node;
  o.interrupt = interrupt;
}

// Opens this end of the scene's transport. peer_node: the peer's node name from the handshake. Waits up to
// solver.handshake_timeout for the peer. Throws rail::core::coupling::CouplingError (timeout, refused) or
// std::runtime_error (bad options).
inline std::unique_ptr<rail::core::coupling::FrameTransport> makeTransport(const rail::core::Scene& scene,
                                                                           rail::core::coupling::Role role,
                                                                           ros::NodeHandle& nh, ros::NodeHandle& pnh,
                                                                           const std::string& peer_node,
                                                                           const std::atomic<bool>* interrupt) {
  using namespace rail::core;
  switch (scene.solver.transport) {
    case Transport::kShm: {
      coupling::ShmOptions o;
      o.role = role;
      o.scene_hash = scene.hash;
      o.wheel_capacity = scene.wheelCount();
      o.run_id = shmRunId(pnh);
      o.attach_timeout = scene.solver.handshake_timeout;
      o.interrupt = interrupt;
      // With a flexible track both waits sleep at once: the vehicle's for a track step (hundreds of us, on
      // two threads), the track's for the vehicle's integration (the track's second thread solves the next
      // base step meanwhile). Spinning or yielding took a core from the threads at work; a futex wake-up
      // costs ~10 us.
      if (scene.runsFeIntegration()) o.spin_time = o.yield_time = 0.0;
      auto t = std::make_unique<coupling::ShmTransport>(o);
      if (!t->replacedStale().empty()) {  // a crashed run's region: say so, the run goes on
        ROS_WARN("%s: shm transport: %s", ros::this_node::getName().c_str(), t->replacedStale().c_str());
      }
      return t;
    }
    case Transport::kService: {
      ros_glue::ServiceTransportOptions o;
      setRosTransportOptions(scene, role, peer_node, interrupt, o);
      o.reply_timeout = scene.solver.exchange_timeout;
      return std::make_unique<ros_glue::ServiceTransport>(nh, o);
    }
    case Transport::kTopic: {
      ros_glue::TopicTransportOptions o;
      setRosTransportOptions(scene, role, peer_node, interrupt, o);
      return std::make_unique<ros_glue::TopicTransport>(nh, o);
    }
  }
  throw std::runtime_error("solver.transport: unknown transport");
}

// makeTransport with the nodes' report of a failure: 0 and the transport in `out`, else the exit code
// (4 peer gone or timed out, 3 refused, 2 bad options) after one FATAL line naming the node, the transport
// and the peer.
inline int openTransport(const rail::core::Scene& scene, rail::core::coupling::Role role, ros::NodeHandle& nh,
                         ros::NodeHandle& pnh, const std::string& peer_node, const std::atomic<bool>* interrupt,
                         std::unique_ptr<rail::core::coupling::FrameTransport>& out) {
  const std::string& me = ros::this_node::getName();
  const char* transport = rail::core::toString(scene.solver.transport);
  try {
    out = makeTransport(scene, role, nh, pnh, peer_node, interrupt);
    return rail::core::kExitOk;
  } catch (const rail::core::coupling::CouplingError& e) {
    ROS_FATAL("%s: cannot open the %s transport to %s: %s", me.c_str(), transport, peer_node.c_str(), e.what());
    return rail::core::coupling::exitCode(e.status());
  } catch (const std::exception& e) {
    ROS_FATAL("%s: cannot open the %s transport: %s", me.c_str(), transport, e.what());
    return rail::core::kExitBadInput;
  }
}

}  // namespace rail::ros_glue
