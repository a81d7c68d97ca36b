// The track side's run loop of a co-simulation, the counterpart of rail_vehicle_node's CosimVehicle: each
// step() receives the vehicle's wheel states of track step k, steps the CosimTrack and sends the wrenches
// back, and applies the run's end rules. ROS-free; the node owns the loop and publishes at outputDue().
//
//   CosimTrackRun run(core::runSettings(scene), track, transport, options);
//   while (run.step() == TrackRunStatus::kRunning) { if (run.outputDue()) publish(); }
//   run.close();   // exitCode(), message()
//
// End rules: the vehicle closes after the step that reaches solver.end, so a close is the run's end. A
// vehicle that closes (or dies) before its first frame, or before a time end less half a step, went away:
// kFailed with exit code 4. A replay ends where its recording does.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <rail_core/cost_profile.hpp>
#include <rail_core/coupling/protocol.hpp>
#include <rail_core/coupling/timed_transport.hpp>
#include <rail_core/coupling/transport.hpp>
#include <rail_core/run_settings.hpp>

#include "rail_track_node/cosim_track.hpp"

namespace rail::track {

enum class TrackRunStatus {
  kRunning,   // one step exchanged
  kFinished,  // the vehicle closed at solver.end (or the replay ended)
  kFailed,    // message() says why, exitCode() is the node's exit code
};

struct CosimTrackRunOptions {
  std::string peer = "(the vehicle node)";  // the vehicle node's name, for messages
  bool replay = false;                      // the frames come from a recording: its end is the run's
  core::CostProfile* cost = nullptr;        // when set: exchange waits and track steps are timed into it
};

class CosimTrackRun {
 public:
  // settings: the scene's (core::runSettings); track and transport must outlive the run.
  CosimTrackRun(const core::RunSettings& settings, CosimTrack& track, core::coupling::FrameTransport& transport,
                CosimTrackRunOptions options = {});

  // One track step: receive (the first waits up to solver.handshake_timeout for the vehicle's set-up, later
  // ones up to solver.exchange_timeout), step the track, send. No allocation on the normal path.
  TrackRunStatus step();
  // After a kRunning step: true when it reaches the next output instant n / output.rate (counted once).
  bool outputDue();
  // Tells the vehicle the track is done (its next receive returns kPeerClosed).
  void close();

  double time() const;          // t_k of the step exchanged last [s] (0 before the first)
  std::uint64_t steps() const;  // steps exchanged so far
  double trackStep() const { return track_step_; }
  const core::coupling::WheelStateFrame& states() const { return coupling_.states(); }
  int exitCode() const { return exit_code_; }
  const std::string& message() const { return message_; }

 private:
  TrackRunStatus fail(int exit_code, std::string message);
  bool reachesOutput(std::uint64_t step) const;  // step k's time reaches the next output instant

  core::RunSettings settings_;
  CosimTrack& track_;
  CosimTrackRunOptions options_;
  std::unique_ptr<core::coupling::TimedTransport> timed_;  // with options.cost
  core::coupling::TrackCoupling coupling_;
  double track_step_;
  std::uint64_t outputs_ = 0;
  int exit_code_ = 0;
  std::string message_;
};

// "wrong wheel count", "bad wheel id", ...: why the track refused a frame.
const char* describe(CosimStepStatus status);

}  // namespace rail::track
