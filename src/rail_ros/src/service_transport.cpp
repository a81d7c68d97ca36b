#include "rail_ros/service_transport.hpp"

#include <condition_variable>
#include <mutex>
#include <thread>

#include <rail_msgs/Lockstep.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <rail_contact/format.hpp>

#include "rail_ros/frame_messages.hpp"
#include "ros_transport_util.hpp"

namespace rail::ros_glue {

namespace coupling = rail::core::coupling;

namespace {

Deadline after(double seconds) {
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

// How long the destructor waits for the caller thread before dropping the connection under it, and again
// before leaving it behind (it then owns the state it uses).
constexpr double kJoinWait = 2.0;

}  // namespace

// ---------------------------------------------------------------------------------------------------------
// Vehicle end: the caller thread makes the calls; the protocol's thread only hands requests over and waits
// for answers with its deadline.
struct ServiceTransport::VehicleEnd : std::enable_shared_from_this<VehicleEnd> {
  enum class Phase {
    kIdle,            // no call in flight, no answer unread
    kRequested,       // the request is handed over; the call is (or is about to be) in flight
    kDone,            // the call returned; answer (or failure) not read yet
    kCloseRequested,  // close(): the caller thread sends the close marker
    kStopped,         // the caller thread has ended
  };

  ServiceTransportOptions o;
  std::string service;  // resolved name
  ros::ServiceClient client;
  rail_msgs::Lockstep srv;  // request and response, reused every step
  std::mutex m;
  std::condition_variable cv;
  Phase phase = Phase::kIdle;
  bool call_ok = false;
  bool closed = false;
  bool give_up = false;    // destructor: no further call
  bool abandoned = false;  // a call outlived its deadline and is still in flight
  std::uint64_t step = 0;  // step of the last request
  std::string peer;        // provider node (set before the thread starts)
  std::thread worker;

  void run(std::shared_ptr<VehicleEnd> self_keepalive);
  Result send(const coupling::WheelStateFrame& frame);
  Result receive(coupling::WrenchFrame& frame, Deadline deadline);
  void close();
  std::string where() const { return "service " + service + " of " + nodeLabel(peer, Role::kTrack); }
};

void ServiceTransport::VehicleEnd::run(std::shared_ptr<VehicleEnd> self_keepalive) {
  (void)self_keepalive;  // keeps this object alive should the destructor leave the thread behind
  std::unique_lock<std::mutex> lock(m);
  for (;;) {
    cv.wait(lock, [&] { return phase == Phase::kRequested || phase == Phase::kCloseRequested || give_up; });
    if (give_up) break;
    if (phase == Phase::kRequested) {
      lock.unlock();
      const bool ok = client.call(srv);
      lock.lock();
      call_ok = ok;
      phase = Phase::kDone;
      abandoned = false;
      cv.notify_all();
      if (closed && !give_up) phase = Phase::kCloseRequested;  // close() came during the call
      continue;
    }
    // Close marker: tells the track the run is over (its receive() then returns kPeerClosed).
    makeCloseMarker(srv.request.states);
    lock.unlock();
    client.call(srv);
    lock.lock();
    break;
  }
  phase = Phase::kStopped;
  cv.notify_all();
}

Result ServiceTransport::VehicleEnd::send(const coupling::WheelStateFrame& frame) {
  std::lock_guard<std::mutex> lock(m);
  if (closed) return {Status::kError, "this end is closed"};
  if (abandoned)
    return {Status::kError, "the call of step " + std::to_string(step) + " on " + where() +
                                " is still in flight (it outlived its deadline)"};
  if (phase != Phase::kIdle)
    return {Status::kError, "send_states called again before receive_wrenches (step " + std::to_string(step) + ")"};
  Result r = toMessage(frame, srv.request.states);
  if (!r) return r;
  step = frame.step;
  phase = Phase::kRequested;
  cv.notify_all();
  return {};
}

Result ServiceTransport::VehicleEnd::receive(coupling::WrenchFrame& frame, Deadline deadline) {
  std::unique_lock<std::mutex> lock(m);
  if (closed) return {Status::kError, "this end is closed"};
  if (phase == Phase::kIdle) return {Status::kError, "receive_wrenches called without send_states"};
  for (;;) {
    if (phase == Phase::kDone) {
      phase = Phase::kIdle;
      if (!call_ok)
        return {Status::kPeerClosed, where() +
                                         ": the call failed, the connection was dropped (the node ended, "
                                         "closed or withdrew the service)"};
      if (!srv.response.ok) return {Status::kRefused, where() + " refused the call: " + srv.response.error};
      return fromMessage(srv.response.wrenches, o.track_step, frame, service.c_str());
    }
    if (phase != Phase::kRequested) return {Status::kError, "this end is closed"};
    Result r = interrupted(o.interrupt);
    if (!r) return r;
    if (Clock::now() >= deadline) {
      abandoned = true;
      return {Status::kTimeout, "no answer from " + where()};
    }
    cv.wait_until(lock, sliceEnd(deadline));
  }
}

void ServiceTransport::VehicleEnd::close() {
  std::lock_guard<std::mutex> lock(m);
  if (closed) return;
  closed = true;
  // A call in flight: the caller thread sends the marker once it returns; otherwise it sends it now.
  if (phase == Phase::kIdle || phase == Phase::kDone) phase = Phase::kCloseRequested;
  cv.notify_all();
}

// ---------------------------------------------------------------------------------------------------------
// Track end: the service callback runs on the spinner thread and waits there for the answer.
struct ServiceTransport::TrackEnd {
  enum class Phase {
    kNone,      // no call waiting
    kPending,   // a call waits; its states are not taken yet
    kTaken,     // receive_states() took the states; the call waits for send_wrenches()
    kAnswered,  // the response is filled; the callback returns it
  };

  ServiceTransportOptions o;
  std::string service;
  ros::CallbackQueue queue;
  ros::ServiceServer server;
  std::unique_ptr<ros::AsyncSpinner> spinner;
  std::mutex m;
  std::condition_variable cv;
  Phase phase = Phase::kNone;
  const rail_msgs::WheelStates* request = nullptr;  // valid while a call waits
  rail_msgs::Lockstep::Response* response = nullptr;
  std::uint64_t step = 0;       // step of the call taken last
  bool vehicle_closed = false;  // close marker received
  bool closed = false;
  bool withdrawn = false;                // the service was shut down
  std::string vehicle;                   // caller node of the last call
  const void* vehicle_header = nullptr;  // connection header of the vehicle's calls (identifies them without a lookup)
  long foreign_calls = 0;                // calls from a node that is not the handshake's peer, refused

  bool serve(ros::ServiceEvent<rail_msgs::Lockstep::Request, rail_msgs::Lockstep::Response>& event);
  Result receive(coupling::WheelStateFrame& frame, Deadline deadline);
  Result send(const coupling::WrenchFrame& frame);
  void close();
  std::string where() const { return "service " + service + ", caller " + nodeLabel(vehicle, Role::kVehicle); }
};

bool ServiceTransport::TrackEnd::serve(
    ros::ServiceEvent<rail_msgs::Lockstep::Request, rail_msgs::Lockstep::Response>& event) {
  const rail_msgs::Lockstep::Request& req = event.getRequest();
  rail_msgs::Lockstep::Response& res = event.getResponse();
  std::unique_lock<std::mutex> lock(m);
  // Calls count only from the handshake's peer: the connection header identifies it without a string lookup;
  // a call on another connection is looked up and refused (ok = false, frame not taken) if another node made it.
  const void* header = &event.getConnectionHeader();
  if (header != vehicle_header) {
    const std::string caller = event.getCallerName();
    if (!o.peer_node.empty() && caller != o.peer_node) {
      if (foreign_calls++ == 0) {
        ROS_WARN("service %s: a call from node %s, not this run's vehicle %s, was refused", service.c_str(),
                 caller.c_str(), o.peer_node.c_str());
      }
      res.ok = false;
      res.error = "node " + caller + " is not this run's vehicle (" + o.peer_node + "): its frame was not used";
      return true;
    }
    vehicle_header = header;
    if (vehicle.empty()) vehicle = caller;
  }
  if (closed) {
    res.ok = false;
    res.error = "the track closed the connection";
    return true;
  }
  if (isCloseMarker(req.states)) {
    vehicle_closed = true;
    cv.notify_all();
    res.ok = true;
    return true;
  }
  if (phase != Phase::kNone) {  // cannot happen with one spinner thread; answered rather than queued
    res.ok = false;
    res.error = "the track is still answering another call";
    return true;
  }
  request = &req.states;
  response = &res;
  phase = Phase::kPending;
  cv.notify_all();
  const Deadline give_up = after(o.reply_timeout);
  while (phase != Phase::kAnswered && !closed && Clock::now() < give_up) cv.wait_until(lock, give_up);
  if (phase != Phase::kAnswered) {
    res.ok = false;
    res.error = closed ? "the track closed the connection"
                       : "the track gave no answer within " + formatNumber(o.reply_timeout) + " s (reply_timeout)";
  }
  request = nullptr;
  response = nullptr;
  phase = Phase::kNone;
  cv.notify_all();
  return true;
}

Result ServiceTransport::TrackEnd::receive(coupling::WheelStateFrame& frame, Deadline deadline) {
  std::unique_lock<std::mutex> lock(m);
  if (closed) return {Status::kError, "this end is closed"};
  if (phase == Phase::kTaken)
    return {Status::kError, "receive_states called again before send_wrenches (step " + std::to_string(step) + ")"};
  for (;;) {
    if (phase == Phase::kPending) {
      Result r = fromMessage(*request, o.track_step, frame, service.c_str());
      if (!r) {  // the vehicle hears of it in the answer
        response->ok = false;
        response->error = r.message;
        phase = Phase::kAnswered;
        cv.notify_all();
        return r;
      }
      step = frame.step;
      phase = Phase::kTaken;
      return {};
    }
    if (vehicle_closed)
      return {Status::kPeerClosed, nodeLabel(vehicle, Role::kVehicle) + " sent its close marker on service " + service};
    Result r = interrupted(o.interrupt);
    if (!r) return r;
    if (Clock::now() >= deadline) return {Status::kTimeout, "no call on " + where()};
    cv.wait_until(lock, sliceEnd(deadline));
  }
}

Result ServiceTransport::TrackEnd::send(const coupling::WrenchFrame& frame) {
  std::lock_guard<std::mutex> lock(m);
  if (closed) return {Status::kError, "this end is closed"};
  if (phase != Phase::kTaken) {
    if (phase == Phase::kNone)
      return {Status::kTimeout, "the call of step " + std::to_string(step) + " on " + where() +
                                    " stopped waiting for its answer (reply_timeout " + formatNumber(o.reply_timeout) +
                                    " s)"};
    return {Status::kError, "send_wrenches called without receive_states"};
  }
  Result r = toMessage(frame, response->wrenches);
  if (!r) {
    response->ok = false;
    response->error = "the track could not answer: " + r.message;
  } else {
    response->ok = true;
  }
  phase = Phase::kAnswered;
  cv.notify_all();
  return r;
}

void ServiceTransport::TrackEnd::close() {
  {
    std::lock_guard<std::mutex> lock(m);
    if (closed) return;
    closed = true;
    cv.notify_all();  // a waiting callback answers "closed" at once
  }
  // Withdrawing the service drops the vehicle's persistent connection: its call fails at once.
  server.shutdown();
}

// ---------------------------------------------------------------------------------------------------------
ServiceTransport::ServiceTransport(ros::NodeHandle& nh, const ServiceTransportOptions& options) : role_(options.role) {
  checkOptions(options, "service transport");
  if (!(options.reply_timeout > 0.0))
    throw std::runtime_error("service transport: reply_timeout must be > 0 s (got " +
                             formatNumber(options.reply_timeout) + ")");
  const std::string service = nh.resolveName(options.service);
  if (role_ == Role::kVehicle) {
    auto v = std::make_shared<VehicleEnd>();
    v->o = options;
    v->service = service;
    reserveMessage(v->srv.request.states, options.wheel_capacity);
    reserveMessage(v->srv.response.wrenches, options.wheel_capacity);
    // Wait for the service (polled quietly every 20 ms, so that an interrupt ends the wait).
    const Deadline deadline = after(options.attach_timeout);
    for (;;) {
      if (ros::service::exists(service, /*print_failure_reason=*/false)) break;
      if (!interrupted(options.interrupt))
        throw coupling::CouplingError(Status::kInterrupted,
                                      "vehicle: interrupted while waiting for service " + service);
      if (Clock::now() >= deadline)
        throw coupling::CouplingError(Status::kTimeout,
                                      "vehicle: the track's service " + service + " did not appear within " +
                                          formatNumber(options.attach_timeout) + " s (solver.handshake_timeout)");
      std::this_thread::sleep_for(detail::kSlice);
    }
    v->peer = options.peer_node.empty() ? detail::serviceProvider(service) : options.peer_node;
    v->client = nh.serviceClient<rail_msgs::Lockstep>(service, /*persistent=*/true);
    v->worker = std::thread(&VehicleEnd::run, v.get(), v);
    vehicle_ = std::move(v);
  } else {
    auto t = std::make_unique<TrackEnd>();
    t->o = options;
    t->service = service;
    t->vehicle = options.peer_node;
    ros::AdvertiseServiceOptions ops;
    TrackEnd* raw = t.get();
    ops.initBySpecType<ros::ServiceEvent<rail_msgs::Lockstep::Request, rail_msgs::Lockstep::Response>>(
        service, [raw](ros::ServiceEvent<rail_msgs::Lockstep::Request, rail_msgs::Lockstep::Response>& e) {
          return raw->serve(e);
        });
    ops.callback_queue = &t->queue;
    t->server = nh.advertiseService(ops);
    if (!t->server) throw coupling::CouplingError(Status::kError, "track: could not advertise service " + service);
    t->spinner = std::make_unique<ros::AsyncSpinner>(1, &t->queue);
    t->spinner->start();
    track_ = std::move(t);
  }
}

ServiceTransport::~ServiceTransport() {
  close();
  if (vehicle_) {
    std::shared_ptr<VehicleEnd> v = vehicle_;
    std::unique_lock<std::mutex> lock(v->m);
    // The close marker normally goes out within a round trip; a track that hangs gets its connection dropped.
    if (!v->cv.wait_until(lock, after(kJoinWait), [&] { return v->phase == VehicleEnd::Phase::kStopped; })) {
      v->give_up = true;
      v->cv.notify_all();
      lock.unlock();
      v->client.shutdown();  // the call in flight has long since started: this ends it
      lock.lock();
    }
    const bool stopped =
        v->cv.wait_until(lock, after(kJoinWait), [&] { return v->phase == VehicleEnd::Phase::kStopped; });
    lock.unlock();
    if (stopped)
      v->worker.join();
    else
      v->worker.detach();  // it holds its own reference to the state; ros::shutdown() will end its call
  }
  if (track_) track_->spinner->stop();  // close() made any waiting callback return
}

Role ServiceTransport::role() const { return role_; }

Result ServiceTransport::sendStates(const coupling::WheelStateFrame& frame, Deadline) {
  if (!vehicle_) return detail::wrongRole(role_, "send_states");
  return vehicle_->send(frame);
}

Result ServiceTransport::receiveWrenches(coupling::WrenchFrame& frame, Deadline deadline) {
  if (!vehicle_) return detail::wrongRole(role_, "receive_wrenches");
  return vehicle_->receive(frame, deadline);
}

Result ServiceTransport::receiveStates(coupling::WheelStateFrame& frame, Deadline deadline) {
  if (!track_) return detail::wrongRole(role_, "receive_states");
  return track_->receive(frame, deadline);
}

Result ServiceTransport::sendWrenches(const coupling::WrenchFrame& frame, Deadline) {
  if (!track_) return detail::wrongRole(role_, "send_wrenches");
  return track_->send(frame);
}

void ServiceTransport::close() {
  if (vehicle_) vehicle_->close();
  if (track_) track_->close();
}

const std::string& ServiceTransport::serviceName() const { return vehicle_ ? vehicle_->service : track_->service; }

std::string ServiceTransport::peerNode() const {
  if (vehicle_) return vehicle_->peer;
  std::lock_guard<std::mutex> lock(track_->m);
  return track_->vehicle;
}

}  // namespace rail::ros_glue
