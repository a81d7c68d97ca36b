// ROS service transport (library rail_ros): one rail_msgs/Lockstep call per track step, states in,
// wrenches out (paper section 5, the exchange of Figure 14 as a remote call).
//
// Vehicle end: a persistent service client; send_states() hands the request to a caller thread owned by
// the transport, receive_wrenches() waits for the answer up to the deadline (roscpp's call has no timeout
// of its own, so the call never runs on the caller's thread). A dropped connection (the track node ended or
// closed) gives kPeerClosed at once, a track that never answers kTimeout.
// Track end: serves the service on a callback queue of its own with one spinner thread; the callback hands
// the states to the waiting receive_states() and blocks until send_wrenches() provides the answer (or
// reply_timeout passes, or the end closes).
// close(): the vehicle sends a close marker (kCloseStep, frame_messages.hpp) from its caller thread; the
// track answers pending calls with ok = false and withdraws the service, which drops the vehicle's
// connection. Messages name the role, the service and the peer's node.
#pragma once

#include <memory>
#include <string>

#include <ros/node_handle.h>

#include "rail_core/coupling/transport.hpp"
#include "rail_ros/ros_transport_options.hpp"

namespace rail::ros_glue {

namespace coupling = rail::core::coupling;

struct ServiceTransportOptions : RosTransportOptions {
  std::string service = "/railsim/lockstep";  // resolved against the node handle given
  double reply_timeout = 10.0;  // track end: longest a call waits for send_wrenches() [s] (solver.exchange_timeout)
};

class ServiceTransport : public coupling::FrameTransport {
 public:
  // Vehicle: waits up to attach_timeout for the service and connects; throws coupling::CouplingError
  // (kTimeout) naming the service when it never appears. Track: advertises the service and starts the
  // spinner thread. Throws std::runtime_error for bad options. ros::init must have been called.
  ServiceTransport(ros::NodeHandle& nh, const ServiceTransportOptions& options);
  ~ServiceTransport() override;  // close(), then joins its threads (bounded)
  ServiceTransport(const ServiceTransport&) = delete;
  ServiceTransport& operator=(const ServiceTransport&) = delete;

  coupling::Role role() const override;
  coupling::Result sendStates(const coupling::WheelStateFrame& frame, coupling::Deadline deadline) override;
  coupling::Result receiveWrenches(coupling::WrenchFrame& frame, coupling::Deadline deadline) override;
  coupling::Result receiveStates(coupling::WheelStateFrame& frame, coupling::Deadline deadline) override;
  coupling::Result sendWrenches(const coupling::WrenchFrame& frame, coupling::Deadline deadline) override;
  void close() override;

  const std::string& serviceName() const;  // resolved
  // The peer's node: the service's provider (vehicle end) or the last caller (track end); empty if unknown.
  std::string peerNode() const;

  struct VehicleEnd;  // implementation of each end (service_transport.cpp)
  struct TrackEnd;

 private:
  std::shared_ptr<VehicleEnd> vehicle_;  // shared with its caller thread
  std::unique_ptr<TrackEnd> track_;
  coupling::Role role_;
};

}  // namespace rail::ros_glue
