// Round-trip time of one co-simulation exchange (the vehicle sends 8 wheel states, the track answers 8
// wrenches, through VehicleCoupling and TrackCoupling) over the ROS service, the ROS topic and the
// shared-memory transports, between two processes that are two ROS nodes. Prints median and 99th
// percentile; not a test.
//
// Needs a ROS master: `roslaunch test/bench_transports.launch` (starts one), or with a running roscore
// `rosrun rail_ros railsim_bench_transports`. The program forks its track end itself.
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <ros/ros.h>

#include "rail_contact/tool_args.hpp"
#include "rail_core/coupling/exchange_bench.hpp"
#include "rail_core/coupling/protocol.hpp"
#include "rail_core/coupling/shm_transport.hpp"
#include "rail_ros/service_transport.hpp"
#include "rail_ros/topic_transport.hpp"

using namespace rail::core::coupling;
using namespace rail::ros_glue;

namespace {
const char* const kUsage =
    "usage: railsim_bench_transports [exchanges] [service,topic,shm]\n"
    "Round-trip time of one co-simulation exchange over each ROS transport and shared memory, between two\n"
    "processes (needs a ROS master). Defaults: 20000 exchanges, all three transports.\n";

namespace bench = rail::core::coupling::bench;
const CouplingConfig kConfig = bench::config(0xbe9c000000000002ull);

struct Names {
  std::string prefix;  // "/railsim_bench_<pid>"
  std::string run_id;  // shm run id
};

// One endpoint of the named transport for `role`.
std::unique_ptr<FrameTransport> make(const std::string& kind, Role role, const Names& names, ros::NodeHandle& nh) {
  auto common = [role](auto& options) {
    options.role = role;
    options.wheel_capacity = bench::kWheels;
  };
  if (kind == "shm") {
    ShmOptions o;
    common(o);
    o.scene_hash = kConfig.scene_hash;
    o.run_id = names.run_id;
    return std::make_unique<ShmTransport>(o);
  }
  if (kind == "service") {
    ServiceTransportOptions o;
    common(o);
    o.track_step = bench::kTrackStep;
    o.service = names.prefix + "/lockstep";
    return std::make_unique<ServiceTransport>(nh, o);
  }
  if (kind == "topic") {
    TopicTransportOptions o;
    common(o);
    o.track_step = bench::kTrackStep;
    o.states_topic = names.prefix + "/wheel_states_exchange";
    o.wrenches_topic = names.prefix + "/contact_wrenches_exchange";
    return std::make_unique<TopicTransport>(nh, o);
  }
  throw std::runtime_error("unknown transport '" + kind + "' (service, topic or shm)");
}

// Remappings from the command line except the node name and log file roslaunch gives (the two
// processes name themselves).
ros::M_string remappings(int argc, char** argv, std::vector<std::string>& rest) {
  ros::M_string m;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto eq = a.find(":=");
    if (eq == std::string::npos) {
      rest.push_back(a);
      continue;
    }
    const std::string key = a.substr(0, eq);
    if (key != "__name" && key != "__log") m[key] = a.substr(eq + 2);
  }
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  if (rail::tools::startTool(argc, argv, kUsage, rail::tools::kOwnOptions)) return 0;  // ROS remappings too
  std::vector<std::string> args;
  const ros::M_string remap = remappings(argc, argv, args);
  char* end = nullptr;
  const long steps = !args.empty() ? std::strtol(args[0].c_str(), &end, 10) : 20000;
  if (!args.empty() && *end != '\0') {
    std::fprintf(stderr, "railsim_bench_transports: '%s' is not a number of exchanges\n%s", args[0].c_str(), kUsage);
    return 2;
  }
  std::vector<std::string> kinds = {"service", "topic", "shm"};
  if (args.size() > 1) {
    kinds.clear();
    std::stringstream ss(args[1]);
    for (std::string k; std::getline(ss, k, ',');) kinds.push_back(k);
  }
  if (steps <= 0) {
    std::fprintf(stderr, "usage: railsim_bench_transports [exchanges > 0] [service,topic,shm]\n");
    return 2;
  }
  const long warmup = std::min(steps / 10, 2000L);
  Names names;
  names.prefix = "/railsim_bench_" + std::to_string(getpid());
  names.run_id = "bench" + std::to_string(getpid());

  const pid_t parent = getpid();
  const pid_t child = fork();
  if (child < 0) {
    std::perror("fork");
    return 6;
  }
  if (child == 0) {  // track node
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(5);
    ros::init(remap, "railsim_bench_track_" + std::to_string(parent), ros::init_options::NoSigintHandler);
    if (!ros::master::check()) _exit(4);
    ros::NodeHandle nh;
    int code = 0;
    for (const std::string& kind : kinds) {
      try {
        auto t = make(kind, Role::kTrack, names, nh);
        code = bench::answerExchanges(*t, kConfig, std::numeric_limits<long>::max());
      } catch (const std::exception& e) {
        std::fprintf(stderr, "track (%s): %s\n", kind.c_str(), e.what());
        code = 3;
      }
      if (code != 0) break;
    }
    ros::shutdown();
    _exit(code);
  }

  ros::init(remap, "railsim_bench_vehicle_" + std::to_string(getpid()), ros::init_options::NoSigintHandler);
  if (!ros::master::check()) {
    std::fprintf(stderr,
                 "railsim_bench_transports needs a ROS master (%s): start roscore, or run "
                 "roslaunch test/bench_transports.launch\n",
                 ros::master::getURI().c_str());
    kill(child, SIGKILL);
    waitpid(child, nullptr, 0);
    return 4;
  }
  ros::NodeHandle nh;
  std::printf(
      "round trip of one exchange, %d wheels, two processes, %u hardware threads, %ld exchanges after %ld "
      "warm-up\n",
      bench::kWheels, std::thread::hardware_concurrency(), steps, warmup);
  bool ok = true;
  for (const std::string& kind : kinds) {
    std::vector<double> rtt;
    bool run_ok = false;
    try {
      auto t = make(kind, Role::kVehicle, names, nh);
      run_ok = bench::timeExchanges(*t, kConfig, warmup, steps, rtt);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "vehicle (%s): %s\n", kind.c_str(), e.what());
    }
    if (run_ok) bench::report(kind.c_str(), 8, rtt);
    ok = ok && run_ok;
    if (!ok) break;
  }
  int status = 0;
  if (!ok) kill(child, SIGKILL);
  waitpid(child, &status, 0);
  ros::shutdown();
  ok = ok && WIFEXITED(status) && WEXITSTATUS(status) == 0;
  if (!ok)
    std::fprintf(stderr, "benchmark failed (track exit status %d)\n", WIFEXITED(status) ? WEXITSTATUS(status) : -1);
  return ok ? 0 : 1;
}
