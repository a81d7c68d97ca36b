#include "rail_vehicle_node/vehicle_run.hpp"

#include <algorithm>
#include <cstdio>

#include <rail_contact/enum_words.hpp>
#include <rail_core/coupling/transport.hpp>
#include <rail_core/exit_codes.hpp>

namespace rail::vehicle {

namespace {
constexpr contact::Word<RunStatus> kRunStatusWords[] = {
    {"running", RunStatus::kRunning},          {"finished", RunStatus::kFinished},
    {"derailed", RunStatus::kDerailed},        {"non-finite state", RunStatus::kNonFinite},
    {"left the track", RunStatus::kLeftTrack}, {"integrator failure", RunStatus::kIntegratorFailed}};
static_assert(contact::namesEvery(kRunStatusWords, RunStatus::kIntegratorFailed));
}  // namespace

const char* toString(RunStatus status) { return contact::wordOf(kRunStatusWords, status); }

int exitCodeOf(RunStatus status) {
  switch (status) {
    case RunStatus::kFinished:
      return core::kExitOk;
    case RunStatus::kDerailed:
    case RunStatus::kLeftTrack:
      return core::kExitDerailed;
    case RunStatus::kNonFinite:
    case RunStatus::kIntegratorFailed:
      return core::kExitNumerical;
    default:
      return core::kExitInternal;
  }
}

VehicleRun::VehicleRun(const core::RunSettings& settings, VehicleSimulator& alone, VehicleRunOptions options)
    : sim_(alone), options_(options), output_period_(settings.output_period), t_limit_(settings.end_time) {}

VehicleRun::VehicleRun(const core::RunSettings& settings, CosimVehicle& cosim, VehicleRunOptions options)
    : VehicleRun(settings, cosim.simulator(), options) {
  cosim_ = &cosim;
}

template <class F>
RunStatus VehicleRun::timed(F&& f) {
  if (options_.cost == nullptr) return f();
  core::CostProfile::Scope timing(*options_.cost, core::CostProfile::kVehicleIntegration);
  return f();
}

VehicleRun::Event VehicleRun::finish(End end, int exit_code) {
  ended_ = true;
  end_ = end;
  exit_code_ = exit_code;
  return Event::kEnd;
}

VehicleRun::Event VehicleRun::next() {
  if (ended_) return Event::kEnd;
  return cosim_ != nullptr ? nextCosim() : nextAlone();
}

// A stopped vehicle run (derailed, non-finite, ...): its message; kEnd. kRunning/kFinished: kOutput.
VehicleRun::Event VehicleRun::checkFailure() {
  char text[96];
  if (cosim_ != nullptr && status_ == RunStatus::kIntegratorFailed &&
      cosim_->exchangeStatus() != core::coupling::Status::kOk) {
    std::snprintf(text, sizeof(text), "exchange with the track node failed at step %llu (t = %.6f s): ",
                  static_cast<unsigned long long>(cosim_->stepsExchanged()), cosim_->time());
    message_ = text + cosim_->message();
    return finish(End::kExchangeFailed, core::coupling::exitCode(cosim_->exchangeStatus()));
  }
  std::snprintf(text, sizeof(text), "run stopped (%s) at t = %.6f s: ", toString(status_), sim_.time());
  message_ = text + (cosim_ != nullptr ? cosim_->message() : sim_.message());
  return finish(End::kFailed, exitCodeOf(status_));
}

VehicleRun::Event VehicleRun::nextAlone() {
  if (!started_) {
    started_ = true;
    output_index_ = next_output_++;
    return Event::kOutput;  // the start state
  }
  if (status_ == RunStatus::kFinished) return finish(End::kFinished, core::kExitOk);
  if (status_ != RunStatus::kRunning) return checkFailure();
  if (options_.stop != nullptr && *options_.stop) return finish(End::kStopped, core::kExitInterrupted);
  const double t_next = std::min(static_cast<double>(next_output_) * output_period_, t_limit_);
  status_ = timed([&] { return sim_.advanceTo(t_next); });
  output_index_ = next_output_++;
  return Event::kOutput;  // also the state where the run stopped
}

VehicleRun::Event VehicleRun::nextCosim() {
  CosimVehicle& v = *cosim_;
  if (!started_) {
    started_ = true;
    status_ = timed([&] { return v.start(); });
  } else {
    if (status_ == RunStatus::kFinished) return finish(End::kFinished, core::kExitOk);
    if (options_.stop != nullptr && *options_.stop) return finish(End::kStopped, core::kExitInterrupted);
    status_ = timed([&] { return v.step(static_cast<double>(next_output_) * output_period_); });
  }
  const double h = v.trackStep();
  for (;;) {
    if (status_ != RunStatus::kRunning && status_ != RunStatus::kFinished) return checkFailure();
    if (v.time() + 1e-9 * h >= static_cast<double>(next_output_) * output_period_ || status_ == RunStatus::kFinished) {
      output_index_ = next_output_++;
      return Event::kOutput;
    }
    if (options_.stop != nullptr && *options_.stop) return finish(End::kStopped, core::kExitInterrupted);
    status_ = timed([&] { return v.step(static_cast<double>(next_output_) * output_period_); });
  }
}

}  // namespace rail::vehicle
