// Synthetic vehicle and track for the transport tests (test_cosim_transports and transport_track_peer):
// the vehicle's wheel states follow a known g(t), the track answers a known f(step, states), so each side
// can check every frame it receives exactly, and the vehicle's extrapolated wrenches can be compared across
// transports. Also the transports the two programs build from the same settings.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include <ros/node_handle.h>

#include "rail_core/coupling/frames.hpp"
#include "rail_core/coupling/protocol.hpp"
#include "rail_core/coupling/shm_transport.hpp"
#include "rail_ros/service_transport.hpp"
#include "rail_ros/topic_transport.hpp"

namespace railsim_test {

constexpr int kWheels = 8;
constexpr double kTrackStep = 1e-4;  // h [s]
constexpr std::uint64_t kSceneHash = 0x5eedc0ffee000001ull;
constexpr double kSpeed = 30.0;        // V [m/s]
constexpr double kWheelRadius = 0.46;  // [m]
constexpr double kPi = 3.14159265358979323846;

inline rail::core::coupling::CouplingConfig config(double exchange_timeout) {
  rail::core::coupling::CouplingConfig c;
  c.track_step = kTrackStep;
  c.exchange_timeout = exchange_timeout;
  c.scene_hash = kSceneHash;
  c.wheel_count = kWheels;
  return c;
}

// g(t): wheel centre i (wheelset i/2, side i%2) rolling at V along x, bouncing 1 mm at 7 Hz.
inline void wheelStateAt(double t, int i, rail::core::coupling::WheelState& w) {
  const double x0 = 20.0 - 2.5 * (i / 2);
  const double y = (i % 2) ? -0.75 : 0.75;
  const double phase = 2.0 * kPi * 7.0 * t + 0.3 * i;
  const double spin = kSpeed * t / kWheelRadius;  // rolling angle [rad]
  w.id = static_cast<std::uint32_t>(i);
  w.arc_length = x0 + kSpeed * t;
  w.p_wheel_in_world = Eigen::Vector3d(x0 + kSpeed * t, y, kWheelRadius + 1e-3 * std::sin(phase));
  w.R_wheelset_to_world = Eigen::Quaterniond(std::cos(0.5 * spin), 0.0, std::sin(0.5 * spin), 0.0).toRotationMatrix();
  w.v_wheel_in_world = Eigen::Vector3d(kSpeed, 0.0, 1e-3 * 2.0 * kPi * 7.0 * std::cos(phase));
  w.omega_wheelset_in_world = Eigen::Vector3d(0.0, kSpeed / kWheelRadius, 0.0);
}

// f(step, state): the wrench the synthetic track returns for one wheel.
inline void wrenchFor(std::uint64_t step, const rail::core::coupling::WheelState& s,
                      rail::core::coupling::WheelWrench& w) {
  const double k = static_cast<double>(step);
  w.id = s.id;
  w.f_wheel_in_world = Eigen::Vector3d(
      -1e3 * s.p_wheel_in_world.y() + 2e3 * std::sin(0.01 * k + s.id), 5e2 * s.R_wheelset_to_world(0, 2),
      8e4 + 1e8 * (s.p_wheel_in_world.z() - kWheelRadius) + 10.0 * s.v_wheel_in_world.z());
  w.n_wheel_in_world = Eigen::Vector3d(1e-2 * s.arc_length, 0.5 * s.omega_wheelset_in_world.y(), 1e-3 * k);
}

// A wheel state as the peer receives it: the wire carries R_wheelset_to_world as a unit quaternion
// (frames.hpp); every other field is copied.
inline rail::core::coupling::WheelState throughWire(rail::core::coupling::WheelState w) {
  w.R_wheelset_to_world =
      rail::core::coupling::orientationFromWire(rail::core::coupling::wireOrientation(w.R_wheelset_to_world));
  return w;
}

// Whether `received` is `sent` bit for bit after the wire (the transports copy doubles; the only computation
// is the orientation's quaternion form, the same code on both sides).
inline bool same(const rail::core::coupling::WheelState& received, const rail::core::coupling::WheelState& sent) {
  const rail::core::coupling::WheelState b = throughWire(sent);
  return received.id == b.id && received.arc_length == b.arc_length &&
         received.p_wheel_in_world == b.p_wheel_in_world && received.R_wheelset_to_world == b.R_wheelset_to_world &&
         received.v_wheel_in_world == b.v_wheel_in_world &&
         received.omega_wheelset_in_world == b.omega_wheelset_in_world;
}

// Names one run uses (a prefix of its own, so that a killed node's registrations do not disturb the next).
struct RunNames {
  std::string prefix;  // "/cosim_<run>"
  std::string run_id;  // shm run id
};

// The transport `kind` (service, topic, shm) for `role`.
inline std::unique_ptr<rail::core::coupling::FrameTransport> makeTransport(const std::string& kind,
                                                                           rail::core::coupling::Role role,
                                                                           const RunNames& names, ros::NodeHandle& nh,
                                                                           const std::string& peer_node) {
  using namespace rail::core;
  namespace ros_glue = rail::ros_glue;
  if (kind == "shm") {
    coupling::ShmOptions o;
    o.role = role;
    o.scene_hash = kSceneHash;
    o.wheel_capacity = kWheels;
    o.run_id = names.run_id;
    o.name_prefix = "railsimtest";
    return std::make_unique<coupling::ShmTransport>(o);
  }
  if (kind == "service") {
    ros_glue::ServiceTransportOptions o;
    o.role = role;
    o.track_step = kTrackStep;
    o.wheel_capacity = kWheels;
    o.peer_node = peer_node;
    o.service = names.prefix + "/lockstep";
    return std::make_unique<ros_glue::ServiceTransport>(nh, o);
  }
  if (kind == "topic") {
    ros_glue::TopicTransportOptions o;
    o.role = role;
    o.track_step = kTrackStep;
    o.wheel_capacity = kWheels;
    o.peer_node = peer_node;
    o.states_topic = names.prefix + "/wheel_states_exchange";
    o.wrenches_topic = names.prefix + "/contact_wrenches_exchange";
    return std::make_unique<ros_glue::TopicTransport>(nh, o);
  }
  throw std::runtime_error("unknown transport '" + kind + "' (service, topic or shm)");
}

}  // namespace railsim_test
