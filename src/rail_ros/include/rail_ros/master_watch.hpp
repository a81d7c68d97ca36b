// Watches the ROS master from a thread of its own: roscpp does not notice a master that went away (the
// nodes' topics and services keep working peer to peer), so a run would go on without one. Once the master
// has failed to answer `misses` checks in a row (one check per `period_s`), the watch sets `lost` and the
// caller's stop flag, so the run loop stops as on a signal (exit code 5) and says why.
#pragma once

#include <atomic>
#include <string>

namespace rail::ros_glue {

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
std::string exitedPeer(const std::string& me);

// Before a node's first NodeHandle (whose registration roscpp retries for ever, deaf to the node's own
// signal handler): waits for the master with a deadline. Returns 0 when it answers; 4 (kExitPeerTimeout)
// after timeout_s with an error naming the master's URI; 5 when `signal` becomes non-zero (SIGINT,
// SIGTERM) meanwhile. node: the node's name for the message.
int waitForMaster(const std::string& node, const std::atomic<int>& signal, double timeout_s = 30.0);

// True, after printing what the node is and how it is started, when argv holds -h or --help (the nodes
// are started by roslaunch; their settings are private parameters, not options).
bool nodeHelpRequested(int argc, char** argv, const char* node, const char* what);

}  // namespace rail::ros_glue
