// Watches the ROS master from a thread of its own: roscpp does not notice a master that went away (the
// nodes' topics and services keep working peer to peer), so a run would go on without one. Once the master
// has failed to answer `misses` checks in a row (one check per `period_s`), the watch sets `lost` and the
// caller's stop flag, so the run loop stops as on a signal (exit code 5) and says why.
#pragma once

#include <atomic>
#include <string>

namespace rail::core::ros_glue {

class MasterWatch {
 public:
  // stop: the run's stop flag (the same one the transports watch). Starts the thread.
  MasterWatch(std::atomic<bool>& stop, double period_s = 1.0, int misses = 2);
  // Stops the thread (it is detached if a check is still blocking on an unreachable host).
  ~MasterWatch();
  MasterWatch(const MasterWatch&) = delete;
  MasterWatch& operator=(const MasterWatch&) = delete;

  bool lost() const { return state_->lost.load(); }
  const std::string& uri() const { return uri_; }  // the master's URI (ROS_MASTER_URI)

  struct State {
    std::atomic<bool> quit{false};
    std::atomic<bool> lost{false};
  };

 private:
  std::string uri_;
  State* state_;  // shared with the thread; freed by whichever of the two ends last
};

// A peer of this run that has already exited, as scripts/railsim_node_guard records it on the parameter
// server (/railsim/node_exit/<name>: {code, run_id}, same /railsim/run_id as this node's): "rail_track
// exited with code 2", or "" when none has. Lets a node waiting for its handshake report a dead peer at
// once instead of after the whole timeout.
std::string exited_peer(const std::string& me);

}  // namespace rail::core::ros_glue
