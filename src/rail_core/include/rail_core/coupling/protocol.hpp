// The co-simulation communication protocol (paper section 5.3, Figure 14), one object per node, advanced
// by the caller. The vehicle (variable step, never larger than the track step h) leads; the track (fixed
// step h) follows. Track step k belongs to t_k = k h, k = 0, 1, 2, ...
//
//   vehicle                                        track
//   integrates to t >= t_k with the wrenches       waits for the states of step k
//   extrapolated from steps k-2, k-1
//   interpolates the wheel states at t_k,
//   exchange(): sends them and waits        --->   receive(): hands them to the caller, who evaluates the
//                                                  contact of step k and advances the track
//   receives the wrenches of step k         <---   send(): returns the wrenches of step k
//
// The first exchange is step 0 at t = 0, made with the initial states before the vehicle integrates, so
// the vehicle never integrates without a wrench from the track: on [t_0, t_1] it uses the step-0 wrench
// held constant, from t_1 on the linear extrapolation of the last two steps. Each side checks every frame
// it receives: step index (no step skipped or repeated), time, wheel count and scene hash.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "rail_core/coupling/frames.hpp"
#include "rail_core/coupling/transport.hpp"
#include "rail_core/scene.hpp"

namespace rail::core::coupling {

struct CouplingConfig {
  double track_step = 0.0;         // h, the track's fixed step [s], > 0
  double exchange_timeout = 10.0;  // longest wait for the peer in one exchange [s], > 0
  std::uint64_t scene_hash = 0;    // stamped on and required in every frame
  int wheel_count = 0;             // N wheels per frame, > 0
};
// From solver.track_step, solver.exchange_timeout, the scene hash and wheel count.
CouplingConfig couplingConfig(const Scene& scene);

// Vehicle side: keeps the last two wrench frames and extrapolates them.
class VehicleCoupling {
 public:
  // Throws std::runtime_error for a non-physical config. The transport must outlive this object.
  VehicleCoupling(const CouplingConfig& config, FrameTransport& transport);

  std::uint64_t nextStep() const { return next_step_; }  // k of the next exchange
  double nextExchangeTime() const;                       // t_k = k h [s]
  // Whether the vehicle, at time t [s], has reached the next exchange (t >= t_k up to 1e-9 h).
  bool exchangeDue(double t) const;

  // The outgoing frame: fill wheels[0 .. wheel_count) with the states interpolated at
  // nextExchangeTime(); exchange() stamps step, time, scene hash and count.
  WheelStateFrame& states() { return states_; }
  // Send the states of step k and wait (up to exchange_timeout, or `deadline`) for the wrenches of step
  // k. On failure the message names this side, the peer and the step; the coupling then stays failed.
  Result exchange();
  Result exchange(Deadline deadline);

  // Wrench frames received so far, saturated at 2.
  int framesReceived() const { return frames_; }
  // Wrench of wheel i at time t [s] (world frame, about the wheel centre): with two frames the line
  // through (t_{k-1}, W_{k-1}) and (t_k, W_k) evaluated at t; with one frame W_0; with none zero.
  // Exact for a wrench history linear in time; for a smooth one the error is
  // W''/2 (t - t_k)(t - t_{k-1}), O(h^2) for t in [t_k, t_k + h].
  void wrenchAt(double t, int i, Eigen::Vector3d& f_wheel_in_world, Eigen::Vector3d& n_wheel_in_world) const;
  // All wheels at time t into `out` (capacity >= wheel_count); out is stamped with t and the last step.
  void extrapolate(double t, WrenchFrame& out) const;
  // The last frame received (W_k); empty stamp before the first exchange.
  const WrenchFrame& lastWrenches() const { return *last_; }

  void close() { transport_.close(); }

 private:
  Result exchangeUntil(Deadline deadline, bool default_deadline);

  CouplingConfig config_;
  FrameTransport& transport_;
  WheelStateFrame states_;
  WrenchFrame buffers_[3];                // previous, last, incoming (rotated by pointer)
  WrenchFrame* previous_ = &buffers_[0];  // W_{k-1}
  WrenchFrame* last_ = &buffers_[1];      // W_k
  WrenchFrame* incoming_ = &buffers_[2];
  std::uint64_t next_step_ = 0;
  int frames_ = 0;
  bool failed_ = false;
};

// Track side: receives the states of each step in order, returns the wrenches.
class TrackCoupling {
 public:
  TrackCoupling(const CouplingConfig& config, FrameTransport& transport);

  std::uint64_t nextStep() const { return next_step_; }  // step receive() waits for
  double nextTime() const;                               // its time k h [s]

  // Wait (up to exchange_timeout, or `deadline`) for the states of the next step and check them.
  Result receive();
  Result receive(Deadline deadline);
  // The states received last (valid after receive() succeeded).
  const WheelStateFrame& states() const { return states_; }
  // The outgoing frame for the step received last: fill wheels[0 .. wheel_count); send() stamps it.
  WrenchFrame& wrenches() { return wrenches_; }
  // Send the wrenches of the step received last (must follow a successful receive()).
  Result send();
  Result send(Deadline deadline);

  void close() { transport_.close(); }

 private:
  Result receiveUntil(Deadline deadline, bool default_deadline);
  Result sendUntil(Deadline deadline, bool default_deadline);

  CouplingConfig config_;
  FrameTransport& transport_;
  WheelStateFrame states_;
  WheelStateFrame incoming_;
  WrenchFrame wrenches_;
  std::uint64_t next_step_ = 0;
  bool awaiting_send_ = false;
  bool failed_ = false;
};

}  // namespace rail::core::coupling
