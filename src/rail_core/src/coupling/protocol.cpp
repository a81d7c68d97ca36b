#include "rail_core/coupling/protocol.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include <rail_contact/format.hpp>

#include "rail_core/scene_loader.hpp"

namespace rail::core::coupling {

using contact::formatNumber;

namespace {

std::string hex(std::uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(v));
  return buf;
}
std::string u64(std::uint64_t v) { return std::to_string(v); }

void checkConfig(const CouplingConfig& c) {
  if (const std::string why = trackStepRule(c.track_step); !why.empty())
    throw std::runtime_error("coupling: solver.track_step " + why);
  if (!(c.exchange_timeout > 0.0) || !std::isfinite(c.exchange_timeout))
    throw std::runtime_error("coupling: solver.exchange_timeout must be > 0 s (got " +
                             formatNumber(c.exchange_timeout) + ")");
  if (c.wheel_count <= 0)
    throw std::runtime_error("coupling: wheel count must be > 0 (got " + std::to_string(c.wheel_count) + ")");
}

// A frame's header for step k of this run: its time k h, the scene hash and the wheel count.
template <class Frame>
void stamp(Frame& frame, std::uint64_t k, const CouplingConfig& c) {
  frame.step = k;
  frame.time = static_cast<double>(k) * c.track_step;
  frame.scene_hash = c.scene_hash;
  frame.count = static_cast<std::uint32_t>(c.wheel_count);
}

Deadline deadlineAfter(double seconds) {
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

// The time a wait was given, for messages.
struct Budget {
  double seconds;
  bool is_exchange_timeout;
};
Budget budgetUntil(Deadline deadline, const CouplingConfig& c, bool is_default) {
  if (is_default) return {c.exchange_timeout, true};
  return {std::chrono::duration<double>(deadline - Clock::now()).count(), false};
}

// "<role>: <doing> step <k>: <what happened>[ (<detail>)]"
Result fail(const Result& r, Role self, const char* doing, std::uint64_t step, const Budget& budget) {
  const char* peer = toString(peerOf(self));
  std::string what;
  switch (r.status) {
    case Status::kTimeout:
      what = std::string("the ") + peer + " did not answer within " + formatNumber(budget.seconds) + " s" +
             (budget.is_exchange_timeout ? " (solver.exchange_timeout)" : "");
      break;
    case Status::kPeerClosed:
      what = std::string("the ") + peer + " closed the connection";
      break;
    case Status::kInterrupted:
      what = "interrupted";
      break;
    default:
      what = toString(r.status);
      break;
  }
  std::string msg = std::string(toString(self)) + ": " + doing + " step " + u64(step) + ": " + what;
  if (!r.message.empty()) msg += " (" + r.message + ")";
  return {r.status, msg};
}

// Check a received stamp against the expected step, its time, the wheel count and the scene hash. `what`
// names the frame. Messages are only built on a refusal.
Result checkStamp(const FrameStamp& got, std::uint32_t count, const CouplingConfig& c, std::uint64_t step, Role self,
                  const char* what) {
  const double t = static_cast<double>(step) * c.track_step;
  const bool hash_ok = got.scene_hash == c.scene_hash;
  const bool step_ok = got.step == step;
  const bool time_ok = std::abs(got.time - t) <= 1e-9 * c.track_step;
  const bool count_ok = count == static_cast<std::uint32_t>(c.wheel_count);
  if (hash_ok && step_ok && time_ok && count_ok) return {};

  std::string msg = std::string(toString(self)) + ": " + what + " from the " + toString(peerOf(self)) +
                    " refused at step " + u64(step) + ": ";
  if (!hash_ok) {
    msg += "scene hash " + hex(got.scene_hash) + " received, " + hex(c.scene_hash) + " expected";
  } else if (!step_ok) {
    const char* kind =
        got.step > step ? "step skipped" : (got.step + 1 == step ? "step repeated" : "step out of order");
    msg += "step " + u64(got.step) + " received, " + u64(step) + " expected (" + kind + ")";
  } else if (!time_ok) {
    msg += "time " + formatNumber(got.time) + " s received, " + formatNumber(t) + " s expected (step " + u64(step) +
           " x track_step " + formatNumber(c.track_step) + " s)";
  } else {
    msg += std::to_string(count) + " wheels received, " + std::to_string(c.wheel_count) + " expected";
  }
  return {Status::kRefused, msg};
}

Result alreadyFailed(Role self) {
  return {Status::kError, std::string(toString(self)) + ": the coupling failed earlier; no further exchange"};
}

}  // namespace

CouplingConfig couplingConfig(const Scene& scene) {
  CouplingConfig c;
  c.track_step = scene.solver.track_step;
  c.exchange_timeout = scene.solver.exchange_timeout;
  c.scene_hash = scene.hash;
  c.wheel_count = scene.wheelCount();
  return c;
}

// ---------------------------------------------------------------------------------------------------------
VehicleCoupling::VehicleCoupling(const CouplingConfig& config, FrameTransport& transport)
    : config_((checkConfig(config), config)),
      transport_(transport),
      states_(config.wheel_count),
      buffers_{WrenchFrame(config.wheel_count), WrenchFrame(config.wheel_count), WrenchFrame(config.wheel_count)} {
  states_.count = static_cast<std::uint32_t>(config.wheel_count);
  for (int i = 0; i < config.wheel_count; ++i) states_.wheels[i].id = static_cast<std::uint32_t>(i);
  for (WrenchFrame& b : buffers_) {
    b.count = static_cast<std::uint32_t>(config.wheel_count);
    for (int i = 0; i < config.wheel_count; ++i) b.wheels[i].id = static_cast<std::uint32_t>(i);
  }
}

double VehicleCoupling::nextExchangeTime() const { return static_cast<double>(next_step_) * config_.track_step; }

bool VehicleCoupling::exchangeDue(double t) const { return t >= nextExchangeTime() - 1e-9 * config_.track_step; }

Result VehicleCoupling::exchange() { return exchangeUntil(deadlineAfter(config_.exchange_timeout), true); }
Result VehicleCoupling::exchange(Deadline deadline) { return exchangeUntil(deadline, false); }

Result VehicleCoupling::exchangeUntil(Deadline deadline, bool default_deadline) {
  if (failed_) return alreadyFailed(Role::kVehicle);
  const Budget budget = budgetUntil(deadline, config_, default_deadline);
  const std::uint64_t k = next_step_;
  stamp(states_, k, config_);
  if (Result r = transport_.sendStates(states_, deadline); !r) {
    failed_ = true;
    return fail(r, Role::kVehicle, "sending the wheel states of", k, budget);
  }
  Result r = transport_.receiveWrenches(*incoming_, deadline);
  if (!r) {
    failed_ = true;
    return fail(r, Role::kVehicle, "waiting for the contact wrenches of", k, budget);
  }
  r = checkStamp(*incoming_, incoming_->count, config_, k, Role::kVehicle, "contact wrenches");
  if (!r) {
    failed_ = true;
    return r;
  }
  WrenchFrame* oldest = previous_;
  previous_ = last_;
  last_ = incoming_;
  incoming_ = oldest;
  if (frames_ < 2) ++frames_;
  ++next_step_;
  return {};
}

void VehicleCoupling::wrenchAt(double t, int i, Eigen::Vector3d& f, Eigen::Vector3d& n) const {
  if (frames_ == 0) {
    f.setZero();
    n.setZero();
    return;
  }
  const WheelWrench& wk = last_->wheels[i];
  if (frames_ == 1) {
    f = wk.f_wheel_in_world;
    n = wk.n_wheel_in_world;
    return;
  }
  // Linear extrapolation through (t_{k-1}, W_{k-1}) and (t_k, W_k): W_k + theta (W_k - W_{k-1}).
  const WheelWrench& wp = previous_->wheels[i];
  const double theta = (t - last_->time) / (last_->time - previous_->time);
  f = wk.f_wheel_in_world + theta * (wk.f_wheel_in_world - wp.f_wheel_in_world);
  n = wk.n_wheel_in_world + theta * (wk.n_wheel_in_world - wp.n_wheel_in_world);
}

void VehicleCoupling::extrapolate(double t, WrenchFrame& out) const {
  out.step = last_->step;
  out.time = t;
  out.scene_hash = config_.scene_hash;
  out.count = static_cast<std::uint32_t>(config_.wheel_count);
  for (int i = 0; i < config_.wheel_count; ++i) {
    out.wheels[i].id = last_->wheels[i].id;
    wrenchAt(t, i, out.wheels[i].f_wheel_in_world, out.wheels[i].n_wheel_in_world);
  }
}

// ---------------------------------------------------------------------------------------------------------
TrackCoupling::TrackCoupling(const CouplingConfig& config, FrameTransport& transport)
    : config_((checkConfig(config), config)),
      transport_(transport),
      states_(config.wheel_count),
      incoming_(config.wheel_count),
      wrenches_(config.wheel_count) {
  wrenches_.count = static_cast<std::uint32_t>(config.wheel_count);
  for (int i = 0; i < config.wheel_count; ++i) wrenches_.wheels[i].id = static_cast<std::uint32_t>(i);
}

double TrackCoupling::nextTime() const { return static_cast<double>(next_step_) * config_.track_step; }

Result TrackCoupling::receive() { return receiveUntil(deadlineAfter(config_.exchange_timeout), true); }
Result TrackCoupling::receive(Deadline deadline) { return receiveUntil(deadline, false); }

Result TrackCoupling::receiveUntil(Deadline deadline, bool default_deadline) {
  if (failed_) return alreadyFailed(Role::kTrack);
  const Budget budget = budgetUntil(deadline, config_, default_deadline);
  if (awaiting_send_)
    return {Status::kError,
            "track: receive() called twice for step " + u64(next_step_ - 1) + " without send() in between"};
  const std::uint64_t k = next_step_;
  Result r = transport_.receiveStates(incoming_, deadline);
  if (!r) {
    failed_ = true;
    return fail(r, Role::kTrack, "waiting for the wheel states of", k, budget);
  }
  r = checkStamp(incoming_, incoming_.count, config_, k, Role::kTrack, "wheel states");
  if (!r) {
    failed_ = true;
    return r;
  }
  std::swap(states_, incoming_);  // swaps the vectors' buffers: no allocation
  awaiting_send_ = true;
  ++next_step_;
  return {};
}

Result TrackCoupling::send() { return sendUntil(deadlineAfter(config_.exchange_timeout), true); }
Result TrackCoupling::send(Deadline deadline) { return sendUntil(deadline, false); }

Result TrackCoupling::sendUntil(Deadline deadline, bool default_deadline) {
  if (failed_) return alreadyFailed(Role::kTrack);
  const Budget budget = budgetUntil(deadline, config_, default_deadline);
  if (!awaiting_send_) return {Status::kError, "track: send() called before receive() for step " + u64(next_step_)};
  const std::uint64_t k = states_.step;
  stamp(wrenches_, k, config_);
  if (Result r = transport_.sendWrenches(wrenches_, deadline); !r) {
    failed_ = true;
    return fail(r, Role::kTrack, "sending the contact wrenches of", k, budget);
  }
  awaiting_send_ = false;
  return {};
}

}  // namespace rail::core::coupling
