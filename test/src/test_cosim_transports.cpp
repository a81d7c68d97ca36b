// rostest (cosim_transports.test): the co-simulation protocol between two ROS nodes over each transport
// in turn: this program is the synthetic vehicle (VehicleCoupling, states g(t)); for every run it starts
// the synthetic track node transport_track_peer (TrackCoupling, wrenches f(step, states)) itself, so that
// it can also kill it.
//
// Checks, for service, topic and shm, 2000 steps each: every step answered once and in order with exactly
// f(k, g(t_k)) (vehicle side) and every step's states received once, in order and exactly g(t_k) (track
// side, its exit code); the wrenches the vehicle extrapolates identical bit for bit across the three
// transports and equal to the linear extrapolation of f; that killing the track node mid-run makes the
// vehicle's next exchange fail with kTimeout or kPeerClosed naming the track within the exchange timeout;
// and that a track node that hangs gives kTimeout at the deadline.
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <ros/ros.h>

#include "cosim_synthetic.hpp"

#ifndef RAILSIM_TRACK_PEER
#error "RAILSIM_TRACK_PEER (path of the transport_track_peer program) must be defined"
#endif

using namespace rail::core::coupling;
using namespace railsim_test;

namespace {

constexpr long kSteps = 2000;
const char* const kVehicleNode = "cosim_transports_vehicle";

// The ROS node of this program, started once and kept for all tests (the last NodeHandle going away
// would shut roscpp down).
ros::NodeHandle& node() {
  static std::unique_ptr<ros::NodeHandle> nh;
  if (!nh) {
    ros::init(ros::M_string{}, kVehicleNode, ros::init_options::NoSigintHandler);
    nh = std::make_unique<ros::NodeHandle>();
  }
  return *nh;
}

// A track node started as a child process; killed and reaped when the object goes away.
class TrackPeer {
 public:
  TrackPeer(const std::string& kind, const RunNames& names, const std::string& node_name, long steps) {
    std::vector<std::string> args = {
        RAILSIM_TRACK_PEER,    kind, names.prefix, names.run_id, ros::this_node::getName(), std::to_string(steps),
        "__name:=" + node_name};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_ = fork();
    if (pid_ == 0) {
      prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlive the test
      execv(argv[0], argv.data());
      _exit(127);
    }
  }
  ~TrackPeer() {
    if (pid_ > 0 && !reaped_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  pid_t pid() const { return pid_; }
  // Exit code once the process ended within `timeout_s`; -1 if it did not (or died of a signal).
  int waitExit(double timeout_s) {
    const auto end =
        Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
    int status = 0;
    while (Clock::now() < end) {
      const pid_t r = waitpid(pid_, &status, WNOHANG);
      if (r == pid_) {
        reaped_ = true;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return -1;
  }
  void killNow() {
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    reaped_ = true;
  }

 private:
  pid_t pid_ = -1;
  bool reaped_ = false;
};

RunNames namesFor(const std::string& run) { return {"/cosim_" + run, "cosim" + std::to_string(getpid()) + run}; }

// Bits of a double, for exact comparison (also of -0.0 against 0.0).
std::uint64_t bits(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

// One run of kSteps exchanges over `kind`: after each exchange k the vehicle extrapolates the wrenches to
// t_k + h/2; all of them (steps x wheels x 6 components) are appended to `extrapolated`.
void runCosim(const std::string& kind, std::vector<double>& extrapolated) {
  ros::NodeHandle& nh = node();
  const RunNames names = namesFor(kind);
  const std::string track_node = "/cosim_track_" + kind;
  TrackPeer peer(kind, names, track_node.substr(1), kSteps);
  ASSERT_GT(peer.pid(), 0);
  std::unique_ptr<FrameTransport> transport;
  ASSERT_NO_THROW(transport = makeTransport(kind, Role::kVehicle, names, nh, track_node));
  VehicleCoupling vehicle(config(10.0), *transport);
  WrenchFrame out(kWheels);
  WheelState g;
  WheelWrench f, f_previous;
  extrapolated.clear();
  extrapolated.reserve(kSteps * kWheels * 6);
  for (long k = 0; k < kSteps; ++k) {
    const double t_k = static_cast<double>(k) * kTrackStep;
    for (int i = 0; i < kWheels; ++i) wheelStateAt(t_k, i, vehicle.states().wheels[i]);
    const Result r = vehicle.exchange();
    ASSERT_TRUE(r.ok()) << kind << ": " << r.message;
    // Step k answered once and in order, with exactly f(k, g(t_k)) (both sides evaluate the same code on
    // the same bits: no tolerance).
    const WrenchFrame& w = vehicle.lastWrenches();
    ASSERT_EQ(w.step, static_cast<std::uint64_t>(k)) << kind;
    ASSERT_EQ(w.count, static_cast<std::uint32_t>(kWheels)) << kind;
    for (int i = 0; i < kWheels; ++i) {
      wheelStateAt(t_k, i, g);
      wrenchFor(static_cast<std::uint64_t>(k), throughWire(g), f);
      ASSERT_EQ(w.wheels[i].f_wheel_in_world, f.f_wheel_in_world) << kind << " step " << k << " wheel " << i;
      ASSERT_EQ(w.wheels[i].n_wheel_in_world, f.n_wheel_in_world) << kind << " step " << k << " wheel " << i;
    }
    // The extrapolation to t_k + h/2: W_k for k = 0, else W_k + theta (W_k - W_{k-1}) with theta = 1/2 up to
    // the rounding of k h, (t - t_k)/(t_k - t_{k-1}) = 0.5 (1 + O(k eps)): a relative 1e-9 of the terms'
    // size covers it with a wide margin (k eps < 1e-12 here).
    const double t = t_k + 0.5 * kTrackStep;
    vehicle.extrapolate(t, out);
    for (int i = 0; i < kWheels; ++i) {
      wheelStateAt(t_k, i, g);
      wrenchFor(static_cast<std::uint64_t>(k), throughWire(g), f);
      Eigen::Matrix<double, 6, 1> expected, got, scale;
      expected << f.f_wheel_in_world, f.n_wheel_in_world;
      scale = expected.cwiseAbs();
      if (k > 0) {
        wheelStateAt(t_k - kTrackStep, i, g);
        wrenchFor(static_cast<std::uint64_t>(k - 1), throughWire(g), f_previous);
        Eigen::Matrix<double, 6, 1> previous;
        previous << f_previous.f_wheel_in_world, f_previous.n_wheel_in_world;
        scale += (expected - previous).cwiseAbs();
        expected += 0.5 * (expected - previous);
      }
      got << out.wheels[i].f_wheel_in_world, out.wheels[i].n_wheel_in_world;
      for (int c = 0; c < 6; ++c) {
        ASSERT_NEAR(got[c], expected[c], 1e-9 * scale[c] + 1e-300) << kind << " step " << k << " wheel " << i;
        extrapolated.push_back(got[c]);
      }
    }
  }
  vehicle.close();
  transport.reset();
  // The track saw every step once, in order, with exactly g(t_k), and ended on the vehicle's close.
  EXPECT_EQ(peer.waitExit(20.0), 0) << kind << ": the track node reported a failure (see its output above)";
}

TEST(CosimTransports, SameWrenchesOverServiceTopicAndShm) {
  std::map<std::string, std::vector<double>> runs;
  for (const std::string kind : {"service", "topic", "shm"}) {
    SCOPED_TRACE(kind);
    ASSERT_NO_FATAL_FAILURE(runCosim(kind, runs[kind]));
    ASSERT_EQ(runs[kind].size(), static_cast<std::size_t>(kSteps * kWheels * 6));
  }
  // Bit for bit: the transports only copy doubles (ROS messages carry them as float64), and the vehicle
  // rebuilds t_k = k h from the step index, so the extrapolations cannot differ at all.
  for (const std::string kind : {"topic", "shm"}) {
    std::size_t differing = 0, first = 0;
    for (std::size_t j = 0; j < runs[kind].size(); ++j)
      if (bits(runs[kind][j]) != bits(runs["service"][j]) && differing++ == 0) first = j;
    EXPECT_EQ(differing, 0u) << kind << " differs from service, first at value " << first << " (step "
                             << first / (kWheels * 6) << ")";
  }
}

// Killing the track node mid-run: the vehicle's next exchange fails with kTimeout or kPeerClosed, names
// the track, and returns within the exchange timeout (plus scheduling slack).
class KilledTrack : public ::testing::TestWithParam<const char*> {};

TEST_P(KilledTrack, VehicleReportsItWithinTheExchangeTimeout) {
  const std::string kind = GetParam();
  ros::NodeHandle& nh = node();
  const RunNames names = namesFor(kind + "_kill");
  const std::string track_node = "/cosim_track_" + kind + "_kill";
  TrackPeer peer(kind, names, track_node.substr(1), kSteps);
  ASSERT_GT(peer.pid(), 0);
  std::unique_ptr<FrameTransport> transport;
  ASSERT_NO_THROW(transport = makeTransport(kind, Role::kVehicle, names, nh, track_node));
  const double exchange_timeout = 3.0;  // [s]
  VehicleCoupling vehicle(config(exchange_timeout), *transport);
  for (long k = 0; k < 200; ++k) {
    for (int i = 0; i < kWheels; ++i) wheelStateAt(static_cast<double>(k) * kTrackStep, i, vehicle.states().wheels[i]);
    const Result r = vehicle.exchange();
    ASSERT_TRUE(r.ok()) << kind << " step " << k << ": " << r.message;
  }
  peer.killNow();
  for (int i = 0; i < kWheels; ++i) wheelStateAt(200 * kTrackStep, i, vehicle.states().wheels[i]);
  const auto t0 = Clock::now();
  const Result r = vehicle.exchange();
  const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_FALSE(r.ok());
  EXPECT_TRUE(r.status == Status::kTimeout || r.status == Status::kPeerClosed)
      << toString(r.status) << ": " << r.message;
  // Slack of 1 s over the timeout for a loaded machine (a timeout itself takes exactly exchange_timeout).
  EXPECT_LT(elapsed, exchange_timeout + 1.0) << r.message;
  EXPECT_NE(r.message.find("the track"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("step 200"), std::string::npos) << r.message;
  if (kind != "shm") EXPECT_NE(r.message.find(track_node), std::string::npos) << r.message;  // the node by name
  std::printf("%s: track killed at step 200, reported after %.3f s: %s\n", kind.c_str(), elapsed, r.message.c_str());
  vehicle.close();
}

INSTANTIATE_TEST_SUITE_P(Transports, KilledTrack, ::testing::Values("service", "topic", "shm"));

// A track node that never answers (stopped with SIGSTOP: alive, connections open): the vehicle's exchange
// returns kTimeout at its deadline, not before and not much after; once the node is killed the vehicle
// closes without hanging.
class HungTrack : public ::testing::TestWithParam<const char*> {};

TEST_P(HungTrack, VehicleTimesOutAtTheDeadline) {
  const std::string kind = GetParam();
  ros::NodeHandle& nh = node();
  const RunNames names = namesFor(kind + "_hung");
  const std::string track_node = "/cosim_track_" + kind + "_hung";
  TrackPeer peer(kind, names, track_node.substr(1), kSteps);
  ASSERT_GT(peer.pid(), 0);
  std::unique_ptr<FrameTransport> transport;
  ASSERT_NO_THROW(transport = makeTransport(kind, Role::kVehicle, names, nh, track_node));
  const double exchange_timeout = 1.0;  // [s]
  VehicleCoupling vehicle(config(exchange_timeout), *transport);
  for (long k = 0; k < 50; ++k) {
    for (int i = 0; i < kWheels; ++i) wheelStateAt(static_cast<double>(k) * kTrackStep, i, vehicle.states().wheels[i]);
    const Result r = vehicle.exchange();
    ASSERT_TRUE(r.ok()) << kind << " step " << k << ": " << r.message;
  }
  ASSERT_EQ(kill(peer.pid(), SIGSTOP), 0);
  for (int i = 0; i < kWheels; ++i) wheelStateAt(50 * kTrackStep, i, vehicle.states().wheels[i]);
  const auto t0 = Clock::now();
  const Result r = vehicle.exchange();
  const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_EQ(r.status, Status::kTimeout) << r.message;
  // Not before the deadline; at most 0.5 s after it (wait slices are 20-50 ms; slack for a loaded machine).
  EXPECT_GE(elapsed, exchange_timeout);
  EXPECT_LT(elapsed, exchange_timeout + 0.5);
  EXPECT_NE(r.message.find("the track did not answer within 1 s"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("step 50"), std::string::npos) << r.message;
  if (kind != "shm") EXPECT_NE(r.message.find(track_node), std::string::npos) << r.message;
  std::printf("%s: track stopped at step 50, reported after %.3f s: %s\n", kind.c_str(), elapsed, r.message.c_str());
  peer.killNow();
  const auto t1 = Clock::now();
  vehicle.close();
  transport.reset();
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - t1).count(), 3.0) << "closing took too long";
}

INSTANTIATE_TEST_SUITE_P(Transports, HungTrack, ::testing::Values("service", "topic", "shm"));

}  // namespace
