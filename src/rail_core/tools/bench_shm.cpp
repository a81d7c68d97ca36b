// Round-trip time of one co-simulation exchange (vehicle sends 8 wheel states, track answers 8 wrenches)
// through the protocol objects: shm transport between two processes (spinning, then futex sleep; and
// futex sleep only), and the in-process loopback between two threads for comparison.
//
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "rail_contact/tool_args.hpp"
#include "rail_core/coupling/loopback_transport.hpp"
#include "rail_core/coupling/protocol.hpp"
#include "rail_core/coupling/shm_transport.hpp"

using namespace rail::core::coupling;

namespace {
const char* const kUsage =
    "usage: railsim_bench_shm [exchanges]\n"
    "Round-trip time of one co-simulation exchange (8 wheel states, 8 wrenches) over shared memory between\n"
    "two processes (spin, yield, then futex; futex only) and in-process between two threads. Default 100000.\n";
}  // namespace

namespace {

constexpr int kWheels = 8;

CouplingConfig benchConfig() {
  CouplingConfig c;
  c.track_step = 2e-5;
  c.exchange_timeout = 10.0;
  c.scene_hash = 0xbe9c000000000001ull;
  c.wheel_count = kWheels;
  return c;
}

// Answers `steps` steps with a wrench made from the states; returns 0 if all went well.
int trackLoop(FrameTransport& t, long steps) {
  TrackCoupling track(benchConfig(), t);
  for (long k = 0; k < steps; ++k) {
    if (!track.receive()) return 1;
    for (int i = 0; i < kWheels; ++i) {
      track.wrenches().wheels[i].f_wheel_in_world = 1e3 * track.states().wheels[i].p_wheel_in_world;
      track.wrenches().wheels[i].n_wheel_in_world = track.states().wheels[i].omega_wheelset_in_world;
    }
    if (!track.send()) return 2;
  }
  return 0;
}

// Times `steps` exchanges (after `warmup` untimed ones); fills round-trip times [s].
bool vehicleLoop(FrameTransport& t, long warmup, long steps, std::vector<double>& rtt) {
  VehicleCoupling v(benchConfig(), t);
  rtt.resize(static_cast<std::size_t>(steps));
  for (long k = 0; k < warmup + steps; ++k) {
    for (int i = 0; i < kWheels; ++i) {
      v.states().wheels[i].p_wheel_in_world = Eigen::Vector3d(1e-3 * k, i, 0.445);
      v.states().wheels[i].omega_wheelset_in_world = Eigen::Vector3d(0, 60.0, 0);
    }
    const auto t0 = Clock::now();
    const Result r = v.exchange();
    const auto t1 = Clock::now();
    if (!r) {
      std::fprintf(stderr, "%s\n", r.message.c_str());
      return false;
    }
    if (k >= warmup) rtt[static_cast<std::size_t>(k - warmup)] = std::chrono::duration<double>(t1 - t0).count();
  }
  return true;
}

void report(const char* what, std::vector<double>& rtt) {
  std::sort(rtt.begin(), rtt.end());
  const auto at = [&](double q) { return rtt[static_cast<std::size_t>(q * static_cast<double>(rtt.size() - 1))]; };
  double sum = 0;
  for (double x : rtt) sum += x;
  std::printf("%-44s n %zu  median %8.2f us  p99 %8.2f us  mean %8.2f us  max %9.1f us\n", what, rtt.size(),
              1e6 * at(0.5), 1e6 * at(0.99), 1e6 * sum / static_cast<double>(rtt.size()), 1e6 * rtt.back());
}

bool benchShm(const char* what, long warmup, long steps, double spin_time, double yield_time) {
  ShmOptions o;
  o.scene_hash = benchConfig().scene_hash;
  o.wheel_capacity = kWheels;
  o.run_id = "bench" + std::to_string(getpid());
  o.spin_time = spin_time;
  o.yield_time = yield_time;
  ShmOptions track_options = o;
  track_options.role = Role::kTrack;
  const pid_t child = fork();
  if (child == 0) {
    int code = 3;
    try {
      ShmTransport t(track_options);
      code = trackLoop(t, warmup + steps);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "track: %s\n", e.what());
    }
    _exit(code);
  }
  std::vector<double> rtt;
  bool ok = false;
  try {
    o.role = Role::kVehicle;
    ShmTransport t(o);
    ok = vehicleLoop(t, warmup, steps, rtt);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vehicle: %s\n", e.what());
  }
  int status = 0;
  if (!ok) kill(child, SIGKILL);
  waitpid(child, &status, 0);
  ok = ok && WIFEXITED(status) && WEXITSTATUS(status) == 0;
  if (ok) report(what, rtt);
  return ok;
}

bool benchLoopback(long warmup, long steps) {
  LoopbackLink link(kWheels);
  int track_code = -1;
  std::thread track([&] { track_code = trackLoop(link.trackEnd(), warmup + steps); });
  std::vector<double> rtt;
  const bool ok = vehicleLoop(link.vehicleEnd(), warmup, steps, rtt);
  if (!ok) link.vehicleEnd().close();
  track.join();
  if (ok && track_code == 0) report("loopback (2 threads, mutex + condvar)", rtt);
  return ok && track_code == 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (rail::tools::startTool(argc, argv, kUsage, 1)) return 0;
  const long steps = static_cast<long>(rail::tools::positionalNumber(argc, argv, 1, 100000, 1, kUsage));
  const long warmup = std::min(steps / 10, 10000L);
  std::printf("round trip of one exchange, %d wheels, %u hardware threads\n", kWheels,
              std::thread::hardware_concurrency());
  const ShmOptions defaults;
  const std::string label = "shm, 2 processes (spin " + std::to_string(std::lround(defaults.spin_time * 1e6)) +
                            " us, yield to " + std::to_string(std::lround(defaults.yield_time * 1e6)) + " us)";
  bool ok = benchShm(label.c_str(), warmup, steps, defaults.spin_time, defaults.yield_time);
  ok = benchShm("shm, 2 processes (futex only)", warmup, steps, 0.0, 0.0) && ok;
  ok = benchLoopback(warmup, steps) && ok;
  return ok ? 0 : 1;
}
