// The co-simulation protocol over the in-process loopback transport: wrench extrapolation, step order,
// refusals, timeouts and shutdown.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <thread>
#include <vector>

#include "rail_core/coupling/loopback_transport.hpp"
#include "rail_core/coupling/protocol.hpp"
#include "rail_core/exit_codes.hpp"

using namespace rail::core;
using namespace rail::core::coupling;

namespace {

constexpr std::uint64_t kHash = 0x00c0ffee12345678ull;

CouplingConfig config(int wheels = 8, double h = 2e-5, double timeout = 5.0) {
  CouplingConfig c;
  c.track_step = h;
  c.exchange_timeout = timeout;
  c.scene_hash = kHash;
  c.wheel_count = wheels;
  return c;
}

// A track thread that answers every step with wrench(t, wheel, f, n) and records the steps it saw.
struct ScriptedTrack {
  using WrenchFn = std::function<void(double t, int wheel, Eigen::Vector3d& f, Eigen::Vector3d& n)>;
  ScriptedTrack(const CouplingConfig& c, FrameTransport& end, WrenchFn fn) : coupling(c, end), wrench(std::move(fn)) {
    thread = std::thread([this, c] {
      for (;;) {
        last = coupling.receive();
        if (!last) return;
        const WheelStateFrame& s = coupling.states();
        seen_steps.push_back(s.step);
        // The states carry the step in the arc length of every wheel (set by the vehicle below).
        for (std::uint32_t i = 0; i < s.count; ++i)
          if (s.wheels[i].arc_length != 100.0 * static_cast<double>(s.step) + i) ++bad_states;
        WrenchFrame& w = coupling.wrenches();
        for (int i = 0; i < c.wheel_count; ++i)
          wrench(s.time, i, w.wheels[i].f_wheel_in_world, w.wheels[i].n_wheel_in_world);
        last = coupling.send();
        if (!last) return;
      }
    });
  }
  ~ScriptedTrack() {
    if (thread.joinable()) thread.join();
  }
  TrackCoupling coupling;
  WrenchFn wrench;
  std::thread thread;
  std::vector<std::uint64_t> seen_steps;
  int bad_states = 0;
  Result last;
};

void fillStates(VehicleCoupling& v, int wheels) {
  for (int i = 0; i < wheels; ++i) v.states().wheels[i].arc_length = 100.0 * static_cast<double>(v.nextStep()) + i;
}

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

}  // namespace

// Before any exchange the wrench is zero; after step 0 (t = 0) it is W_0 held constant on [t_0, t_1].
TEST(CouplingProtocol, FirstStepHoldsTheInitialWrench) {
  const CouplingConfig c = config(2);
  LoopbackLink link(2);
  ScriptedTrack track(c, link.trackEnd(), [](double t, int i, Eigen::Vector3d& f, Eigen::Vector3d& n) {
    f = Eigen::Vector3d(1.0 + i, 2.0, 3.0) * (1.0 + 1e5 * t);
    n = Eigen::Vector3d(-1.0, 0.5 * i, 7.0) * (1.0 + 1e5 * t);
  });
  VehicleCoupling v(c, link.vehicleEnd());
  Eigen::Vector3d f, n;
  EXPECT_EQ(v.framesReceived(), 0);
  v.wrenchAt(0.0, 1, f, n);
  EXPECT_EQ(f, Eigen::Vector3d::Zero());
  EXPECT_EQ(n, Eigen::Vector3d::Zero());
  EXPECT_EQ(v.nextExchangeTime(), 0.0);

  fillStates(v, 2);
  ASSERT_TRUE(v.exchange()) << v.exchange().message;
  EXPECT_EQ(v.framesReceived(), 1);
  EXPECT_EQ(v.nextExchangeTime(), c.track_step);
  for (double t : {0.0, 0.5 * c.track_step, c.track_step}) {
    v.wrenchAt(t, 1, f, n);  // exactly the step-0 values, whatever t
    EXPECT_EQ(f, Eigen::Vector3d(2.0, 2.0, 3.0));
    EXPECT_EQ(n, Eigen::Vector3d(-1.0, 0.5, 7.0));
  }
  v.close();
}

// A wrench history linear in time is extrapolated exactly (up to rounding: tolerance 1e-12 relative,
// a few ulps of the O(1e4 N) values after the O(1) operations of the extrapolation).
TEST(CouplingProtocol, ExtrapolationIsExactForLinearHistory) {
  const CouplingConfig c = config(4, 1e-4);
  LoopbackLink link(4);
  auto linear = [](double t, int i, Eigen::Vector3d& f, Eigen::Vector3d& n) {
    f = Eigen::Vector3d(1e4 + 100 * i, -2e3, 5e4) + t * Eigen::Vector3d(3e6, -1e6 * (i + 1), 2e5);
    n = Eigen::Vector3d(10.0 * i, 20.0, -30.0) + t * Eigen::Vector3d(-4e4, 1e3, 7e3 * i);
  };
  ScriptedTrack track(c, link.trackEnd(), linear);
  VehicleCoupling v(c, link.vehicleEnd());
  for (int k = 0; k < 20; ++k) {
    fillStates(v, 4);
    ASSERT_TRUE(v.exchange());
    if (v.framesReceived() < 2) continue;
    const double tk = static_cast<double>(k) * c.track_step;
    for (double theta : {0.0, 0.25, 0.5, 1.0}) {
      const double t = tk + theta * c.track_step;
      for (int i = 0; i < 4; ++i) {
        Eigen::Vector3d f, n, f_exact, n_exact;
        v.wrenchAt(t, i, f, n);
        linear(t, i, f_exact, n_exact);
        EXPECT_LE((f - f_exact).norm(), 1e-12 * f_exact.norm()) << "k " << k << " theta " << theta;
        EXPECT_LE((n - n_exact).norm(), 1e-12 * std::max(1.0, n_exact.norm())) << "k " << k;
      }
    }
  }
  v.close();
}

// For W(t) = a t^2 the linear extrapolation from t_{k-1}, t_k has the closed-form error
// W(t) - P(t) = a (t - t_k)(t - t_{k-1}) (Lagrange remainder, W'' = 2a constant): at t_k + theta h it is
// a h^2 theta (1 + theta), O(h^2), at most W'' h^2 over one step. Checked to 1e-9 relative (rounding of
// values ~a t^2 against differences ~a h^2), and halving h divides the error by 4.
TEST(CouplingProtocol, ExtrapolationErrorIsSecondOrderForQuadraticHistory) {
  const double a = 2.5e9;  // [N/s^2]
  auto run = [&](double h, double theta) {
    const CouplingConfig c = config(1, h);
    LoopbackLink link(1);
    ScriptedTrack track(c, link.trackEnd(), [&](double t, int, Eigen::Vector3d& f, Eigen::Vector3d& n) {
      f = Eigen::Vector3d(a * t * t, 0.0, -a * t * t);
      n = Eigen::Vector3d::Zero();
    });
    VehicleCoupling v(c, link.vehicleEnd());
    const int steps = static_cast<int>(std::lround(1e-3 / h));  // end at t_k = 1 ms whatever h
    for (int k = 0; k <= steps; ++k) {
      fillStates(v, 1);
      EXPECT_TRUE(v.exchange());
    }
    v.close();
    const double tk = static_cast<double>(steps) * h;
    const double t = tk + theta * h;
    Eigen::Vector3d f, n;
    v.wrenchAt(t, 0, f, n);
    const double error = a * t * t - f.x();
    const double predicted = a * (t - tk) * (t - (tk - h));
    EXPECT_NEAR(error, predicted, 1e-9 * a * t * t) << "h " << h << " theta " << theta;
    EXPECT_LE(std::abs(error), 2.0 * a * h * h * (1 + 1e-6));  // W'' h^2
    return error;
  };
  for (double theta : {0.5, 1.0}) {
    const double e1 = run(2e-5, theta);
    const double e2 = run(1e-5, theta);
    EXPECT_NEAR(e1 / e2, 4.0, 1e-3) << "theta " << theta;  // O(h^2)
  }
}

// 1000 exchanges: the track sees every step once and in order, the vehicle gets f(step) back.
TEST(CouplingProtocol, LoopbackThousandStepsInOrder) {
  const CouplingConfig c = config(8);
  LoopbackLink link(8);
  auto f_of_step = [&](double t, int i, Eigen::Vector3d& f, Eigen::Vector3d& n) {
    const double k = std::round(t / c.track_step);
    f = Eigen::Vector3d(k, -k, 1000.0 + i);
    n = Eigen::Vector3d(2 * k, i, 0.0);
  };
  ScriptedTrack track(c, link.trackEnd(), f_of_step);
  VehicleCoupling v(c, link.vehicleEnd());
  for (std::uint64_t k = 0; k < 1000; ++k) {
    ASSERT_EQ(v.nextStep(), k);
    ASSERT_EQ(v.nextExchangeTime(), static_cast<double>(k) * c.track_step);
    fillStates(v, 8);
    const Result r = v.exchange();
    ASSERT_TRUE(r) << r.message;
    const WrenchFrame& w = v.lastWrenches();
    ASSERT_EQ(w.step, k);
    ASSERT_EQ(w.scene_hash, kHash);
    for (int i = 0; i < 8; ++i) {
      ASSERT_EQ(w.wheels[i].f_wheel_in_world, Eigen::Vector3d(double(k), -double(k), 1000.0 + i));
      ASSERT_EQ(w.wheels[i].n_wheel_in_world, Eigen::Vector3d(2.0 * k, i, 0.0));
    }
  }
  v.close();
  track.thread.join();
  ASSERT_EQ(track.seen_steps.size(), 1000u);
  for (std::uint64_t k = 0; k < 1000; ++k) ASSERT_EQ(track.seen_steps[k], k);
  EXPECT_EQ(track.bad_states, 0);
  // The vehicle's close ends the track's next wait as "peer closed", naming both roles and the step.
  EXPECT_EQ(track.last.status, Status::kPeerClosed);
  EXPECT_EQ(track.last.message, "track: waiting for the wheel states of step 1000: the vehicle closed the connection");
  EXPECT_EQ(exitCode(track.last.status), kExitPeerTimeout);
}

// The track refuses a frame with another scene hash, a skipped step and a repeated step.
TEST(CouplingProtocol, TrackRefusesWrongHashAndStep) {
  const CouplingConfig c = config(2, 0.005);
  auto frame = [&](std::uint64_t step, std::uint64_t hash) {
    WheelStateFrame f(2);
    f.step = step;
    f.time = static_cast<double>(step) * c.track_step;
    f.scene_hash = hash;
    f.count = 2;
    return f;
  };
  const Deadline soon = Clock::now() + std::chrono::seconds(5);
  {
    LoopbackLink link(2);
    TrackCoupling track(c, link.trackEnd());
    ASSERT_TRUE(link.vehicleEnd().sendStates(frame(0, 0xabcdef), soon));
    const Result r = track.receive();
    EXPECT_EQ(r.status, Status::kRefused);
    EXPECT_EQ(r.message,
              "track: wheel states from the vehicle refused at step 0: scene hash 0000000000abcdef received, "
              "00c0ffee12345678 expected");
    EXPECT_EQ(exitCode(r.status), kExitPeerRefused);
    // The coupling stays failed.
    EXPECT_EQ(track.receive().status, Status::kError);
  }
  for (std::uint64_t bad : {2u, 0u}) {
    LoopbackLink link(2);
    TrackCoupling track(c, link.trackEnd());
    WrenchFrame answer(2);
    ASSERT_TRUE(link.vehicleEnd().sendStates(frame(0, kHash), soon));
    ASSERT_TRUE(track.receive());
    ASSERT_TRUE(track.send());
    ASSERT_TRUE(link.vehicleEnd().receiveWrenches(answer, soon));
    EXPECT_EQ(answer.step, 0u);
    ASSERT_TRUE(link.vehicleEnd().sendStates(frame(bad, kHash), soon));
    const Result r = track.receive();
    EXPECT_EQ(r.status, Status::kRefused);
    EXPECT_EQ(r.message, "track: wheel states from the vehicle refused at step 1: step " + std::to_string(bad) +
                             " received, 1 expected (" + (bad == 2 ? "step skipped" : "step repeated") + ")");
  }
  {  // Another wheel count.
    LoopbackLink link(2);
    TrackCoupling track(c, link.trackEnd());
    WheelStateFrame f = frame(0, kHash);
    f.count = 1;
    ASSERT_TRUE(link.vehicleEnd().sendStates(f, soon));
    const Result r = track.receive();
    EXPECT_EQ(r.status, Status::kRefused);
    EXPECT_EQ(r.message, "track: wheel states from the vehicle refused at step 0: 1 wheels received, 2 expected");
  }
  {  // A time that does not belong to the step.
    LoopbackLink link(2);
    TrackCoupling track(c, link.trackEnd());
    WheelStateFrame f = frame(0, kHash);
    f.time = 0.0025;
    ASSERT_TRUE(link.vehicleEnd().sendStates(f, soon));
    const Result r = track.receive();
    EXPECT_EQ(r.status, Status::kRefused);
    EXPECT_EQ(r.message,
              "track: wheel states from the vehicle refused at step 0: time 0.0025 s received, 0 s expected "
              "(step 0 x track_step 0.005 s)");
  }
}

// The vehicle refuses wrenches of another step or scene.
TEST(CouplingProtocol, VehicleRefusesWrongAnswer) {
  const CouplingConfig c = config(2, 0.005);
  const Deadline soon = Clock::now() + std::chrono::seconds(5);
  LoopbackLink link(2);
  VehicleCoupling v(c, link.vehicleEnd());
  WheelStateFrame got(2);
  std::thread fake_track([&] {
    ASSERT_TRUE(link.trackEnd().receiveStates(got, soon));
    WrenchFrame w(2);
    w.step = 7;
    w.time = 3.5;
    w.scene_hash = kHash;
    w.count = 2;
    ASSERT_TRUE(link.trackEnd().sendWrenches(w, soon));
  });
  const Result r = v.exchange();
  fake_track.join();
  EXPECT_EQ(r.status, Status::kRefused);
  EXPECT_EQ(r.message,
            "vehicle: contact wrenches from the track refused at step 0: step 7 received, 0 expected (step "
            "skipped)");
  EXPECT_EQ(v.framesReceived(), 0);  // the refused frame did not enter the extrapolation
}

// A track that never answers: the exchange returns kTimeout after the exchange timeout. Slack 0.25 s
// for scheduling on a loaded machine (the wait itself sleeps in slices of at most 20 ms).
TEST(CouplingProtocol, SilentPeerTimesOut) {
  const CouplingConfig c = config(2, 2e-5, 0.3);
  LoopbackLink link(2);
  VehicleCoupling v(c, link.vehicleEnd());
  const auto t0 = Clock::now();
  const Result r = v.exchange();
  const double elapsed = secondsSince(t0);
  EXPECT_EQ(r.status, Status::kTimeout);
  EXPECT_GE(elapsed, 0.3);
  EXPECT_LE(elapsed, 0.3 + 0.25);
  EXPECT_EQ(r.message,
            "vehicle: waiting for the contact wrenches of step 0: the track did not answer within 0.3 s "
            "(solver.exchange_timeout)");
  EXPECT_EQ(exitCode(r.status), kExitPeerTimeout);

  TrackCoupling track(c, link.trackEnd());  // nothing more comes from the (failed) vehicle
  const auto t1 = Clock::now();
  const Result rt = track.receive();
  EXPECT_EQ(rt.status, Status::kOk) << rt.message;  // the states of step 0 were handed over
  ASSERT_TRUE(track.send());
  const Result r2 = track.receive();
  const double elapsed2 = secondsSince(t1);
  EXPECT_EQ(r2.status, Status::kTimeout);
  EXPECT_LE(elapsed2, 0.3 + 0.25);
  EXPECT_EQ(r2.message,
            "track: waiting for the wheel states of step 1: the vehicle did not answer within 0.3 s "
            "(solver.exchange_timeout)");
}

// The caller's interrupt flag ends a wait promptly (within 0.25 s of being raised; slices are 20 ms).
TEST(CouplingProtocol, InterruptEndsTheWait) {
  std::atomic<bool> stop{false};
  const CouplingConfig c = config(2, 2e-5, 30.0);
  LoopbackLink link(2, &stop);
  TrackCoupling track(c, link.trackEnd());
  std::thread raiser([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    stop = true;
  });
  const auto t0 = Clock::now();
  const Result r = track.receive();
  raiser.join();
  EXPECT_EQ(r.status, Status::kInterrupted);
  EXPECT_LE(secondsSince(t0), 0.1 + 0.25);
  EXPECT_EQ(r.message, "track: waiting for the wheel states of step 0: interrupted");
  EXPECT_EQ(exitCode(r.status), kExitInterrupted);
}

TEST(CouplingProtocol, NonPhysicalConfigIsRefused) {
  LoopbackLink link(2);
  CouplingConfig c = config(2);
  c.track_step = -1e-5;
  try {
    VehicleCoupling v(c, link.vehicleEnd());
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "coupling: solver.track_step must be between 1e-07 and 0.01 s, got -1e-05");
  }
  c = config(2);
  c.exchange_timeout = 0.0;
  EXPECT_THROW(TrackCoupling(c, link.trackEnd()), std::runtime_error);
  c = config(0);
  EXPECT_THROW(TrackCoupling(c, link.trackEnd()), std::runtime_error);
}

TEST(CouplingProtocol, SendBeforeReceiveIsAnError) {
  LoopbackLink link(2);
  TrackCoupling track(config(2), link.trackEnd());
  const Result r = track.send();
  EXPECT_EQ(r.status, Status::kError);
  EXPECT_EQ(r.message, "track: send() called before receive() for step 0");
}

TEST(CouplingProtocol, ConfigFromScene) {
  Scene s;
  s.has_vehicle = true;
  s.vehicle.wheelsets = 4;
  s.solver.track_step = 1e-5;
  s.solver.exchange_timeout = 3.0;
  s.hash = 42;
  const CouplingConfig c = couplingConfig(s);
  EXPECT_EQ(c.track_step, 1e-5);
  EXPECT_EQ(c.exchange_timeout, 3.0);
  EXPECT_EQ(c.scene_hash, 42u);
  EXPECT_EQ(c.wheel_count, 8);
}
