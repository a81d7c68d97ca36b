// What both nodes do around a run's outputs and its end, the same way: where a bag goes and how it is opened
// and closed, the cost profile written beside it, the progress line, and the closing lines (how the contact
// was found; a stop by a signal or a lost master).
#pragma once

#include <ros/node_handle.h>
#include <ros/time.h>
#include <rosbag/bag.h>

#include <cerrno>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <rail_contact/contact_detection.hpp>
#include <rail_core/cost_profile.hpp>
#include <rail_core/scene.hpp>

namespace rail::ros_glue {

class MasterWatch;
struct NodeStop;

// The directory of a run's files: the node's ~output_dir, else $ROS_HOME/railsim, else ~/.ros/railsim.
std::string outputDir(const ros::NodeHandle& pnh);

// Where a bag named in the scene goes: absolute as given, else under outputDir(pnh).
std::string bagPath(const ros::NodeHandle& pnh, const std::string& name);

// A path beside a bag: its stem (without ".bag") followed by `suffix` ("run.bag", ".cost.yaml" ->
// "run.cost.yaml").
std::string besideBag(const std::string& bag_path, const std::string& suffix);

// The bag a node records to. open() creates its directory; close() (or the destructor) closes it, so that
// a stopped run leaves a readable bag. A write that fails (disk full, file gone or unwritable) makes
// failed() true and skips the later writes: the caller stops the run, close() keeps what is readable.
class OutputBag {
 public:
  OutputBag() = default;
  ~OutputBag();
  OutputBag(const OutputBag&) = delete;
  OutputBag& operator=(const OutputBag&) = delete;

  // Opens `path` for writing, creating its directory. False after one FATAL line naming the node, the scene
  // file and output.bag, with the reason.
  bool open(const std::string& node, const std::string& scene_file, const std::string& path);
  bool isOpen() const { return bag_ && bag_->isOpen(); }
  const std::string& path() const { return path_; }

  // A bag refuses time 0: a message at t = 0 is filed at the smallest time it takes.
  template <class Message>
  void write(const std::string& topic, const ros::Time& stamp, const Message& message) {
    if (failed() || !bag_) return;
    errno = 0;
    try {
      bag_->write(topic, stamp < ros::TIME_MIN ? ros::TIME_MIN : stamp, message);
    } catch (const std::exception& e) {
      fail(path_, errno, e.what());
    }
  }

  // A write of this bag or of a file beside it failed; error() says "cannot write <file>: <reason>".
  bool failed() const { return !error_.empty(); }
  const std::string& error() const { return error_; }

  // Closes the bag and says so ("<node>: bag closed: <path>"); nothing when it is not open. After a failed
  // write, a bag that cannot be completed (its index not written) or that does not open again is removed,
  // and an ERROR line says so.
  void close(const std::string& node);

  // Writes `text` to besideBag(path(), suffix). When it cannot: an ERROR line naming the file and the
  // system's reason, no partial file left, failed() true. Nothing without a bag path.
  void writeBeside(const std::string& node, const std::string& suffix, const std::string& text);

 private:
  // Records the first failure: the system's reason (errno `err`) and what the library said, or `what` alone.
  void fail(const std::string& file, int err, const char* what);

  // A rosbag::Bag whose close() threw retries it in its destructor, which then ends the process: such a
  // bag is released instead (abandoned, its file removed), so it is held by pointer.
  std::unique_ptr<rosbag::Bag> bag_;
  std::string path_;
  std::string error_;
};

// A node's run around its loop, kept the same way by both nodes and the moving-load run: the stop flag and
// the master watch (a lost master stops the run like a signal), the cost profile and its finer clock, the
// set-up time (from construction to startLoop, less the waits for the peer or viewers), the loop's wall
// time and the irregularity stations it evaluated.
class NodeRun {
 public:
  explicit NodeRun(std::string node);
  ~NodeRun();
  NodeRun(const NodeRun&) = delete;
  NodeRun& operator=(const NodeRun&) = delete;

  const std::string& node() const { return node_; }
  NodeStop& stop() const { return stop_; }
  core::CostProfile& cost() { return cost_; }
  core::CostClock& clock() { return clock_; }

  // A wait for the peer or for viewers (s): not the node's own set-up.
  void excludeFromSetUp(double seconds) { excluded_ += seconds; }
  // The loop starts: the set-up time goes to the cost profile; the loop's clock starts.
  void startLoop();
  // Wall time since startLoop (s).
  double loopSeconds() const;
  // After the loop: the irregularity stations the loop evaluated go to the clock, a lost master or an
  // unreported signal is said (reportStop). Returns the exit code to use.
  int endLoop(double t, bool stop_logged, int exit_code, const char* suffix = "");
  // The outputs could not be written: one FATAL line naming the file and the reason, and the stop time.
  // Returns kExitWriteFailed.
  int writeFailed(const OutputBag& bag, double t) const;

 private:
  std::string node_;
  NodeStop& stop_;
  std::unique_ptr<MasterWatch> master_watch_;
  core::CostProfile cost_;
  core::CostClock clock_;
  std::chrono::steady_clock::time_point setup0_, loop0_;
  double excluded_ = 0.0;
  long long irregularity_stations0_ = 0;
};

// The node-private marker parameters (documented in launch/cosim.launch and the README), read in one place
// with their defaults.
struct MarkerParams {
  std::string frame_id = "world";           // ~frame_id: the frame of the track's markers
  double scale = 200.0;                     // ~marker_scale: magnification of the rail deflection
  double colour_range = 1.0e-3;             // ~marker_colour_range: deflection (m) at full colour
  double rate = 25.0;                       // ~marker_rate: markers per simulated second (at most output.rate)
  double force_scale = 1e-5;                // ~force_scale: vehicle's contact-force arrows, m per N
  double period(double output_rate) const;  // simulated seconds between marker updates
};
MarkerParams markerParams(const ros::NodeHandle& pnh);

// The console's progress line of a long run, at most once per `period_s` of wall time: simulated time, per
// cent of the expected end, real-time factor and ETA. Starts its wall clock when built.
class ProgressLine {
 public:
  ProgressLine(std::string node, double t_end_estimate, double period_s = 5.0);
  // True when `period_s` has passed since the last line: print() then.
  bool due() const;
  // Prints the line now; `extra` (may be empty) is added after the time, e.g. "leading wheelset at
  // s = 12.34 m". Builds no string.
  void print(double t, const char* extra = "");
  double wallSeconds() const;

 private:
  std::string node_;
  double t_end_;
  double period_s_;
  std::chrono::steady_clock::time_point wall0_, last_;
};

// The progress line itself: "<node>: t = 1.234 s of 15.500 s (8.0 %)[, extra], real-time factor 0.93, ETA 13 s".
void logProgress(const std::string& node, double t, double t_end, double real_time_factor, double eta_s,
                 const char* extra = "");

// "<node>: <how the contact was found>" as INFO, or as WARN when some points were approximate or a second
// contact past a surface's end was not evaluated, so that a run never hides them.
void logDetection(const std::string& node, const contact::DetectionCounts& counts);

// The end of a run that a lost master or a signal may have cut short. A lost master gives an ERROR line
// naming its URI and exit code 5 (kExitInterrupted); a signal not yet reported by the loop (it ended a
// wait for the peer) gives a WARN line naming it. Returns the exit code to use (exit_code otherwise).
// t: the simulated time reached; stop_logged: the loop already said why it stopped; suffix: added to the
// signal's line (e.g. "; closing the bag").
int reportStop(const std::string& node, const MasterWatch& master_watch, double t, bool stop_logged, int exit_code,
               const char* suffix = "");

}  // namespace rail::ros_glue
