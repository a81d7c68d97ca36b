#include "rail_ros/topic_transport.hpp"

#include <vector>

#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <rail_contact/format.hpp>

#include "rail_ros/frame_messages.hpp"
#include "ros_transport_util.hpp"

namespace rail::ros_glue {

namespace coupling = rail::core::coupling;

namespace {

ros::WallDuration wall(Clock::duration d) {
  return d <= Clock::duration::zero() ? ros::WallDuration(0.0)
                                      : ros::WallDuration(std::chrono::duration<double>(d).count());
}

// How long frames already on their way are still collected after the peer's connection dropped: its last
// frame travels on the other connection and may be read a little after the drop is seen.
constexpr double kDropGrace = 0.02;  // [s]

}  // namespace

struct TopicTransport::Impl {
  enum class Outcome { kWaiting, kGot, kRefused, kCloseMarker };

  TopicTransportOptions o;
  Role role = Role::kVehicle;
  std::string out_topic, in_topic;  // resolved names
  ros::CallbackQueue frame_queue;   // frames received on in_topic
  ros::CallbackQueue link_queue;    // subscribers (dis)connecting to out_topic
  ros::Publisher pub;
  ros::Subscriber sub;
  rail_msgs::WheelStates states_out;  // outgoing messages, reused
  rail_msgs::ContactWrenches wrenches_out;

  // The receive in progress.
  coupling::WheelStateFrame* states_target = nullptr;
  coupling::WrenchFrame* wrenches_target = nullptr;
  Outcome outcome = Outcome::kWaiting;
  Result refusal;
  std::uint64_t expected = 0;  // step the next received frame must carry
  bool awaiting = false;       // vehicle: states sent, wrenches not yet received

  std::string peer;                      // the peer's node
  const void* peer_header = nullptr;     // connection header of the peer's frames (identifies them without a lookup)
  long foreign_frames = 0;               // frames from a node that is not the handshake's peer, dropped
  std::vector<std::string> subscribers;  // nodes subscribed to out_topic (changes only when links change)
  bool peer_dropped = false;             // the peer's subscription to out_topic ended
  bool closed = false;

  void onLink(const ros::SingleSubscriberPublisher& p, bool connected);
  template <class Msg>
  void onFrame(const ros::MessageEvent<Msg const>& event);
  template <class Frame>
  Result receive(Frame& frame, Deadline deadline);
  template <class Frame, class Msg>
  Result send(const Frame& frame, Msg& msg);
  bool hasSubscriber() const;
  void setTarget(coupling::WheelStateFrame& f) { states_target = &f; }
  void setTarget(coupling::WrenchFrame& f) { wrenches_target = &f; }
  bool fill(const rail_msgs::WheelStates& m, Result& r) {
    if (!states_target) return false;
    r = fromMessage(m, o.track_step, *states_target, in_topic.c_str());
    return true;
  }
  bool fill(const rail_msgs::ContactWrenches& m, Result& r) {
    if (!wrenches_target) return false;
    r = fromMessage(m, o.track_step, *wrenches_target, in_topic.c_str());
    return true;
  }
};

void TopicTransport::Impl::onLink(const ros::SingleSubscriberPublisher& p, bool connected) {
  const std::string name = p.getSubscriberName();
  if (connected) {
    subscribers.push_back(name);
    return;
  }
  for (auto it = subscribers.begin(); it != subscribers.end(); ++it)
    if (*it == name) {
      subscribers.erase(it);
      break;
    }
  if (!peer.empty() && name == peer) peer_dropped = true;
}

bool TopicTransport::Impl::hasSubscriber() const {
  if (o.peer_node.empty()) return !subscribers.empty();
  for (const std::string& s : subscribers)
    if (s == o.peer_node) return true;
  return false;
}

template <class Msg>
void TopicTransport::Impl::onFrame(const ros::MessageEvent<Msg const>& event) {
  const Msg& msg = *event.getConstMessage();
  // Frames count only from the handshake's peer: the connection header identifies it without a string
  // lookup; a frame on another connection is looked up once and dropped if another node sent it.
  const void* header = event.getConnectionHeaderPtr().get();
  if (header != peer_header) {
    const std::string& from = event.getPublisherName();
    if (!o.peer_node.empty() && from != o.peer_node) {
      if (foreign_frames++ == 0) {
        ROS_WARN(
            "topic %s: a frame from node %s, not this run's peer %s, was dropped (further ones are dropped "
            "silently)",
            in_topic.c_str(), from.c_str(), o.peer_node.c_str());
      }
      return;
    }
    peer_header = header;
    if (peer.empty()) peer = from;
  }
  if (outcome != Outcome::kWaiting) return;  // (only pumped while waiting)
  if (isCloseMarker(msg)) {
    outcome = Outcome::kCloseMarker;
    return;
  }
  if (msg.step != expected) {
    outcome = Outcome::kRefused;
    refusal = {Status::kRefused, "topic " + in_topic + ": step " + std::to_string(msg.step) + " received from node " +
                                     event.getPublisherName() + ", " + std::to_string(expected) + " expected"};
    return;
  }
  Result r;
  if (!fill(msg, r)) return;
  if (r) {
    outcome = Outcome::kGot;
  } else {
    outcome = Outcome::kRefused;
    refusal = r;
  }
}

template <class Frame>
Result TopicTransport::Impl::receive(Frame& frame, Deadline deadline) {
  if (closed) return {Status::kError, "this end is closed"};
  outcome = Outcome::kWaiting;
  setTarget(frame);
  Result result;
  bool first = true;
  for (;;) {
    // Frames first: one that is ready is delivered even after the deadline.
    const Clock::time_point now = Clock::now();
    frame_queue.callOne(first ? ros::WallDuration(0.0) : wall(detail::sliceEnd(deadline) - now));
    first = false;
    if (outcome != Outcome::kWaiting) break;
    link_queue.callAvailable(ros::WallDuration(0.0));
    if (peer_dropped) {
      const Deadline grace =
          Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kDropGrace));
      while (outcome == Outcome::kWaiting && Clock::now() < grace) frame_queue.callOne(wall(grace - Clock::now()));
      if (outcome != Outcome::kWaiting) break;
      result = {Status::kPeerClosed, nodeLabel(peer, coupling::peerOf(role)) + " ended its subscription to " +
                                         out_topic + " (the node ended or closed)"};
      break;
    }
    result = interrupted(o.interrupt);
    if (!result) break;
    if (Clock::now() >= deadline) {
      result = {Status::kTimeout, "no frame of step " + std::to_string(expected) + " on topic " + in_topic + " from " +
                                      nodeLabel(peer, coupling::peerOf(role))};
      break;
    }
  }
  states_target = nullptr;
  wrenches_target = nullptr;
  switch (outcome) {
    case Outcome::kGot:
      return {};
    case Outcome::kRefused:
      return refusal;
    case Outcome::kCloseMarker:
      return {Status::kPeerClosed, nodeLabel(peer, coupling::peerOf(role)) + " sent its close marker on " + in_topic};
    case Outcome::kWaiting:
      break;
  }
  return result;
}

template <class Frame, class Msg>
Result TopicTransport::Impl::send(const Frame& frame, Msg& msg) {
  if (closed) return {Status::kError, "this end is closed"};
  Result r = toMessage(frame, msg);
  if (!r) return r;
  pub.publish(msg);  // serialised here; written by roscpp's network thread
  return {};
}

// ---------------------------------------------------------------------------------------------------------
TopicTransport::TopicTransport(ros::NodeHandle& nh, const TopicTransportOptions& options)
    : impl_(std::make_unique<Impl>()) {
  checkOptions(options, "topic transport");
  Impl& d = *impl_;
  d.o = options;
  d.role = options.role;
  d.peer = options.peer_node;
  const bool vehicle = d.role == Role::kVehicle;
  const std::string states = nh.resolveName(options.states_topic);
  const std::string wrenches = nh.resolveName(options.wrenches_topic);
  d.out_topic = vehicle ? states : wrenches;
  d.in_topic = vehicle ? wrenches : states;
  reserveMessage(d.states_out, options.wheel_capacity);
  reserveMessage(d.wrenches_out, options.wheel_capacity);

  // Queue size 0 = unbounded (roscpp): no frame is dropped, in lockstep or when a bag runs ahead.
  ros::AdvertiseOptions ao;
  Impl* raw = &d;
  const ros::SubscriberStatusCallback on_connect = [raw](const ros::SingleSubscriberPublisher& p) {
    raw->onLink(p, true);
  };
  const ros::SubscriberStatusCallback on_disconnect = [raw](const ros::SingleSubscriberPublisher& p) {
    raw->onLink(p, false);
  };
  if (vehicle)
    ao.init<rail_msgs::WheelStates>(d.out_topic, 0, on_connect, on_disconnect);
  else
    ao.init<rail_msgs::ContactWrenches>(d.out_topic, 0, on_connect, on_disconnect);
  ao.latch = false;
  ao.callback_queue = &d.link_queue;
  d.pub = nh.advertise(ao);

  ros::SubscribeOptions so;
  if (vehicle)
    so.initByFullCallbackType<const ros::MessageEvent<rail_msgs::ContactWrenches const>&>(
        d.in_topic, 0, [raw](const ros::MessageEvent<rail_msgs::ContactWrenches const>& e) { raw->onFrame(e); });
  else
    so.initByFullCallbackType<const ros::MessageEvent<rail_msgs::WheelStates const>&>(
        d.in_topic, 0, [raw](const ros::MessageEvent<rail_msgs::WheelStates const>& e) { raw->onFrame(e); });
  so.transport_hints = ros::TransportHints().tcpNoDelay();
  so.callback_queue = &d.frame_queue;
  d.sub = nh.subscribe(so);
  if (!d.pub || !d.sub)
    throw coupling::CouplingError(Status::kError, std::string(coupling::toString(d.role)) + ": could not advertise " +
                                                      d.out_topic + " or subscribe to " + d.in_topic);

  if (!options.wait_for_subscriber) return;
  // Wait until the peer subscribes to this end's topic, so that the first frame reaches it (not latched).
  const Deadline deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.attach_timeout));
  for (;;) {
    d.link_queue.callAvailable(ros::WallDuration(0.0));
    if (d.hasSubscriber()) break;
    const Result r = interrupted(options.interrupt);
    if (!r)
      throw coupling::CouplingError(
          Status::kInterrupted,
          std::string(coupling::toString(d.role)) + ": interrupted while waiting for a subscriber of " + d.out_topic);
    if (Clock::now() >= deadline)
      throw coupling::CouplingError(Status::kTimeout, std::string(coupling::toString(d.role)) + ": " +
                                                          nodeLabel(options.peer_node, coupling::peerOf(d.role)) +
                                                          " did not subscribe to " + d.out_topic + " within " +
                                                          formatNumber(options.attach_timeout) +
                                                          " s (solver.handshake_timeout)");
    d.link_queue.callAvailable(ros::WallDuration(0.01));
  }
}

TopicTransport::~TopicTransport() {
  close();
  impl_->pub.shutdown();
}

Role TopicTransport::role() const { return impl_->role; }

Result TopicTransport::sendStates(const coupling::WheelStateFrame& frame, Deadline) {
  Impl& d = *impl_;
  if (d.role != Role::kVehicle) return detail::wrongRole(d.role, "send_states");
  Result r = d.send(frame, d.states_out);
  if (r) {
    d.expected = frame.step;
    d.awaiting = true;
  }
  return r;
}

Result TopicTransport::receiveWrenches(coupling::WrenchFrame& frame, Deadline deadline) {
  Impl& d = *impl_;
  if (d.role != Role::kVehicle) return detail::wrongRole(d.role, "receive_wrenches");
  if (!d.awaiting) return {Status::kError, "receive_wrenches called without send_states"};
  Result r = d.receive(frame, deadline);
  if (r) d.awaiting = false;
  return r;
}

Result TopicTransport::receiveStates(coupling::WheelStateFrame& frame, Deadline deadline) {
  Impl& d = *impl_;
  if (d.role != Role::kTrack) return detail::wrongRole(d.role, "receive_states");
  Result r = d.receive(frame, deadline);
  if (r) ++d.expected;
  return r;
}

Result TopicTransport::sendWrenches(const coupling::WrenchFrame& frame, Deadline) {
  Impl& d = *impl_;
  if (d.role != Role::kTrack) return detail::wrongRole(d.role, "send_wrenches");
  return d.send(frame, d.wrenches_out);
}

void TopicTransport::close() {
  Impl& d = *impl_;
  if (d.closed) return;
  d.closed = true;
  if (d.role == Role::kVehicle) {
    makeCloseMarker(d.states_out);
    d.pub.publish(d.states_out);
  } else {
    makeCloseMarker(d.wrenches_out);
    d.pub.publish(d.wrenches_out);
  }
  // Stop receiving now; the publisher is withdrawn by the destructor, so that roscpp's network thread can
  // still write the marker (the peer also sees this end's subscription end, which tells it the same).
  d.sub.shutdown();
}

const std::string& TopicTransport::peerNode() const { return impl_->peer; }

}  // namespace rail::ros_glue
