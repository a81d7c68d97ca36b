// A FrameTransport that forwards every call to another one and adds the wall time each call took (the
// wait for the peer included) to a CostProfile's kTransportWait. ROS-free; no allocation.
#pragma once

#include "rail_core/cost_profile.hpp"
#include "rail_core/coupling/transport.hpp"

namespace rail::core::coupling {

class TimedTransport final : public FrameTransport {
 public:
  // inner and profile must outlive this object.
  TimedTransport(FrameTransport& inner, CostProfile& profile) : inner_(inner), profile_(profile) {}
  Role role() const override { return inner_.role(); }
  Result sendStates(const WheelStateFrame& f, Deadline d) override {
    CostProfile::Scope s(profile_, CostProfile::kTransportWait);
    return inner_.sendStates(f, d);
  }
  Result receiveWrenches(WrenchFrame& f, Deadline d) override {
    CostProfile::Scope s(profile_, CostProfile::kTransportWait);
    return inner_.receiveWrenches(f, d);
  }
  Result receiveStates(WheelStateFrame& f, Deadline d) override {
    CostProfile::Scope s(profile_, CostProfile::kTransportWait);
    return inner_.receiveStates(f, d);
  }
  Result sendWrenches(const WrenchFrame& f, Deadline d) override {
    CostProfile::Scope s(profile_, CostProfile::kTransportWait);
    return inner_.sendWrenches(f, d);
  }
  void close() override { inner_.close(); }

 private:
  FrameTransport& inner_;
  CostProfile& profile_;
};

}  // namespace rail::core::coupling
