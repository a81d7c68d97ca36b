#include "rail_ros/run_output.hpp"

#include <ros/console.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include <rail_contact/irregularities.hpp>
#include <rail_core/exit_codes.hpp>

#include "rail_ros/master_watch.hpp"
#include "rail_ros/node_scaffold.hpp"

namespace rail::ros_glue {

namespace {

// mkdir -p; false on the first level that cannot be made.
bool makeDirs(const std::string& path) {
  for (std::size_t pos = 1; pos <= path.size(); ++pos) {
    if (pos == path.size() || path[pos] == '/') {
      const std::string part = path.substr(0, pos);
      if (::mkdir(part.c_str(), 0755) != 0 && errno != EEXIST) return false;
    }
  }
  return true;
}

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

std::string outputDir(const ros::NodeHandle& pnh) {
  std::string dir;
  if (pnh.getParam("output_dir", dir) && !dir.empty()) return dir;
  const char* ros_home = std::getenv("ROS_HOME");
  if (ros_home != nullptr && *ros_home != '\0') return std::string(ros_home) + "/railsim";
  const char* home = std::getenv("HOME");
  return std::string(home != nullptr && *home != '\0' ? home : ".") + "/.ros/railsim";
}

std::string bagPath(const ros::NodeHandle& pnh, const std::string& name) {
  if (!name.empty() && name[0] == '/') return name;
  return outputDir(pnh) + "/" + name;
}

std::string besideBag(const std::string& bag_path, const std::string& suffix) {
  const std::size_t dot = bag_path.rfind(".bag");
  const bool has_extension = dot != std::string::npos && dot + 4 == bag_path.size();
  return (has_extension ? bag_path.substr(0, dot) : bag_path) + suffix;
}

OutputBag::~OutputBag() {
  if (!isOpen()) return;
  try {
    bag_->close();
  } catch (const std::exception&) {
    static_cast<void>(bag_.release());  // see bag_: its destructor would retry the close and end the process
  }
}

bool OutputBag::open(const std::string& node, const std::string& scene_file, const std::string& path) {
  const std::size_t slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? std::string() : path.substr(0, slash);
  if (!dir.empty() && !makeDirs(dir)) {
    ROS_FATAL("%s: %s: output.bag: cannot create the directory %s", node.c_str(), scene_file.c_str(), dir.c_str());
    return false;
  }
  try {
    bag_ = std::make_unique<rosbag::Bag>(path, rosbag::bagmode::Write);
  } catch (const std::exception& e) {
    bag_.reset();
    ROS_FATAL("%s: %s: output.bag: cannot write %s: %s", node.c_str(), scene_file.c_str(), path.c_str(), e.what());
    return false;
  }
  path_ = path;
  return true;
}

void OutputBag::fail(const std::string& file, int err, const char* what) {
  if (failed()) return;
  error_ = "cannot write " + file + ": " + (err != 0 ? std::string(std::strerror(err)) + " (" + what + ")" : what);
}

void OutputBag::close(const std::string& node) {
  if (!isOpen()) return;
  errno = 0;
  try {
    bag_->close();
  } catch (const std::exception& e) {
    fail(path_, errno, e.what());
    static_cast<void>(bag_.release());  // see bag_
  }
  if (!failed()) {
    ROS_INFO("%s: bag closed: %s", node.c_str(), path_.c_str());
    return;
  }
  bool readable = bag_ != nullptr;
  if (readable) {
    try {
      rosbag::Bag check(path_, rosbag::bagmode::Read);
    } catch (const std::exception&) {
      readable = false;
    }
  }
  if (readable) {
    ROS_WARN("%s: bag closed: %s (it holds what was written before the failed write)", node.c_str(), path_.c_str());
  } else {
    std::remove(path_.c_str());
    ROS_ERROR("%s: removed the incomplete bag %s (it could not be closed after the failed write)", node.c_str(),
              path_.c_str());
  }
}

void OutputBag::writeBeside(const std::string& node, const std::string& suffix, const std::string& text) {
  if (path_.empty()) return;
  const std::string path = besideBag(path_, suffix);
  errno = 0;
  std::FILE* f = std::fopen(path.c_str(), "w");
  int err = errno;
  bool written = f != nullptr && std::fputs(text.c_str(), f) >= 0 && std::fflush(f) == 0;
  if (f != nullptr) {
    if (!written) err = errno;
    if (std::fclose(f) != 0 && written) {
      err = errno;
      written = false;
    }
  }
  if (written) return;
  if (f != nullptr) std::remove(path.c_str());
  ROS_ERROR("%s: cannot write %s: %s%s", node.c_str(), path.c_str(), std::strerror(err),
            f != nullptr ? "; removed the partial file" : "");
  fail(path, err, "write error");
}

NodeRun::NodeRun(std::string node)
    : node_(std::move(node)),
      stop_(nodeStop()),
      master_watch_(std::make_unique<MasterWatch>(stop_.requested)),
      setup0_(std::chrono::steady_clock::now()),
      loop0_(setup0_) {}

NodeRun::~NodeRun() = default;

void NodeRun::startLoop() {
  loop0_ = std::chrono::steady_clock::now();
  cost_.add(core::CostProfile::kSetUp, std::chrono::duration<double>(loop0_ - setup0_).count() - excluded_);
  irregularity_stations0_ = contact::Irregularities::stationsEvaluated();
}

double NodeRun::loopSeconds() const { return secondsSince(loop0_); }

int NodeRun::endLoop(double t, bool stop_logged, int exit_code, const char* suffix) {
  clock_.counts[core::CostClock::kIrregularityEvaluations] =
      contact::Irregularities::stationsEvaluated() - irregularity_stations0_;
  return reportStop(node_, *master_watch_, t, stop_logged, exit_code, suffix);
}

int NodeRun::writeFailed(const OutputBag& bag, double t) const {
  ROS_FATAL("%s: %s; stopped at t = %.4f s", node_.c_str(), bag.error().c_str(), t);
  return core::kExitWriteFailed;
}

ProgressLine::ProgressLine(std::string node, double t_end_estimate, double period_s)
    : node_(std::move(node)),
      t_end_(t_end_estimate),
      period_s_(period_s),
      wall0_(std::chrono::steady_clock::now()),
      last_(wall0_) {}

double ProgressLine::wallSeconds() const { return secondsSince(wall0_); }

bool ProgressLine::due() const { return secondsSince(last_) >= period_s_; }

void ProgressLine::print(double t, const char* extra) {
  last_ = std::chrono::steady_clock::now();
  const double rtf = t / std::max(wallSeconds(), 1e-9);
  const double eta = std::max(0.0, (t_end_ - t) / std::max(rtf, 1e-12));
  logProgress(node_, t, t_end_, rtf, eta, extra);
}

void logProgress(const std::string& node, double t, double t_end, double real_time_factor, double eta_s,
                 const char* extra) {
  ROS_INFO("%s: t = %.3f s of %.3f s (%.1f %%)%s%s, real-time factor %.3g, ETA %.0f s", node.c_str(), t, t_end,
           100.0 * t / std::max(t_end, 1e-9), *extra == '\0' ? "" : ", ", extra, real_time_factor, eta_s);
}

void logDetection(const std::string& node, const contact::DetectionCounts& counts) {
  if (counts.approximations > 0) {
    ROS_WARN("%s: %s", node.c_str(), contact::describe(counts).c_str());
  } else {
    ROS_INFO("%s: %s", node.c_str(), contact::describe(counts).c_str());
  }
}

int reportStop(const std::string& node, const MasterWatch& master_watch, double t, bool stop_logged, int exit_code,
               const char* suffix) {
  if (master_watch.lost()) {
    ROS_ERROR("%s: the ROS master %s went away: stopped at t = %.4f s", node.c_str(), master_watch.uri().c_str(), t);
    return core::kExitInterrupted;
  }
  if (nodeStop().signal != 0 && !stop_logged) {
    ROS_WARN("%s: stopped at t = %.4f s (%s)%s", node.c_str(), t, nodeStop().reason(), suffix);
  }
  return exit_code;
}

MarkerParams markerParams(const ros::NodeHandle& pnh) {
  MarkerParams m;
  m.frame_id = pnh.param<std::string>("frame_id", m.frame_id);
  m.scale = pnh.param("marker_scale", m.scale);
  m.colour_range = pnh.param("marker_colour_range", m.colour_range);
  m.rate = pnh.param("marker_rate", m.rate);
  m.force_scale = pnh.param("force_scale", m.force_scale);
  return m;
}

double MarkerParams::period(double output_rate) const { return 1.0 / std::min(output_rate, rate); }

}  // namespace rail::ros_glue
