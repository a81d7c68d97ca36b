#include "rail_ros/master_watch.hpp"

#include <ros/master.h>
#include <ros/param.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>

namespace rail::ros_glue {

namespace {
// The state outlives whichever of watch and thread ends last.
struct Shared : MasterWatch::State {
  std::atomic<int> owners{2};
};
void release(Shared* s) {
  if (s->owners.fetch_sub(1) == 1) delete s;
}
}  // namespace

MasterWatch::MasterWatch(std::atomic<bool>& stop, double period_s, int misses) : uri_(ros::master::getURI()) {
  auto* shared = new Shared();
  state_ = shared;
  std::thread([shared, &stop, period_s, misses] {
    int missed = 0;
    const auto step = std::chrono::milliseconds(50);
    while (!shared->quit.load()) {
      for (double waited = 0.0; waited < period_s && !shared->quit.load(); waited += 0.05) {
        std::this_thread::sleep_for(step);
      }
      if (shared->quit.load()) break;
      missed = ros::master::check() ? 0 : missed + 1;
      if (missed >= misses) {
        shared->lost.store(true);
        stop.store(true);
        break;
      }
    }
    release(shared);
  }).detach();
}

MasterWatch::~MasterWatch() {
  state_->quit.store(true);
  release(static_cast<Shared*>(state_));
}

std::string exitedPeer(const std::string& me) {
  XmlRpc::XmlRpcValue exits;
  if (!ros::param::get("/railsim/node_exit", exits) || exits.getType() != XmlRpc::XmlRpcValue::TypeStruct) {
    return "";
  }
  std::string run_id;
  ros::param::get("/railsim/run_id", run_id);
  const std::string my_name = me.substr(me.find_last_of('/') + 1);
  for (auto& [name, entry] : exits) {
    if (name == my_name || entry.getType() != XmlRpc::XmlRpcValue::TypeStruct || !entry.hasMember("code") ||
        entry["code"].getType() != XmlRpc::XmlRpcValue::TypeInt) {
      continue;
    }
    const bool same_run = entry.hasMember("run_id") && entry["run_id"].getType() == XmlRpc::XmlRpcValue::TypeString &&
                          static_cast<std::string>(entry["run_id"]) == run_id;
    if (!same_run) continue;
    const int code = entry["code"];
    return code < 0 ? name + " was killed by signal " + std::to_string(-code)
                    : name + " exited with code " + std::to_string(code);
  }
  return "";
}

int waitForMaster(const std::string& node, const std::atomic<int>& signal, double timeout_s) {
  const auto t0 = std::chrono::steady_clock::now();
  bool said = false;
  while (!ros::master::check()) {
    if (signal.load() != 0) return 5;
    const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (waited > timeout_s) {
      std::fprintf(stderr,
                   "%s: no ROS master answers at %s after %.0f s: start the node with roslaunch (or "
                   "roscore first)\n",
                   node.c_str(), ros::master::getURI().c_str(), timeout_s);
      return 4;
    }
    if (!said && waited > 2.0) {
      std::fprintf(stderr, "%s: waiting for the ROS master at %s (up to %.0f s)\n", node.c_str(),
                   ros::master::getURI().c_str(), timeout_s);
      said = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  return 0;
}

bool nodeHelpRequested(int argc, char** argv, const char* node, const char* what) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      std::printf(
          "%s: %s\nStarted by roslaunch (launch/*.launch; ./railsim run picks the file); its settings are "
          "the private parameters ~scene_yaml (the scene, loaded by launch/scene.launch with its overrides), "
          "~output_dir and ~validate_only.\n"
          "See README.md (running a scenario, exit codes) and docs/scene.md.\n",
          node, what);
      return true;
    }
  }
  return false;
}

}  // namespace rail::ros_glue
