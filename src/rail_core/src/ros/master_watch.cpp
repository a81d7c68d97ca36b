#include "rail_core/ros/master_watch.hpp"

#include <ros/master.h>

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

}  // namespace rail::core::ros_glue
