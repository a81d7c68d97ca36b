#include "rail_core/ros/master_watch.hpp"

#include <ros/master.h>
#include <ros/param.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <chrono>
#include <memory>
#include <thread>

namespace rail::core::ros_glue {

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

std::string exited_peer(const std::string& me) {
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

}  // namespace rail::core::ros_glue
