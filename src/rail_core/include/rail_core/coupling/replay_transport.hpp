// The track end of a replay: wheel states recorded by an earlier run (at its output.rate) drive the track
// side alone. The recorded states are interpolated to each track step t_k = k h (positions, velocities,
// angular velocities and arc lengths linearly; orientations by slerp) and handed to the track as the
// vehicle's frames, stamped with this scene's hash; the wrenches go nowhere. ROS-free: the caller reads the
// recording (rail_ros/replay_bag.hpp reads a bag's /wheel_states).
#pragma once

#include <string>
#include <vector>

#include "rail_core/coupling/transport.hpp"

namespace rail::core::coupling {

// One recorded run: frames[i] at times[i] [s], strictly increasing, the first at t = 0.
struct RecordedStates {
  std::string source;  // where it was read from, for messages (e.g. the bag's path)
  std::vector<double> times;
  std::vector<WheelStateFrame> frames;
};

class ReplayTransport final : public FrameTransport {
 public:
  // track_step: h [s]; scene_hash: stamped on every frame; t_end: the scene's end time (replays stop at the
  // earlier of it and the recording's last instant; <= 0: the recording's). Throws std::runtime_error
  // naming recording.source when it has fewer than two instants, does not start at t = 0 (within h / 2),
  // its times do not increase or its frames differ in wheel count.
  ReplayTransport(RecordedStates recording, double track_step, std::uint64_t scene_hash, double t_end);

  double endTime() const { return t_stop_; }
  // First to last wheel centre along the track in the recording's first frame [m]: the recorded vehicle's
  // wheel span, which the track sizes its window by.
  double wheelSpan() const;
  int wheelCount() const { return static_cast<int>(recording_.frames.front().count); }

  Role role() const override { return Role::kTrack; }
  // States of the next step k, interpolated at k h; kPeerClosed after the recording's last instant.
  Result receiveStates(WheelStateFrame& out, Deadline deadline) override;
  // The wrenches are dropped.
  Result sendWrenches(const WrenchFrame& frame, Deadline deadline) override;
  Result sendStates(const WheelStateFrame& frame, Deadline deadline) override;  // kError: not this end's
  Result receiveWrenches(WrenchFrame& frame, Deadline deadline) override;       // kError: not this end's
  void close() override {}

 private:
  RecordedStates recording_;
  double h_;
  std::uint64_t hash_;
  double t_stop_ = 0.0;
  std::size_t segment_ = 0;  // recording interval [times[segment_], times[segment_ + 1]] of the last step
  std::uint64_t step_ = 0;
};

}  // namespace rail::core::coupling
