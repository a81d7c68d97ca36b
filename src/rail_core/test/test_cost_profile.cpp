// The cost profile: scopes add their wall time to their component only; a component never used shows
// zero; the transport decorator times both directions and forwards the frames unchanged.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "rail_core/cost_profile.hpp"
#include "rail_core/coupling/loopback_transport.hpp"
#include "rail_core/coupling/timed_transport.hpp"

using namespace rail::core;

TEST(CostProfile, ScopesAddToTheirComponentOnly) {
  CostProfile p;
  {
    CostProfile::Scope s(p, CostProfile::kTrackStep);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  // sleep_for waits at least the time asked; the upper bound only guards against a wrong unit (s vs ms).
  EXPECT_GE(p.seconds(CostProfile::kTrackStep), 0.020);
  EXPECT_LT(p.seconds(CostProfile::kTrackStep), 2.0);
  EXPECT_EQ(p.calls(CostProfile::kTrackStep), 1);
  for (int c = 0; c < CostProfile::kComponentCount; ++c) {
    if (c == CostProfile::kTrackStep) continue;
    EXPECT_EQ(p.seconds(static_cast<CostProfile::Component>(c)), 0.0) << CostProfile::name(static_cast<CostProfile::Component>(c));
    EXPECT_EQ(p.calls(static_cast<CostProfile::Component>(c)), 0);
  }
}

TEST(CostProfile, YamlListsEveryComponentTheCountsAndTheEffects) {
  CostProfile p;
  p.add(CostProfile::kVehicleIntegration, 3.0);
  p.add(CostProfile::kPublish, 1.0);
  p.set_count("cvode_steps", 1200);
  Scene scene;
  scene.file = "s.yaml";
  scene.effects.flange_contact = false;
  const std::string y = p.to_yaml("/v", scene, 5.0, 2.0);
  EXPECT_NE(y.find("wall_per_simulated_second: 2.5"), std::string::npos) << y;
  EXPECT_NE(y.find("vehicle_integration: {seconds: 3, share: 0.6, calls: 1}"), std::string::npos) << y;
  EXPECT_NE(y.find("track_step: {seconds: 0, share: 0, calls: 0}"), std::string::npos) << y;
  EXPECT_NE(y.find("other: {seconds: 1}"), std::string::npos) << y;  // 5 - 3 - 1
  EXPECT_NE(y.find("cvode_steps: 1200"), std::string::npos) << y;
  EXPECT_NE(y.find("flange_contact: off"), std::string::npos) << y;
  EXPECT_NE(y.find("spin_creepage: on"), std::string::npos) << y;
}

TEST(CostProfile, TimedTransportTimesBothDirectionsAndForwardsFrames) {
  using namespace rail::core::coupling;
  LoopbackLink link(2);
  CostProfile pv, pt;
  TimedTransport tv(link.vehicle_end(), pv), tt(link.track_end(), pt);
  WheelStateFrame s(2), s_in(2);
  s.step = 7;
  s.count = 2;
  s.wheels[1].p_wheel_in_world = Eigen::Vector3d(1.0, 2.0, 3.0);
  const Deadline d = Clock::now() + std::chrono::seconds(1);
  ASSERT_TRUE(tv.send_states(s, d));
  ASSERT_TRUE(tt.receive_states(s_in, d));
  EXPECT_EQ(s_in.step, 7u);
  EXPECT_EQ(s_in.wheels[1].p_wheel_in_world, s.wheels[1].p_wheel_in_world);
  EXPECT_EQ(pv.calls(CostProfile::kTransportWait), 1);
  EXPECT_EQ(pt.calls(CostProfile::kTransportWait), 1);
  EXPECT_EQ(tv.role(), Role::kVehicle);
}
