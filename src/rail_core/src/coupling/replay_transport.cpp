#include "rail_core/coupling/replay_transport.hpp"

#include <algorithm>
#include <stdexcept>

#include <rail_contact/format.hpp>

namespace rail::core::coupling {

using contact::formatNumber;

ReplayTransport::ReplayTransport(RecordedStates recording, double track_step, std::uint64_t scene_hash, double t_end)
    : recording_(std::move(recording)), h_(track_step), hash_(scene_hash) {
  const std::string& src = recording_.source;
  if (recording_.frames.size() != recording_.times.size()) {
    throw std::runtime_error(src + ": the recording's times and frames differ in number");
  }
  if (recording_.frames.empty()) throw std::runtime_error(src + ": no wheel states recorded (needed to replay a run)");
  if (recording_.frames.size() < 2)
    throw std::runtime_error(src + ": the wheel states have one instant; a replay needs two");
  if (recording_.times.front() > 0.5 * h_) {
    throw std::runtime_error(src + ": the wheel states start at t = " + formatNumber(recording_.times.front()) +
                             " s; a replay starts at t = 0");
  }
  for (std::size_t i = 1; i < recording_.times.size(); ++i) {
    if (!(recording_.times[i] > recording_.times[i - 1])) {
      throw std::runtime_error(
          src + ": the wheel states' times do not increase at t = " + formatNumber(recording_.times[i]) + " s");
    }
    if (recording_.frames[i].count != recording_.frames[0].count) {
      throw std::runtime_error(src + ": the wheel states at t = " + formatNumber(recording_.times[i]) + " s have " +
                               std::to_string(recording_.frames[i].count) + " wheels, the first " +
                               std::to_string(recording_.frames[0].count));
    }
  }
  t_stop_ = t_end > 0.0 ? std::min(recording_.times.back(), t_end) : recording_.times.back();
}

double ReplayTransport::wheelSpan() const {
  const WheelStateFrame& first = recording_.frames.front();
  double lo = first.wheels.front().arc_length, hi = lo;
  for (std::uint32_t i = 0; i < first.count; ++i) {
    lo = std::min(lo, first.wheels[i].arc_length);
    hi = std::max(hi, first.wheels[i].arc_length);
  }
  return hi - lo;
}

Result ReplayTransport::receiveStates(WheelStateFrame& out, Deadline) {
  const double t = static_cast<double>(step_) * h_;
  if (t > t_stop_ + 1e-9 * h_) return {Status::kPeerClosed, "end of the replayed run"};
  const std::vector<double>& times = recording_.times;
  while (segment_ + 2 < times.size() && times[segment_ + 1] < t) ++segment_;
  const double t0 = times[segment_], t1 = times[segment_ + 1];
  const double a = std::min(1.0, std::max(0.0, (t - t0) / (t1 - t0)));
  const WheelStateFrame& f0 = recording_.frames[segment_];
  const WheelStateFrame& f1 = recording_.frames[segment_ + 1];
  if (static_cast<int>(f0.count) > out.capacity()) {
    return {Status::kRefused, "replay: a recorded frame has more wheels than the track takes"};
  }
  out.count = f0.count;
  for (std::uint32_t i = 0; i < f0.count; ++i) {
    const WheelState& w0 = f0.wheels[i];
    const WheelState& w1 = f1.wheels[i];
    WheelState& o = out.wheels[i];
    o.id = w0.id;
    o.arc_length = (1 - a) * w0.arc_length + a * w1.arc_length;
    o.p_wheel_in_world = (1 - a) * w0.p_wheel_in_world + a * w1.p_wheel_in_world;
    o.R_wheelset_to_world =
        orientationFromWire(wireOrientation(w0.R_wheelset_to_world).slerp(a, wireOrientation(w1.R_wheelset_to_world)));
    o.v_wheel_in_world = (1 - a) * w0.v_wheel_in_world + a * w1.v_wheel_in_world;
    o.omega_wheelset_in_world = (1 - a) * w0.omega_wheelset_in_world + a * w1.omega_wheelset_in_world;
  }
  out.step = step_;
  out.time = t;
  out.scene_hash = hash_;
  ++step_;
  return {};
}

Result ReplayTransport::sendWrenches(const WrenchFrame&, Deadline) { return {}; }

Result ReplayTransport::sendStates(const WheelStateFrame&, Deadline) {
  return {Status::kError, "replay: the track end does not send states"};
}

Result ReplayTransport::receiveWrenches(WrenchFrame&, Deadline) {
  return {Status::kError, "replay: the track end does not receive wrenches"};
}

}  // namespace rail::core::coupling
