// gtest (no ROS master needed): the conversions between the coupling frames and rail_msgs
// (rail_ros/frame_messages.hpp): exact round trip, time rebuilt from the step, refusals, the close
// marker, and no allocation once the messages are reserved. Replaces the global operator new to count
// allocations, so it is an executable of its own.
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>

#include <gtest/gtest.h>

#include "rail_ros/frame_messages.hpp"

namespace {
long g_allocations = 0;
}  // namespace

void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

using namespace rail::core;
using namespace rail::ros_glue;

namespace {

constexpr int kWheels = 8;
constexpr double kStep = 2e-5;  // h [s]

std::uint64_t bits(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

// Wheel states with values that expose any arithmetic on the way: -0.0, a subnormal, extremes.
coupling::WheelStateFrame sampleStates(std::uint64_t step) {
  coupling::WheelStateFrame f(kWheels);
  f.step = step;
  f.time = static_cast<double>(step) * kStep;
  f.scene_hash = 0x0123456789abcdefull;
  f.count = kWheels;
  for (int i = 0; i < kWheels; ++i) {
    coupling::WheelState& w = f.wheels[i];
    w.id = static_cast<std::uint32_t>(i);
    w.arc_length = 1e3 / 3.0 + i;
    w.p_wheel_in_world = Eigen::Vector3d(-0.0, 0.1 * i + 1e-17, std::numeric_limits<double>::denorm_min());
    w.R_wheelset_to_world = Eigen::Quaterniond(0.3, -0.4, 0.5 + 1e-16, -0.7).normalized().toRotationMatrix();
    w.v_wheel_in_world = Eigen::Vector3d(std::numeric_limits<double>::max(), -1.0 / 7.0, 2.0 / 3.0);
    w.omega_wheelset_in_world = Eigen::Vector3d(1e-300, 65.2173913043478, -std::numeric_limits<double>::min());
  }
  return f;
}

coupling::WrenchFrame sampleWrenches(std::uint64_t step) {
  coupling::WrenchFrame f(kWheels);
  f.step = step;
  f.time = static_cast<double>(step) * kStep;
  f.scene_hash = 0xfedcba9876543210ull;
  f.count = kWheels;
  for (int i = 0; i < kWheels; ++i) {
    f.wheels[i].id = static_cast<std::uint32_t>(i);
    f.wheels[i].f_wheel_in_world = Eigen::Vector3d(1.0 / 3.0 * i, -0.0, 72900.0 + 1e-11);
    f.wheels[i].n_wheel_in_world = Eigen::Vector3d(-1234.5, 1e-310, 1e308);
  }
  return f;
}

void expectSameBits(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  for (int c = 0; c < 3; ++c) EXPECT_EQ(bits(a[c]), bits(b[c]));
}

}  // namespace

// Every double goes through unchanged (bit for bit, -0.0 and subnormals included): the conversions copy.
TEST(FrameMessages, WheelStatesRoundTripIsExact) {
  const coupling::WheelStateFrame in = sampleStates(62500);
  rail_msgs::WheelStates msg;
  reserveMessage(msg, kWheels);
  ASSERT_TRUE(toMessage(in, msg).ok());
  EXPECT_EQ(msg.header.frame_id, "world");
  EXPECT_EQ(msg.step, 62500u);
  EXPECT_EQ(msg.scene_hash, in.scene_hash);
  ASSERT_EQ(msg.wheels.size(), static_cast<std::size_t>(kWheels));
  // 62500 x 2e-5 s = 1.25 s exactly representable in the stamp.
  EXPECT_EQ(msg.header.stamp.sec, 1u);
  EXPECT_EQ(msg.header.stamp.nsec, 250000000u);
  for (int i = 0; i < kWheels; ++i) {
    EXPECT_EQ(msg.wheels[i].wheel_id, i);
    EXPECT_EQ(msg.wheels[i].wheelset, i / 2);  // id = 2 * wheelset + side
    EXPECT_EQ(msg.wheels[i].side, i % 2 ? rail_msgs::WheelState::SIDE_RIGHT : rail_msgs::WheelState::SIDE_LEFT);
  }
  coupling::WheelStateFrame out(kWheels);
  ASSERT_TRUE(fromMessage(msg, kStep, out, "test").ok());
  EXPECT_EQ(out.step, in.step);
  EXPECT_EQ(bits(out.time), bits(in.time));
  EXPECT_EQ(out.scene_hash, in.scene_hash);
  ASSERT_EQ(out.count, in.count);
  for (int i = 0; i < kWheels; ++i) {
    const coupling::WheelState& a = in.wheels[i];
    const coupling::WheelState& b = out.wheels[i];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(bits(a.arc_length), bits(b.arc_length));
    expectSameBits(a.p_wheel_in_world, b.p_wheel_in_world);
    // The message carries the orientation as a unit quaternion: the matrix comes back from the same
    // conversions bit for bit, and equal to the sent one to round-off.
    const Eigen::Matrix3d R_wire = coupling::orientationFromWire(coupling::wireOrientation(a.R_wheelset_to_world));
    for (int c = 0; c < 9; ++c) EXPECT_EQ(bits(R_wire.data()[c]), bits(b.R_wheelset_to_world.data()[c]));
    EXPECT_LT((b.R_wheelset_to_world - a.R_wheelset_to_world).norm(), 1e-15);
    expectSameBits(a.v_wheel_in_world, b.v_wheel_in_world);
    expectSameBits(a.omega_wheelset_in_world, b.omega_wheelset_in_world);
  }
}

TEST(FrameMessages, WrenchesRoundTripIsExact) {
  const coupling::WrenchFrame in = sampleWrenches(17);
  rail_msgs::ContactWrenches msg;
  reserveMessage(msg, kWheels);
  ASSERT_TRUE(toMessage(in, msg).ok());
  coupling::WrenchFrame out(kWheels);
  ASSERT_TRUE(fromMessage(msg, kStep, out, "test").ok());
  EXPECT_EQ(out.step, 17u);
  EXPECT_EQ(out.scene_hash, in.scene_hash);
  ASSERT_EQ(out.count, in.count);
  for (int i = 0; i < kWheels; ++i) {
    EXPECT_EQ(out.wheels[i].id, in.wheels[i].id);
    expectSameBits(out.wheels[i].f_wheel_in_world, in.wheels[i].f_wheel_in_world);
    expectSameBits(out.wheels[i].n_wheel_in_world, in.wheels[i].n_wheel_in_world);
  }
}

// The stamp has ns resolution; the receiver rebuilds t_k = k h bit for bit from the step, also where k h is
// not a whole number of nanoseconds (h = 12.3456789123 us).
TEST(FrameMessages, TimeRebuiltExactlyFromTheStep) {
  const double h = 1.23456789123e-5;  // [s]
  for (std::uint64_t k : {0ull, 1ull, 3ull, 1234567ull, 4000000000ull}) {
    coupling::WrenchFrame in = sampleWrenches(k);
    in.time = static_cast<double>(k) * h;
    rail_msgs::ContactWrenches msg;
    reserveMessage(msg, kWheels);
    ASSERT_TRUE(toMessage(in, msg).ok()) << k;
    coupling::WrenchFrame out(kWheels);
    ASSERT_TRUE(fromMessage(msg, h, out, "test").ok()) << k;
    EXPECT_EQ(bits(out.time), bits(static_cast<double>(k) * h)) << k;
  }
}

// A stamp 1 ns off (rounding) is accepted; 2 ns off is refused, naming the source, the stamp and k h.
TEST(FrameMessages, StampNotMatchingTheStepRefused) {
  rail_msgs::WheelStates msg;
  reserveMessage(msg, kWheels);
  ASSERT_TRUE(toMessage(sampleStates(100), msg).ok());  // t = 2 ms
  coupling::WheelStateFrame out(kWheels);
  msg.header.stamp.nsec += 1;
  EXPECT_TRUE(fromMessage(msg, kStep, out, "/x/states").ok());
  msg.header.stamp.nsec += 1;
  out.step = 999;
  const coupling::Result r = fromMessage(msg, kStep, out, "/x/states");
  EXPECT_EQ(r.status, coupling::Status::kRefused);
  EXPECT_NE(r.message.find("/x/states"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("0.002000002"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("step 100"), std::string::npos) << r.message;
  EXPECT_EQ(out.step, 999u);  // unchanged
}

TEST(FrameMessages, MoreWheelsThanTheCapacityRefused) {
  rail_msgs::WheelStates msg;
  reserveMessage(msg, kWheels);
  ASSERT_TRUE(toMessage(sampleStates(5), msg).ok());
  coupling::WheelStateFrame small(4);
  const coupling::Result r = fromMessage(msg, kStep, small, "/x/states");
  EXPECT_EQ(r.status, coupling::Status::kRefused);
  EXPECT_NE(r.message.find("8 wheels"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("capacity 4"), std::string::npos) << r.message;
  EXPECT_EQ(small.count, 0u);
}

TEST(FrameMessages, UnrepresentableValuesGiveAnError) {
  rail_msgs::WheelStates msg;
  reserveMessage(msg, kWheels);
  coupling::WheelStateFrame f = sampleStates(5);
  f.wheels[3].id = 256;  // the message's wheel_id is a uint8
  coupling::Result r = toMessage(f, msg);
  EXPECT_EQ(r.status, coupling::Status::kError);
  EXPECT_NE(r.message.find("wheel id 256"), std::string::npos) << r.message;
  EXPECT_TRUE(msg.wheels.empty());  // unchanged
  f = sampleStates(5);
  f.time = -1e-3;
  r = toMessage(f, msg);
  EXPECT_EQ(r.status, coupling::Status::kError);
  EXPECT_NE(r.message.find("-0.001"), std::string::npos) << r.message;
}

TEST(FrameMessages, CloseMarker) {
  rail_msgs::ContactWrenches msg;
  reserveMessage(msg, kWheels);
  ASSERT_TRUE(toMessage(sampleWrenches(3), msg).ok());
  EXPECT_FALSE(isCloseMarker(msg));
  makeCloseMarker(msg);
  EXPECT_TRUE(isCloseMarker(msg));
  EXPECT_EQ(msg.step, kCloseStep);
  EXPECT_GE(msg.wrenches.capacity(), static_cast<std::size_t>(kWheels));  // reusable without allocating
}

// Once reserved, converting both ways allocates nothing (also after a close marker emptied the array).
TEST(FrameMessages, NoAllocationOnceReserved) {
  coupling::WheelStateFrame states = sampleStates(0), states_out(kWheels);
  coupling::WrenchFrame wrenches = sampleWrenches(0), wrenches_out(kWheels);
  rail_msgs::WheelStates sm;
  rail_msgs::ContactWrenches wm;
  reserveMessage(sm, kWheels);
  reserveMessage(wm, kWheels);
  const long before = g_allocations;
  bool ok = true;
  for (std::uint64_t k = 0; k < 1000; ++k) {
    states.step = wrenches.step = k;
    states.time = wrenches.time = static_cast<double>(k) * kStep;
    ok = ok && toMessage(states, sm).ok() && fromMessage(sm, kStep, states_out, "s").ok();
    ok = ok && toMessage(wrenches, wm).ok() && fromMessage(wm, kStep, wrenches_out, "w").ok();
    if (k == 500) {
      makeCloseMarker(sm);
      makeCloseMarker(wm);
    }
  }
  const long allocations = g_allocations - before;
  EXPECT_TRUE(ok);
  EXPECT_EQ(allocations, 0);
  // The counter does count: the first conversion into a message never reserved allocates its array.
  rail_msgs::WheelStates fresh;
  const long before_fresh = g_allocations;
  ASSERT_TRUE(toMessage(states, fresh).ok());
  EXPECT_GT(g_allocations - before_fresh, 0);
}
