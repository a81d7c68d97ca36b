// In-process transport for tests and single-process runs: two one-frame mailboxes (vehicle to track,
// track to vehicle) guarded by a mutex and condition variables. The vehicle and track sides run in
// different threads.
#pragma once

#include <condition_variable>
#include <mutex>

#include "rail_core/coupling/transport.hpp"

namespace rail::core::coupling {

// Owns both mailboxes and both endpoints; must outlive the endpoints' users.
class LoopbackLink {
 public:
  // wheel_capacity: largest frame carried. interrupt: optional flag that ends any wait with kInterrupted.
  explicit LoopbackLink(int wheel_capacity, const std::atomic<bool>* interrupt = nullptr);
  LoopbackLink(const LoopbackLink&) = delete;
  LoopbackLink& operator=(const LoopbackLink&) = delete;

  FrameTransport& vehicleEnd() { return vehicle_end_; }
  FrameTransport& trackEnd() { return track_end_; }

 private:
  class End : public FrameTransport {
   public:
    End(LoopbackLink& link, Role role) : link_(link), role_(role) {}
    Role role() const override { return role_; }
    Result sendStates(const WheelStateFrame& frame, Deadline deadline) override;
    Result receiveWrenches(WrenchFrame& frame, Deadline deadline) override;
    Result receiveStates(WheelStateFrame& frame, Deadline deadline) override;
    Result sendWrenches(const WrenchFrame& frame, Deadline deadline) override;
    void close() override;

   private:
    LoopbackLink& link_;
    Role role_;
  };
  // A one-frame slot: full = written and not yet read.
  template <class Frame>
  struct Mailbox {
    explicit Mailbox(int capacity) : frame(capacity) {}
    Frame frame;
    bool full = false;
  };
  template <class Frame>
  Result put(Mailbox<Frame>& box, const Frame& frame, Role writer, Deadline deadline);
  template <class Frame>
  Result take(Mailbox<Frame>& box, Frame& frame, Role reader, Deadline deadline);
  bool closed(Role r) const { return r == Role::kVehicle ? vehicle_closed_ : track_closed_; }

  const std::atomic<bool>* interrupt_;
  std::mutex mutex_;
  std::condition_variable changed_;
  Mailbox<WheelStateFrame> states_;
  Mailbox<WrenchFrame> wrenches_;
  bool vehicle_closed_ = false;
  bool track_closed_ = false;
  End vehicle_end_;
  End track_end_;
};

}  // namespace rail::core::coupling
