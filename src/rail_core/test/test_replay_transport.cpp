// The replay's frames: recorded states interpolated to each track step (linearly, orientations by slerp),
// stamped with the scene's hash and step, closed after the recording's end (or the scene's end time), and
// the recordings a replay cannot use refused with their source named.
#include <gtest/gtest.h>

#include <cmath>

#include "rail_core/coupling/replay_transport.hpp"

namespace cc = rail::core::coupling;

namespace {

// Two wheels at instants 0 and 0.01 s: moving 0.3 m along x, the wheelset turning 90 deg about z.
cc::RecordedStates twoInstants() {
  cc::RecordedStates r;
  r.source = "run.bag";
  for (int k = 0; k < 2; ++k) {
    cc::WheelStateFrame f(2);
    f.count = 2;
    for (int i = 0; i < 2; ++i) {
      cc::WheelState& w = f.wheels[static_cast<std::size_t>(i)];
      w.id = static_cast<std::uint32_t>(i);
      w.arc_length = 10.0 - 2.5 * i + 0.3 * k;
      w.p_wheel_in_world = Eigen::Vector3d(w.arc_length, 0.0, 0.5);
      w.v_wheel_in_world = Eigen::Vector3d(30.0 + 10.0 * k, 0.0, 0.0);
      w.R_wheelset_to_world = Eigen::AngleAxisd(k * M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    }
    r.times.push_back(0.01 * k);
    r.frames.push_back(f);
  }
  return r;
}

std::string refusal(cc::RecordedStates r) {
  try {
    cc::ReplayTransport t(std::move(r), 1e-3, 7, 0.0);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(ReplayTransport, InterpolatesEachTrackStepAndClosesAfterTheRecording) {
  cc::ReplayTransport t(twoInstants(), 2.5e-3, 42, 0.0);
  EXPECT_DOUBLE_EQ(t.endTime(), 0.01);
  EXPECT_NEAR(t.wheelSpan(), 2.5, 1e-12);
  cc::WheelStateFrame f(2);
  for (int k = 0; k <= 4; ++k) {
    ASSERT_TRUE(t.receiveStates(f, {})) << k;
    const double a = 0.25 * k;  // fraction of the interval
    EXPECT_EQ(f.step, static_cast<std::uint64_t>(k));
    EXPECT_DOUBLE_EQ(f.time, 2.5e-3 * k);
    EXPECT_EQ(f.scene_hash, 42u);
    EXPECT_EQ(f.count, 2u);
    EXPECT_NEAR(f.wheels[1].arc_length, 7.5 + 0.3 * a, 1e-12);
    EXPECT_NEAR(f.wheels[1].p_wheel_in_world.x(), 7.5 + 0.3 * a, 1e-12);
    EXPECT_NEAR(f.wheels[0].v_wheel_in_world.x(), 30.0 + 10.0 * a, 1e-12);
    // slerp: the yaw angle grows linearly, 0 .. 90 deg.
    const Eigen::Vector3d x = f.wheels[0].R_wheelset_to_world * Eigen::Vector3d::UnitX();
    EXPECT_NEAR(std::atan2(x.y(), x.x()), a * M_PI / 2, 1e-12);
  }
  EXPECT_EQ(t.receiveStates(f, {}).status, cc::Status::kPeerClosed);
  EXPECT_TRUE(t.sendWrenches(cc::WrenchFrame(2), {}));
  EXPECT_EQ(t.sendStates(f, {}).status, cc::Status::kError);
}

TEST(ReplayTransport, TheScenesEndTimeShortensTheReplay) {
  cc::ReplayTransport t(twoInstants(), 2.5e-3, 42, 0.005);
  EXPECT_DOUBLE_EQ(t.endTime(), 0.005);
  cc::WheelStateFrame f(2);
  for (int k = 0; k <= 2; ++k) ASSERT_TRUE(t.receiveStates(f, {})) << k;
  EXPECT_EQ(t.receiveStates(f, {}).status, cc::Status::kPeerClosed);
}

TEST(ReplayTransport, RefusesRecordingsItCannotReplayNamingTheirSource) {
  cc::RecordedStates one = twoInstants();
  one.times.pop_back();
  one.frames.pop_back();
  EXPECT_EQ(refusal(one), "run.bag: the wheel states have one instant; a replay needs two");

  cc::RecordedStates late = twoInstants();
  late.times = {0.5, 0.6};
  EXPECT_EQ(refusal(late), "run.bag: the wheel states start at t = 0.5 s; a replay starts at t = 0");

  cc::RecordedStates backwards = twoInstants();
  backwards.times = {0.0, 0.0};
  EXPECT_EQ(refusal(backwards), "run.bag: the wheel states' times do not increase at t = 0 s");

  cc::RecordedStates fewer = twoInstants();
  fewer.frames[1].count = 1;
  EXPECT_EQ(refusal(fewer), "run.bag: the wheel states at t = 0.01 s have 1 wheels, the first 2");
}
