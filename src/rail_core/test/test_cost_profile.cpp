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
    EXPECT_EQ(p.seconds(static_cast<CostProfile::Component>(c)), 0.0)
        << CostProfile::name(static_cast<CostProfile::Component>(c));
    EXPECT_EQ(p.calls(static_cast<CostProfile::Component>(c)), 0);
  }
}

TEST(CostProfile, YamlListsEveryComponentTheCountsAndTheEffects) {
  CostProfile p;
  p.add(CostProfile::kVehicleIntegration, 3.0);
  p.add(CostProfile::kPublish, 1.0);
  p.setCount("cvode_steps", 1200);
  Scene scene;
  scene.file = "s.yaml";
  scene.effects.flange_contact = false;
  const std::string y = p.toYaml("/v", scene.file, scene.effects, 5.0, 2.0);
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
  TimedTransport tv(link.vehicleEnd(), pv), tt(link.trackEnd(), pt);
  WheelStateFrame s(2), s_in(2);
  s.step = 7;
  s.count = 2;
  s.wheels[1].p_wheel_in_world = Eigen::Vector3d(1.0, 2.0, 3.0);
  const Deadline d = Clock::now() + std::chrono::seconds(1);
  ASSERT_TRUE(tv.sendStates(s, d));
  ASSERT_TRUE(tt.receiveStates(s_in, d));
  EXPECT_EQ(s_in.step, 7u);
  EXPECT_EQ(s_in.wheels[1].p_wheel_in_world, s.wheels[1].p_wheel_in_world);
  EXPECT_EQ(pv.calls(CostProfile::kTransportWait), 1);
  EXPECT_EQ(pt.calls(CostProfile::kTransportWait), 1);
  EXPECT_EQ(tv.role(), Role::kVehicle);
}

// The node-level optional outputs (effects.rviz_markers, contact_point_output, the track's energy_output) go
// through TimedOutput:
// off, the output is not produced and its part shows exactly zero time and calls; on, it is produced
// under its part's clock.
TEST(CostClock, TimedOutputOffProducesNothingAndCostsNothing) {
  for (CostClock::Part part : {CostClock::kMarkers, CostClock::kContactPointOutput, CostClock::kEnergyOutput}) {
    CostClock clock;
    int produced = 0;
    EXPECT_FALSE(timedOutput(&clock, part, false, [&] { ++produced; }));
    EXPECT_EQ(produced, 0);
    EXPECT_EQ(clock.calls[part], 0);
    EXPECT_EQ(clock.seconds[part], 0.0);
    EXPECT_TRUE(timedOutput(&clock, part, true, [&] {
      ++produced;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }));
    EXPECT_EQ(produced, 1);
    EXPECT_EQ(clock.calls[part], 1);
    // sleep_for waits at least the time asked; the upper bound only guards against a wrong unit.
    EXPECT_GE(clock.seconds[part], 0.002);
    EXPECT_LT(clock.seconds[part], 2.0);
    // No clock: still produced, nothing recorded anywhere.
    EXPECT_TRUE(timedOutput(nullptr, part, true, [&] { ++produced; }));
    EXPECT_EQ(produced, 2);
  }
}

// The finer split nests in the coarse components and the per-component "other" makes the shares add up:
// track side, track_step 4 s = contact 1 + 0.5, rhs 0.5, solve 1.5, rest 0.5.
// With the solve on a second thread, track_rhs and track_solve are beside the loop (not subtracted from
// track_step) and the loop's share is the wait for them.
TEST(CostClock, ASolveBesideTheLoopIsReportedBesideIt) {
  CostProfile p;
  p.add(CostProfile::kTrackStep, 4.0);
  CostClock k;
  k.track_solve_beside = true;
  k.add(CostClock::kTrackRhs, 0.5);
  k.add(CostClock::kTrackSolve, 1.5);
  k.add(CostClock::kTrackSolveWait, 0.25);
  Scene scene;
  scene.file = "s.yaml";
  const std::string y = p.toYaml("/t", scene.file, scene.effects, 10.0, 1.0, &k);
  EXPECT_NE(y.find("track_solve: {seconds: 1.5, share: 0.15, calls: 1, within: beside_track_step}"), std::string::npos)
      << y;
  EXPECT_NE(y.find("track_solve_wait: {seconds: 0.25, share: 0.025, calls: 1, within: track_step}"), std::string::npos)
      << y;
  EXPECT_NE(y.find("track_step_other: {seconds: 3.75, share: 0.375}"), std::string::npos) << y;  // 4 - 0.25
  const std::string text = p.toText("/t", 10.0, 1.0, &k);
  EXPECT_NE(text.find("beside: track_solve"), std::string::npos) << text;
}

TEST(CostClock, FinerSplitAddsUpWithinItsComponent) {
  CostProfile p;
  p.add(CostProfile::kTrackStep, 4.0);
  p.add(CostProfile::kPublish, 1.0);
  CostClock k;
  k.contact.detection_seconds = 1.0;
  k.contact.forces_seconds = 0.5;
  k.contact.evaluations = 8;
  k.add(CostClock::kTrackRhs, 0.5);
  k.add(CostClock::kTrackSolve, 1.5);
  k.add(CostClock::kRailDeflection, 0.25);
  Scene scene;
  scene.file = "s.yaml";
  const std::string y = p.toYaml("/t", scene.file, scene.effects, 10.0, 1.0, &k);
  EXPECT_NE(y.find("contact_detection: {seconds: 1, share: 0.1, calls: 8, within: track_step}"), std::string::npos)
      << y;
  EXPECT_NE(y.find("track_solve: {seconds: 1.5, share: 0.15, calls: 1, within: track_step}"), std::string::npos) << y;
  EXPECT_NE(y.find("track_step_other: {seconds: 0.5, share: 0.05}"), std::string::npos)
      << y;                                                                                   // 4 - 1 - 0.5 - 0.5 - 1.5
  EXPECT_NE(y.find("publish_other: {seconds: 0.75, share: 0.075}"), std::string::npos) << y;  // 1 - 0.25
  EXPECT_NE(y.find("flange_searches: 0"), std::string::npos) << y;
  // Vehicle side: the contact parts are inside the right-hand sides and not subtracted again.
  CostProfile v;
  v.add(CostProfile::kVehicleIntegration, 3.0);
  CostClock kv;
  kv.add(CostClock::kVehicleRhs, 2.0);
  kv.contact.detection_seconds = 1.0;
  kv.contact.evaluations = 8;
  const std::string yv = v.toYaml("/v", scene.file, scene.effects, 4.0, 1.0, &kv);
  EXPECT_NE(yv.find("contact_detection: {seconds: 1, share: 0.25, calls: 8, within: vehicle_integration}"),
            std::string::npos)
      << yv;
  EXPECT_NE(yv.find("vehicle_integration_other: {seconds: 1, share: 0.25}"), std::string::npos) << yv;  // 3 - 2
}
