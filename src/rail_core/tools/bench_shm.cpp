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
#include "rail_core/coupling/exchange_bench.hpp"
#include "rail_core/coupling/loopback_transport.hpp"
#include "rail_core/coupling/protocol.hpp"
#include "rail_core/coupling/shm_transport.hpp"

using namespace rail::core::coupling;

namespace {
const char* const kUsage =
    "usage: railsim_bench_shm [exchanges]\n"
    "Round-trip time of one co-simulation exchange (8 wheel states, 8 wrenches) over shared memory between\n"
    "two processes (spin, yield, then futex; futex only) and in-process between two threads. Default 100000.\n";

namespace bench = rail::core::coupling::bench;
const CouplingConfig kConfig = bench::config(0xbe9c000000000001ull);

bool benchShm(const char* what, long warmup, long steps, double spin_time, double yield_time) {
  ShmOptions o;
  o.scene_hash = kConfig.scene_hash;
  o.wheel_capacity = bench::kWheels;
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
      code = bench::answerExchanges(t, kConfig, warmup + steps);
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
    ok = bench::timeExchanges(t, kConfig, warmup, steps, rtt);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vehicle: %s\n", e.what());
  }
  int status = 0;
  if (!ok) kill(child, SIGKILL);
  waitpid(child, &status, 0);
  ok = ok && WIFEXITED(status) && WEXITSTATUS(status) == 0;
  if (ok) bench::report(what, 44, rtt);
  return ok;
}

bool benchLoopback(long warmup, long steps) {
  LoopbackLink link(bench::kWheels);
  int track_code = -1;
  std::thread track([&] { track_code = bench::answerExchanges(link.trackEnd(), kConfig, warmup + steps); });
  std::vector<double> rtt;
  const bool ok = bench::timeExchanges(link.vehicleEnd(), kConfig, warmup, steps, rtt);
  if (!ok) link.vehicleEnd().close();
  track.join();
  if (ok && track_code == 0) bench::report("loopback (2 threads, mutex + condvar)", 44, rtt);
  return ok && track_code == 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (rail::tools::startTool(argc, argv, kUsage, 1)) return 0;
  const long steps = static_cast<long>(rail::tools::positionalNumber(argc, argv, 1, 100000, 1, kUsage));
  const long warmup = std::min(steps / 10, 10000L);
  std::printf("round trip of one exchange, %d wheels, %u hardware threads\n", bench::kWheels,
              std::thread::hardware_concurrency());
  const ShmOptions defaults;
  const std::string label = "shm, 2 processes (spin " + std::to_string(std::lround(defaults.spin_time * 1e6)) +
                            " us, yield to " + std::to_string(std::lround(defaults.yield_time * 1e6)) + " us)";
  bool ok = benchShm(label.c_str(), warmup, steps, defaults.spin_time, defaults.yield_time);
  ok = benchShm("shm, 2 processes (futex only)", warmup, steps, 0.0, 0.0) && ok;
  ok = benchLoopback(warmup, steps) && ok;
  return ok ? 0 : 1;
}
