#include "rail_track_node/cosim_track_run.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>

#include <rail_contact/enum_words.hpp>
#include <rail_core/exit_codes.hpp>

namespace rail::track {

namespace cc = core::coupling;

namespace {

cc::FrameTransport& timedOrPlain(std::unique_ptr<cc::TimedTransport>& timed, cc::FrameTransport& transport,
                                 core::CostProfile* cost) {
  if (cost == nullptr) return transport;
  timed = std::make_unique<cc::TimedTransport>(transport, *cost);
  return *timed;
}

constexpr rail::contact::Word<CosimStepStatus> kStepStatusWords[] = {
    {"accepted", CosimStepStatus::kOk},
    {"wrong wheel count", CosimStepStatus::kWrongWheelCount},
    {"bad wheel id", CosimStepStatus::kBadWheelId},
    {"a wheel is outside the track window (solver.track_window: margins too small?)",
     CosimStepStatus::kWheelOutsideWindow},
    {"the track window could not move", CosimStepStatus::kWindowMoveFailed}};
static_assert(rail::contact::namesEvery(kStepStatusWords, CosimStepStatus::kWindowMoveFailed));

}  // namespace

const char* describe(CosimStepStatus status) { return rail::contact::wordOf(kStepStatusWords, status); }

CosimTrackRun::CosimTrackRun(const core::RunSettings& settings, CosimTrack& track, cc::FrameTransport& transport,
                             CosimTrackRunOptions options)
    : settings_(settings),
      track_(track),
      options_(std::move(options)),
      coupling_(settings.coupling, timedOrPlain(timed_, transport, options_.cost)),
      track_step_(settings.coupling.track_step) {}

double CosimTrackRun::time() const {
  return coupling_.nextStep() == 0 ? 0.0 : static_cast<double>(coupling_.nextStep() - 1) * track_step_;
}

std::uint64_t CosimTrackRun::steps() const { return coupling_.nextStep(); }

TrackRunStatus CosimTrackRun::fail(int exit_code, std::string message) {
  exit_code_ = exit_code;
  message_ = std::move(message);
  return TrackRunStatus::kFailed;
}

TrackRunStatus CosimTrackRun::step() {
  char text[160];
  // Step 0 waits for the vehicle's set-up (its settling): the handshake timeout.
  const cc::Result r =
      coupling_.nextStep() == 0
          ? coupling_.receive(cc::Clock::now() + std::chrono::duration_cast<cc::Clock::duration>(
                                                     std::chrono::duration<double>(settings_.handshake_timeout)))
          : coupling_.receive();
  if (r.status == cc::Status::kPeerClosed) {
    const bool no_frame = coupling_.nextStep() == 0;
    const double t_last = no_frame ? -1.0 : time();
    // An end by arc length (end_time infinite) is the vehicle's to tell: its closing ends the run.
    const bool before_end =
        no_frame || (std::isfinite(settings_.end_time) && t_last < settings_.end_time - 0.5 * track_step_);
    if (!options_.replay && before_end) {
      std::snprintf(text, sizeof(text), " went away after step %lld (t = %.6f s), before solver.end: ",
                    static_cast<long long>(coupling_.nextStep()) - 1, t_last);
      return fail(core::kExitPeerTimeout, "the vehicle node " + options_.peer + text + r.message);
    }
    return TrackRunStatus::kFinished;
  }
  if (!r) {
    std::snprintf(text, sizeof(text), " failed at step %llu: ", static_cast<unsigned long long>(coupling_.nextStep()));
    return fail(cc::exitCode(r.status), "exchange with the vehicle node " + options_.peer + text + r.message);
  }
  // A step whose contacts are published searches every surface (exact gaps).
  track_.setExactGaps(reachesOutput(coupling_.states().step));
  CosimStepStatus status;
  if (options_.cost != nullptr) {
    core::CostProfile::Scope timing(*options_.cost, core::CostProfile::kTrackStep);
    status = track_.stepForces(coupling_.states(), coupling_.wrenches());
  } else {
    status = track_.stepForces(coupling_.states(), coupling_.wrenches());
  }
  const auto step = static_cast<unsigned long long>(coupling_.states().step);
  if (status != CosimStepStatus::kOk) {
    std::snprintf(text, sizeof(text), "step %llu: the vehicle's frame was refused (", step);
    return fail(core::kExitPeerRefused, text + std::string(describe(status)) + ")");
  }
  // The rest of the track's step (the Newmark completion with the step's contact loads) before the
  // vehicle's integration; the next base solve runs beside that integration.
  if (options_.cost != nullptr) {
    const auto t0 = std::chrono::steady_clock::now();
    track_.finishStep();
    options_.cost->addSeconds(core::CostProfile::kTrackStep,
                              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  } else {
    track_.finishStep();
  }
  const cc::Result w = coupling_.send();
  if (!w) {
    std::snprintf(text, sizeof(text), "sending the wrenches of step %llu to the vehicle node ", step);
    return fail(cc::exitCode(w.status), text + options_.peer + " failed: " + w.message);
  }
  return TrackRunStatus::kRunning;
}

bool CosimTrackRun::reachesOutput(std::uint64_t step) const {
  const double t = static_cast<double>(step) * track_step_;
  return t + 1e-9 * track_step_ >= static_cast<double>(outputs_) * settings_.output_period;
}

bool CosimTrackRun::outputDue() {
  if (!reachesOutput(coupling_.states().step)) return false;
  ++outputs_;
  return true;
}

void CosimTrackRun::close() { coupling_.close(); }

}  // namespace rail::track
