// ROS topic transport (library rail_ros): the vehicle publishes its wheel states on the states topic,
// the track its wrenches on the wrenches topic, each frame stamped with its step index. Suited to runs that
// are recorded (rosbag record of the two exchange topics) and replayed (a bag of the states topic can
// drive a track node on its own: options.wait_for_subscriber = false).
//
// Not latched; publisher and subscriber queues unbounded (size 0), so no frame is ever dropped (in lockstep
// at most one frame per direction is in flight; a replayed bag may run ahead of the track); the
// subscriptions ask for TCP_NODELAY. Each receiver waits, up to the deadline, for the frame of the step it
// expects (the vehicle: the step it sent; the track: 0, 1, 2, ...) and refuses a frame of any other step
// (kRefused naming both). Incoming messages are delivered on a callback queue of the transport's own,
// pumped by the receiving call (no thread of its own). The peer's departure is seen from its
// subscription to this end's topic: a close marker (close()), or the peer node's connection dropping
// (the node ended) gives kPeerClosed.
#pragma once

#include <memory>
#include <string>

#include <ros/node_handle.h>

#include "rail_core/coupling/transport.hpp"
#include "rail_ros/ros_transport_options.hpp"

namespace rail::ros_glue {

namespace coupling = rail::core::coupling;

struct TopicTransportOptions : RosTransportOptions {
  std::string states_topic = "/railsim/wheel_states_exchange";        // vehicle -> track (WheelStates)
  std::string wrenches_topic = "/railsim/contact_wrenches_exchange";  // track -> vehicle (ContactWrenches)
  // Construction waits (up to attach_timeout) until this end's topic has a subscriber: the peer node when
  // peer_node is given, any subscriber otherwise. false for a track driven by a bag.
  bool wait_for_subscriber = true;
};

class TopicTransport : public coupling::FrameTransport {
 public:
  // Advertises this end's topic, subscribes to the peer's, and waits for the subscriber (see
  // wait_for_subscriber); throws coupling::CouplingError (kTimeout) naming the topic when none comes,
  // std::runtime_error for bad options. ros::init must have been called.
  TopicTransport(ros::NodeHandle& nh, const TopicTransportOptions& options);
  ~TopicTransport() override;  // close()
  TopicTransport(const TopicTransport&) = delete;
  TopicTransport& operator=(const TopicTransport&) = delete;

  coupling::Role role() const override;
  coupling::Result sendStates(const coupling::WheelStateFrame& frame, coupling::Deadline deadline) override;
  coupling::Result receiveWrenches(coupling::WrenchFrame& frame, coupling::Deadline deadline) override;
  coupling::Result receiveStates(coupling::WheelStateFrame& frame, coupling::Deadline deadline) override;
  coupling::Result sendWrenches(const coupling::WrenchFrame& frame, coupling::Deadline deadline) override;
  // Publishes the close marker and withdraws both topics. Never blocks.
  void close() override;

  // The peer's node (given, or the publisher of the first frame received); empty if unknown.
  const std::string& peerNode() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace rail::ros_glue
