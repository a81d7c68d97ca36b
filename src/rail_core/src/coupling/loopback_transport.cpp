#include "rail_core/coupling/loopback_transport.hpp"

#include <algorithm>
#include <string>

namespace rail::core::coupling {

namespace {
// Longest sleep between checks of the interrupt flag.
constexpr auto kSlice = std::chrono::milliseconds(20);

Result wrongRole(Role role, const char* call) {
  return {Status::kError, std::string(call) + " called on the " + toString(role) + " end"};
}
}  // namespace

LoopbackLink::LoopbackLink(int wheel_capacity, const std::atomic<bool>* interrupt)
    : interrupt_(interrupt),
      states_(wheel_capacity),
      wrenches_(wheel_capacity),
      vehicle_end_(*this, Role::kVehicle),
      track_end_(*this, Role::kTrack) {}

// Wait on the condition variable until pred() holds or something ends the wait. Called with the lock held.
template <class Pred>
static Result waitFor(std::unique_lock<std::mutex>& lock, std::condition_variable& cv, Pred pred,
                      const std::atomic<bool>* interrupt, const bool& own_closed, const bool& peer_closed,
                      Deadline deadline) {
  for (;;) {
    if (own_closed) return {Status::kError, "this end is closed"};
    if (pred()) return {};
    if (peer_closed) return {Status::kPeerClosed, {}};
    if (interrupt && interrupt->load(std::memory_order_relaxed)) return {Status::kInterrupted, {}};
    const auto now = Clock::now();
    if (now >= deadline) return {Status::kTimeout, {}};
    cv.wait_until(lock, std::min(deadline, now + kSlice));
  }
}

template <class Frame>
Result LoopbackLink::put(Mailbox<Frame>& box, const Frame& frame, Role writer, Deadline deadline) {
  std::unique_lock<std::mutex> lock(mutex_);
  const bool& own = writer == Role::kVehicle ? vehicle_closed_ : track_closed_;
  const bool& peer = writer == Role::kVehicle ? track_closed_ : vehicle_closed_;
  Result r = waitFor(
      lock, changed_, [&] { return !box.full; }, interrupt_, own, peer, deadline);
  if (!r) return r;
  if (!copyFrame(frame, box.frame))
    return {Status::kError, "frame of " + std::to_string(frame.count) + " wheels exceeds the capacity " +
                                std::to_string(box.frame.capacity())};
  box.full = true;
  lock.unlock();
  changed_.notify_all();
  return {};
}

template <class Frame>
Result LoopbackLink::take(Mailbox<Frame>& box, Frame& frame, Role reader, Deadline deadline) {
  std::unique_lock<std::mutex> lock(mutex_);
  const bool& own = reader == Role::kVehicle ? vehicle_closed_ : track_closed_;
  const bool& peer = reader == Role::kVehicle ? track_closed_ : vehicle_closed_;
  Result r = waitFor(
      lock, changed_, [&] { return box.full; }, interrupt_, own, peer, deadline);
  if (!r) return r;
  if (!copyFrame(box.frame, frame))
    return {Status::kError, "frame of " + std::to_string(box.frame.count) + " wheels exceeds the receiving capacity " +
                                std::to_string(frame.capacity())};
  box.full = false;
  lock.unlock();
  changed_.notify_all();
  return {};
}

Result LoopbackLink::End::sendStates(const WheelStateFrame& frame, Deadline deadline) {
  if (role_ != Role::kVehicle) return wrongRole(role_, "send_states");
  return link_.put(link_.states_, frame, role_, deadline);
}
Result LoopbackLink::End::receiveWrenches(WrenchFrame& frame, Deadline deadline) {
  if (role_ != Role::kVehicle) return wrongRole(role_, "receive_wrenches");
  return link_.take(link_.wrenches_, frame, role_, deadline);
}
Result LoopbackLink::End::receiveStates(WheelStateFrame& frame, Deadline deadline) {
  if (role_ != Role::kTrack) return wrongRole(role_, "receive_states");
  return link_.take(link_.states_, frame, role_, deadline);
}
Result LoopbackLink::End::sendWrenches(const WrenchFrame& frame, Deadline deadline) {
  if (role_ != Role::kTrack) return wrongRole(role_, "send_wrenches");
  return link_.put(link_.wrenches_, frame, role_, deadline);
}
void LoopbackLink::End::close() {
  {
    std::lock_guard<std::mutex> lock(link_.mutex_);
    (role_ == Role::kVehicle ? link_.vehicle_closed_ : link_.track_closed_) = true;
  }
  link_.changed_.notify_all();
}

}  // namespace rail::core::coupling
