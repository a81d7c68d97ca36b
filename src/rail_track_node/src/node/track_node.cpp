// rail_track node: ROS wiring of the track side. Reads the scene from the parameter server, validates it,
// reports what it will simulate, then
//  - in a co-simulation scene: waits for the vehicle node's handshake, opens the scene's transport and
//    answers every track step with the CosimTrack (contact on the rails, FE track with flexible) until the
//    vehicle closes, publishing contact points and rail deflections at output.rate;
//  - in a moving-load scene: builds the flexible track, runs it to solver.end and publishes /clock
//    (simulated time), rail deflections and markers, recording the scene's output.topics to a bag.
// Physics lives in the ROS-free core (rail_track_node/scene_track.hpp, track_simulator.hpp).
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <rosgraph_msgs/Clock.h>
#include <visualization_msgs/MarkerArray.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <sys/stat.h>

#include "rail_ros/master_watch.hpp"
#include "rail_ros/node_scaffold.hpp"
#include <vector>

#include <rail_core/cost_profile.hpp>
#include <rail_core/coupling/timed_transport.hpp>
#include <rail_core/exit_codes.hpp>
#include <rail_ros/scene_param.hpp>
#include <rail_core/scene_loader.hpp>
#include <rail_msgs/ContactPoints.h>
#include <rail_msgs/RailDeflection.h>
#include <rail_msgs/RailPadForces.h>
#include <rail_msgs/Energy.h>
#include <rail_msgs/WheelStates.h>

#include <rail_ros/contact_point_message.hpp>
#include <rail_ros/cosim_transport.hpp>
#include "rail_track_node/cosim_track.hpp"
#include "rail_track_node/track_window.hpp"

#include "rail_track_node/scene_track.hpp"
#include "rail_track_node/track_simulator.hpp"

using namespace rail::core;
namespace ros_glue = rail::ros_glue;
namespace rt = rail::track;

namespace {

// The stop request of this process (rail_ros/node_scaffold.hpp): SIGINT, SIGTERM or a lost master.
std::atomic<bool>& g_stop = rail::ros_glue::nodeStop().requested;
std::atomic<int>& g_signal = rail::ros_glue::nodeStop().signal;
const char* stopReason() { return rail::ros_glue::nodeStop().reason(); }

// mkdir -p; false on failure.
bool makeDirs(const std::string& dir) {
  std::string path;
  std::size_t pos = 0;
  while (pos != std::string::npos) {
    pos = dir.find('/', pos + 1);
    path = dir.substr(0, pos);
    if (path.empty()) continue;
    if (mkdir(path.c_str(), 0755) != 0 && errno != EEXIST) return false;
  }
  return true;
}

// Where a bag named in the scene goes: absolute as given, else under the node's ~output_dir (default
// $ROS_HOME/railsim).
std::string bagPath(ros::NodeHandle& pnh, const std::string& name) {
  if (!name.empty() && name[0] == '/') return name;
  std::string dir = pnh.param<std::string>("output_dir", "");
  if (dir.empty()) {
    const char* ros_home = std::getenv("ROS_HOME");
    const char* home = std::getenv("HOME");
    dir = std::string(ros_home ? ros_home : (std::string(home ? home : ".") + "/.ros")) + "/railsim";
  }
  return dir + "/" + name;
}

// Opens path for writing (creating its directory); false after one FATAL message naming the scene key.
bool openBag(const std::string& me, const Scene& scene, const std::string& path, rosbag::Bag& bag) {
  const std::string bag_dir = path.substr(0, path.rfind('/'));
  if (!bag_dir.empty() && !makeDirs(bag_dir)) {
    ROS_FATAL("%s: %s: output.bag: cannot create the directory %s", me.c_str(), scene.file.c_str(), bag_dir.c_str());
    return false;
  }
  try {
    bag.open(path, rosbag::bagmode::Write);
  } catch (const std::exception& e) {
    ROS_FATAL("%s: %s: output.bag: cannot write %s: %s", me.c_str(), scene.file.c_str(), path.c_str(), e.what());
    return false;
  }
  return true;
}

bool contains(const std::vector<std::string>& v, const std::string& x) {
  for (const std::string& s : v)
    if (s == x) return true;
  return false;
}

// Rails as line strips coloured by vertical deflection (displacements magnified by `scale`) and the
// sleepers as a line list between their end nodes. Message storage allocated once; update() only writes.
class TrackMarkers {
 public:
  TrackMarkers(const rt::TrackModel& model, const std::string& frame_id, double scale, double colour_range)
      : model_(model), scale_(scale), colour_range_(colour_range) {
    const rt::TrackMesh& mesh = model.mesh;
    const double incl = model.data.layout.rail_inclination;
    msg_.markers.resize(3);
    for (int r = 0; r < 2; ++r) {
      visualization_msgs::Marker& m = msg_.markers[r];
      m.header.frame_id = frame_id;
      m.ns = "rails";
      m.id = r;
      m.type = visualization_msgs::Marker::LINE_STRIP;
      m.action = visualization_msgs::Marker::ADD;
      m.pose.orientation.w = 1.0;
      m.scale.x = 0.07;  // line width, m (rail head width)
      m.color.a = 1.0;
      const std::size_t n = mesh.rail_nodes[r].size();
      m.points.resize(n);
      m.colors.resize(n);
      up_[r].resize(n);
      const double sg = r == rt::kLeftRail ? 1.0 : -1.0;
      for (std::size_t k = 0; k < n; ++k) {
        const int beam = mesh.rail_beams[r][k + 1 < n ? k : k - 1];
        const Eigen::Matrix3d& R = mesh.beams[beam].R_local_to_world;
        up_[r][k] = sg * std::sin(incl) * R.col(1) + std::cos(incl) * R.col(2);  // track normal
      }
    }
    visualization_msgs::Marker& s = msg_.markers[2];
    s.header.frame_id = frame_id;
    s.ns = "sleepers";
    s.id = 0;
    s.type = visualization_msgs::Marker::LINE_LIST;
    s.action = visualization_msgs::Marker::ADD;
    s.pose.orientation.w = 1.0;
    s.scale.x = 0.22;  // line width, m (sleeper width)
    s.color.r = s.color.g = s.color.b = 0.55f;
    s.color.a = 1.0;
    s.points.resize(2 * mesh.sleeper_nodes.size());
  }

  const visualization_msgs::MarkerArray& update(const Eigen::VectorXd& d, const ros::Time& stamp) {
    const rt::TrackMesh& mesh = model_.mesh;
    for (int r = 0; r < 2; ++r) {
      visualization_msgs::Marker& m = msg_.markers[r];
      m.header.stamp = stamp;
      for (std::size_t k = 0; k < m.points.size(); ++k) {
        const int node = mesh.rail_nodes[r][k];
        const Eigen::Vector3d u = translation(d, node);
        const Eigen::Vector3d p = mesh.nodes[node].p_in_world + scale_ * u;
        m.points[k].x = p.x();
        m.points[k].y = p.y();
        m.points[k].z = p.z();
        // 0 (no deflection, blue) .. 1 (colour_range down, red).
        const double w = std::min(1.0, std::max(0.0, -u.dot(up_[r][k]) / colour_range_));
        m.colors[k].r = static_cast<float>(w);
        m.colors[k].g = static_cast<float>(0.3 * (1.0 - w));
        m.colors[k].b = static_cast<float>(1.0 - w);
        m.colors[k].a = 1.0f;
      }
    }
    visualization_msgs::Marker& s = msg_.markers[2];
    s.header.stamp = stamp;
    for (std::size_t k = 0; k < mesh.sleeper_nodes.size(); ++k) {
      for (int e = 0; e < 2; ++e) {
        const int node = mesh.sleeper_nodes[k][e == 0 ? 0 : 5];
        const Eigen::Vector3d p = mesh.nodes[node].p_in_world + scale_ * translation(d, node);
        s.points[2 * k + e].x = p.x();
        s.points[2 * k + e].y = p.y();
        s.points[2 * k + e].z = p.z();
      }
    }
    return msg_;
  }

 private:
  Eigen::Vector3d translation(const Eigen::VectorXd& d, int node) const {
    Eigen::Vector3d u;
    for (int q = 0; q < 3; ++q) {
      const int i = model_.mesh.dofIndex(node, q);
      u(q) = i >= 0 ? d(i) : 0.0;
    }
    return u;
  }
  const rt::TrackModel& model_;
  double scale_, colour_range_;
  std::array<std::vector<Eigen::Vector3d>, 2> up_;
  visualization_msgs::MarkerArray msg_;
};

void fill(geometry_msgs::Vector3& out, const Eigen::Vector3d& v) {
  out.x = v.x();
  out.y = v.y();
  out.z = v.z();
}

int runMovingLoads(ros::NodeHandle& nh, ros::NodeHandle& pnh, const Scene& scene) {
  const std::string me = ros::this_node::getName();
  rail::ros_glue::MasterWatch master_watch(g_stop);  // a lost master stops the run like a signal
  // ---- build ----
  std::unique_ptr<rt::SceneTrack> track;
  rt::SimulatorSettings settings;
  try {
    track.reset(new rt::SceneTrack(rt::buildSceneTrack(scene)));
    settings.t_end = rt::movingLoadEndTime(scene);
  } catch (const std::exception& e) {
    ROS_FATAL("%s: %s", me.c_str(), e.what());
    return kExitBadInput;
  }
  settings.dt = scene.solver.track_step;
  settings.loads = scene.moving_loads;
  settings.rail_height = track->rail_height;
  const rt::TrackModel& model = track->model;
  ROS_INFO("%s: flexible track built: %d free DOFs, %d sleepers; running to t = %.4g s with dt = %.3g s (%ld steps)",
           me.c_str(), model.system.size(), model.mesh.n_sleepers, settings.t_end, settings.dt,
           std::lround(settings.t_end / settings.dt));
  // Factorising K_eff and the static solve fail on non-physical track data (e.g. a matrix that is not
  // positive definite): a refused input, named with the scene and its track data file.
  std::unique_ptr<rt::TrackSimulator> sim_ptr;
  try {
    sim_ptr.reset(new rt::TrackSimulator(model, settings));
  } catch (const std::exception& e) {
    ROS_FATAL("%s: %s: track.data %s: the track cannot be solved: %s", me.c_str(), scene.file.c_str(),
              scene.track.data.path.c_str(), e.what());
    return kExitBadInput;
  }
  rt::TrackSimulator& sim = *sim_ptr;
  sim.setProgressCallback(
      [&me](const rt::SimulationProgress& p) {
        ROS_INFO("%s: t = %.4f s of %.4f s (%.1f %%), %.3g x real time, %.0f s left", me.c_str(), p.t, p.t_end,
                 p.percent, p.real_time_factor, p.eta);
      },
      pnh.param("progress_interval", 2.0));

  const bool deflections = scene.effects.rail_deflection_output && !scene.output.deflection_sections.empty();
  if (deflections) {
    const rt::TrackFrameFunction frames = rt::seatPlaneFrames(track->geometry, track->seat_below_centre);
    for (std::size_t i = 0; i < scene.output.deflection_sections.size(); ++i) {
      try {
        sim.addSection(scene.output.deflection_sections[i], frames);
      } catch (const std::exception& e) {
        ROS_FATAL("%s: %s: output.deflection_sections[%zu]: %s", me.c_str(), scene.file.c_str(), i, e.what());
        return kExitBadInput;
      }
    }
  }

  // ---- ROS wiring ----
  ros::Publisher clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  ros::Publisher deflection_pub, marker_pub;
  if (deflections) deflection_pub = nh.advertise<rail_msgs::RailDeflection>("/rail_deflection", 100);
  std::unique_ptr<TrackMarkers> markers;
  double marker_period = 0.0;
  if (scene.effects.rviz_markers) {
    marker_pub = nh.advertise<visualization_msgs::MarkerArray>("/markers", 2, true);
    markers.reset(new TrackMarkers(model, pnh.param<std::string>("frame_id", "world"),
                                   pnh.param("marker_scale", 200.0), pnh.param("marker_colour_range", 1.0e-3)));
    marker_period = 1.0 / std::min(scene.output.rate, pnh.param("marker_rate", 25.0));
  }

  rosbag::Bag bag;
  bool bag_open = false;
  bool bag_deflection = false, bag_markers = false, bag_clock = false;
  std::string bag_path;
  if (!scene.output.bag.empty()) {
    bag_path = bagPath(pnh, scene.output.bag);
    if (!openBag(me, scene, bag_path, bag)) return kExitBadInput;
    bag_open = true;
    bag_deflection = deflections && contains(scene.output.topics, "rail_deflection");
    bag_markers = markers && contains(scene.output.topics, "markers");
    bag_clock = contains(scene.output.topics, "clock");
    for (const std::string& t : scene.output.topics)
      if (t != "rail_deflection" && t != "markers" && t != "clock")
        ROS_WARN("%s: output.topics: %s has no source in a moving-load run; not recorded", me.c_str(), t.c_str());
    ROS_INFO("%s: recording to %s", me.c_str(), bag_path.c_str());
  }

  // Optionally wait (wall clock) for subscribers to connect, so that they see the run from t = 0.
  const double wait = pnh.param("wait_for_subscribers", 0.0);
  if (wait > 0.0) {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(wait);
    while (!g_stop && ros::ok() && ros::WallTime::now() < until &&
           ((deflections && deflection_pub.getNumSubscribers() == 0) ||
            (markers && marker_pub.getNumSubscribers() == 0)))
      ros::WallDuration(0.02).sleep();
  }

  // ---- loop: advance to each output time, publish ----
  const int n_sections = sim.sectionCount();
  std::vector<rail_msgs::RailDeflection> deflection_msgs(n_sections);
  for (rail_msgs::RailDeflection& m : deflection_msgs) m.header.frame_id = "track";
  rt::RailSectionDeflection deflection;
  rosgraph_msgs::Clock clock_msg;
  const double period = 1.0 / scene.output.rate;
  double next_marker = 0.0;
  long k = 0;
  int exit_code = kExitOk;
  while (true) {
    if (g_stop || !ros::ok()) {
      ROS_WARN("%s: stopped at t = %.4f s (%s)", me.c_str(), sim.time(), stopReason());
      exit_code = kExitInterrupted;
      break;
    }
    sim.advanceTo(std::min(k * period, settings.t_end));
    const ros::Time stamp(sim.time());
    // A bag refuses time 0: the first output (t = 0) is filed at the smallest time it takes.
    const ros::Time bag_time = stamp < ros::TIME_MIN ? ros::TIME_MIN : stamp;
    clock_msg.clock = stamp;
    clock_pub.publish(clock_msg);
    if (bag_clock) bag.write("/clock", bag_time, clock_msg);
    for (int i = 0; i < n_sections; ++i) {
      sim.sectionDeflection(i, deflection);
      rail_msgs::RailDeflection& m = deflection_msgs[i];
      m.header.stamp = stamp;
      m.arc_length = deflection.s;
      fill(m.left_displacement, deflection.displacement[rt::kLeftRail]);
      fill(m.left_rotation, deflection.rotation[rt::kLeftRail]);
      fill(m.right_displacement, deflection.displacement[rt::kRightRail]);
      fill(m.right_rotation, deflection.rotation[rt::kRightRail]);
      deflection_pub.publish(m);
      if (bag_deflection) bag.write("/rail_deflection", bag_time, m);
    }
    if (markers && (sim.time() + 1e-12 >= next_marker || sim.finished())) {
      next_marker += marker_period;
      const visualization_msgs::MarkerArray& ma = markers->update(sim.state().d, stamp);
      marker_pub.publish(ma);
      if (bag_markers) bag.write("/markers", bag_time, ma);
    }
    if (sim.finished()) break;
    ++k;
  }
  if (master_watch.lost()) {
    ROS_ERROR("%s: the ROS master %s went away: stopped at t = %.4f s", me.c_str(), master_watch.uri().c_str(),
              sim.time());
    exit_code = kExitInterrupted;
  }
  if (bag_open) {
    bag.close();
    ROS_INFO("%s: bag closed: %s", me.c_str(), bag_path.c_str());
  }
  if (exit_code == kExitOk) {
    ROS_INFO("%s: finished at t = %.4f s (%ld steps)", me.c_str(), sim.time(), sim.steps());
    // Let subscribers receive the last messages.
    ros::WallDuration(0.3).sleep();
  }
  return exit_code;
}


// Replay: the wheel states recorded in a bag (/wheel_states, e.g. by the vehicle node of any earlier run)
// drive the track side alone. The recorded states (at the run's output.rate) are interpolated to each
// track step t_k = k h (positions, velocities, angular velocities and arc lengths linearly; orientations
// by slerp) and handed to the track as the vehicle's frames, stamped with this scene's hash; the wrenches
// go nowhere. The bag is read directly rather than played: the track may run far slower than real time
// and a played topic would drop frames.
class ReplayTransport final : public rail::core::coupling::FrameTransport {
  using Result = rail::core::coupling::Result;
  using Status = rail::core::coupling::Status;

 public:
  // Reads every /wheel_states message of `bag_path`. Throws std::runtime_error naming the bag and what is
  // missing or inconsistent.
  ReplayTransport(const std::string& bag_path, const Scene& scene, int wheel_count)
      : h_(scene.solver.track_step), hash_(scene.hash) {
    rosbag::Bag bag;
    try {
      bag.open(bag_path, rosbag::bagmode::Read);
    } catch (const std::exception& e) {
      throw std::runtime_error(bag_path + ": cannot read the replay bag: " + e.what());
    }
    rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{"/wheel_states"}));
    for (const rosbag::MessageInstance& m : view) {
      const rail_msgs::WheelStates::ConstPtr msg = m.instantiate<rail_msgs::WheelStates>();
      if (!msg) continue;
      if (static_cast<int>(msg->wheels.size()) != wheel_count) {
        throw std::runtime_error(bag_path + ": /wheel_states at t = " + std::to_string(msg->header.stamp.toSec()) +
                                 " s has " + std::to_string(msg->wheels.size()) + " wheels, the scene's vehicle " +
                                 std::to_string(wheel_count));
      }
      const double t = msg->header.stamp.toSec() <= 1e-6 ? 0.0 : msg->header.stamp.toSec();
      if (!times_.empty() && t <= times_.back()) continue;  // repeated output instant
      times_.push_back(t);
      rail::core::coupling::WheelStateFrame f(wheel_count);
      f.count = static_cast<std::uint32_t>(wheel_count);
      for (int i = 0; i < wheel_count; ++i) {
        const rail_msgs::WheelState& w = msg->wheels[static_cast<std::size_t>(i)];
        auto& o = f.wheels[static_cast<std::size_t>(i)];
        o.id = w.wheel_id;
        o.arc_length = w.arc_length;
        o.p_wheel_in_world = Eigen::Vector3d(w.position.x, w.position.y, w.position.z);
        o.q_wheelset_to_world = Eigen::Quaterniond(w.orientation.w, w.orientation.x, w.orientation.y, w.orientation.z);
        o.v_wheel_in_world = Eigen::Vector3d(w.linear_velocity.x, w.linear_velocity.y, w.linear_velocity.z);
        o.omega_wheelset_in_world = Eigen::Vector3d(w.angular_velocity.x, w.angular_velocity.y, w.angular_velocity.z);
      }
      frames_.push_back(std::move(f));
    }
    if (frames_.empty()) throw std::runtime_error(bag_path + ": no /wheel_states in the bag (needed to replay a run)");
    if (frames_.size() < 2) throw std::runtime_error(bag_path + ": /wheel_states has one message; a replay needs two");
    // The scene's end time (if it has one) shortens the replay.
    t_stop_ = scene.solver.end.kind == EndKind::kTime ? std::min(times_.back(), scene.solver.end.value) : times_.back();
    if (times_.front() > 0.5 * h_) {
      throw std::runtime_error(bag_path + ": /wheel_states starts at t = " + std::to_string(times_.front()) +
                               " s; a replay starts at t = 0");
    }
  }
  double endTime() const { return t_stop_; }
  // First to last wheel centre along the track in the run's first frame (m): the recorded vehicle's span.
  double wheelSpan() const {
    double lo = frames_.front().wheels.front().arc_length, hi = lo;
    for (const auto& w : frames_.front().wheels) {
      lo = std::min(lo, w.arc_length);
      hi = std::max(hi, w.arc_length);
    }
    return hi - lo;
  }
  rail::core::coupling::Role role() const override { return rail::core::coupling::Role::kTrack; }
  Result sendStates(const rail::core::coupling::WheelStateFrame&, rail::core::coupling::Deadline) override {
    return {Status::kError, "replay: the track end does not send states"};
  }
  Result receiveWrenches(rail::core::coupling::WrenchFrame&, rail::core::coupling::Deadline) override {
    return {Status::kError, "replay: the track end does not receive wrenches"};
  }
  // States of the next step k, interpolated at k h; kPeerClosed after the bag's last instant.
  Result receiveStates(rail::core::coupling::WheelStateFrame& out, rail::core::coupling::Deadline) override {
    const double t = static_cast<double>(step_) * h_;
    if (t > t_stop_ + 1e-9 * h_) return {Status::kPeerClosed, "end of the replayed run"};
    while (seg_ + 2 < times_.size() && times_[seg_ + 1] < t) ++seg_;
    const double t0 = times_[seg_], t1 = times_[seg_ + 1];
    const double a = std::min(1.0, std::max(0.0, (t - t0) / (t1 - t0)));
    const auto& f0 = frames_[seg_];
    const auto& f1 = frames_[seg_ + 1];
    out.count = f0.count;
    for (std::uint32_t i = 0; i < f0.count; ++i) {
      const auto& w0 = f0.wheels[i];
      const auto& w1 = f1.wheels[i];
      auto& o = out.wheels[i];
      o.id = w0.id;
      o.arc_length = (1 - a) * w0.arc_length + a * w1.arc_length;
      o.p_wheel_in_world = (1 - a) * w0.p_wheel_in_world + a * w1.p_wheel_in_world;
      o.q_wheelset_to_world = w0.q_wheelset_to_world.slerp(a, w1.q_wheelset_to_world);
      o.v_wheel_in_world = (1 - a) * w0.v_wheel_in_world + a * w1.v_wheel_in_world;
      o.omega_wheelset_in_world = (1 - a) * w0.omega_wheelset_in_world + a * w1.omega_wheelset_in_world;
    }
    out.step = step_;
    out.time = t;
    out.scene_hash = hash_;
    ++step_;
    return {};
  }
  Result sendWrenches(const rail::core::coupling::WrenchFrame&, rail::core::coupling::Deadline) override {
    return {};
  }
  void close() override {}

 private:
  double h_;
  double t_stop_ = 0.0;
  std::uint64_t hash_;
  std::vector<double> times_;
  std::vector<rail::core::coupling::WheelStateFrame> frames_;
  std::size_t seg_ = 0;
  std::uint64_t step_ = 0;
};

// The track side of the co-simulation after the handshake: opens the scene's transport, answers every
// track step with the CosimTrack until the vehicle closes, and publishes /contact_points (world) and
// /rail_deflection (track frame, output.deflection_sections) at output.rate. The vehicle node records the
// run's bag (output.bag); what only the track has (contact_points, rail_deflection, when output.topics
// names them) goes to a companion bag beside it, <stem>.track.bag. peer: the vehicle node's name;
// wheel_span: the vehicle's first to last wheel (m, from the handshake; a replay takes it from the bag).
int runCosim(ros::NodeHandle& nh, ros::NodeHandle& pnh, const Scene& scene, const std::string& peer,
             double wheel_span, const std::string& replay_bag = "") {
  namespace cc = rail::core::coupling;
  const std::string me = ros::this_node::getName();
  CostProfile cost;
  rail::ros_glue::MasterWatch master_watch(g_stop);  // a lost master stops the run like a signal
  rail::core::CostClock clock;  // the finer split, filled by the track core (cost_profile.hpp)
  std::unique_ptr<cc::FrameTransport> transport;
  const bool replay = !replay_bag.empty();
  if (replay) {
    try {
      auto r = std::make_unique<ReplayTransport>(replay_bag, scene, scene.wheelCount());
      ROS_INFO("%s: replaying the wheel states of %s (t = 0 .. %.4f s)", me.c_str(), replay_bag.c_str(), r->endTime());
      wheel_span = r->wheelSpan();
      transport = std::move(r);
    } catch (const std::exception& e) {
      ROS_FATAL("%s: %s", me.c_str(), e.what());
      return kExitBadInput;
    }
  }
  rt::CosimTrackOptions track_options;
  track_options.cost = &clock;
  track_options.window.vehicle_length = wheel_span;
  const auto setup0 = std::chrono::steady_clock::now();
  std::unique_ptr<rt::CosimTrack> track;
  try {
    track.reset(new rt::CosimTrack(scene, track_options));
  } catch (const std::exception& e) {
    ROS_FATAL("%s: cannot build the track: %s", me.c_str(), e.what());
    return kExitBadInput;
  }
  const bool deflections = scene.effects.rail_deflection_output && !scene.output.deflection_sections.empty();
  if (deflections) {
    for (std::size_t i = 0; i < scene.output.deflection_sections.size(); ++i) {
      try {
        track->addSection(scene.output.deflection_sections[i]);
      } catch (const std::exception& e) {
        ROS_FATAL("%s: %s: output.deflection_sections[%zu]: %s", me.c_str(), scene.file.c_str(), i, e.what());
        return kExitBadInput;
      }
    }
  }
  try {
    if (!replay) transport = rail::ros_glue::makeTransport(scene, cc::Role::kTrack, nh, pnh, peer, &g_stop);
  } catch (const cc::CouplingError& e) {
    ROS_FATAL("%s: cannot open the %s transport to %s: %s", me.c_str(), toString(scene.solver.transport),
              peer.c_str(), e.what());
    return cc::exitCode(e.status());
  } catch (const std::exception& e) {
    ROS_FATAL("%s: cannot open the %s transport: %s", me.c_str(), toString(scene.solver.transport), e.what());
    return kExitBadInput;
  }
  ROS_INFO("%s: %s track built (%d wheels); serving the %s transport, track step %g s", me.c_str(),
           track->flexible() ? "flexible" : "rigid", track->wheelCount(), toString(scene.solver.transport),
           scene.solver.track_step);

  ros::Publisher points_pub, deflection_pub;
  if (scene.effects.contact_point_output) points_pub = nh.advertise<rail_msgs::ContactPoints>("/contact_points", 100);
  if (deflections) deflection_pub = nh.advertise<rail_msgs::RailDeflection>("/rail_deflection", 100);
  // Companion bag of the track's outputs.
  rosbag::Bag bag;
  std::string bag_path;
  const bool rec_points = scene.effects.contact_point_output && contains(scene.output.topics, "contact_points");
  const bool rec_deflection = deflections && contains(scene.output.topics, "rail_deflection");
  // Pad forces under the train (effects.pad_force_output, flexible track): the sleepers from
  // output.pad_force_margin behind the rearmost wheel to as far ahead of the foremost one.
  const bool pads = scene.effects.pad_force_output && track->flexible();
  const bool rec_pads = pads && contains(scene.output.topics, "pad_forces");
  ros::Publisher pads_pub;
  if (pads) pads_pub = nh.advertise<rail_msgs::RailPadForces>("/pad_forces", 100);
  std::vector<rt::PadForceSample> pad_samples(pads ? static_cast<std::size_t>(track->sleeperCount()) : 0u);
  rail_msgs::RailPadForces pads_msg;
  pads_msg.header.frame_id = "track";
  for (auto* v : {&pads_msg.left_pad_force, &pads_msg.right_pad_force, &pads_msg.left_rail_displacement,
                  &pads_msg.right_rail_displacement}) {
    v->reserve(pad_samples.size());
  }
  pads_msg.arc_length.reserve(pad_samples.size());
  // Mechanical energy of the FE track (effects.energy_output, flexible track).
  const bool energy = scene.effects.energy_output && track->flexible();
  const bool rec_energy = energy && contains(scene.output.topics, "track_energy");
  ros::Publisher energy_pub;
  if (energy) energy_pub = nh.advertise<rail_msgs::Energy>("/track_energy", 100);
  rail_msgs::Energy energy_msg;
  energy_msg.header.frame_id = "track";
  if (!scene.output.bag.empty() && (rec_points || rec_deflection || rec_pads || rec_energy)) {
    bag_path = bagPath(pnh, scene.output.bag);
    const std::size_t dot = bag_path.rfind(".bag");
    bag_path = (dot != std::string::npos && dot + 4 == bag_path.size() ? bag_path.substr(0, dot) : bag_path) +
               ".track.bag";
    if (!openBag(me, scene, bag_path, bag)) return kExitBadInput;
    ROS_INFO("%s: recording the track's outputs to %s", me.c_str(), bag_path.c_str());
  }
  // rviz markers of the deflected rails and sleepers (effects.rviz_markers, flexible track only: the rigid
  // FE track has no mesh), at ~marker_rate. On a moving window the markers follow the window's mesh (rebuilt
  // after each move) and show its total displacement d_g + w.
  ros::Publisher marker_pub;
  std::unique_ptr<TrackMarkers> markers;
  const rt::TrackWindow* window = track->trackWindow();
  int marker_window_moves = -1;
  Eigen::VectorXd d_total;  // window: d_g + w, sized at each rebuild
  const std::string marker_frame = pnh.param<std::string>("frame_id", "world");
  const double marker_scale = pnh.param("marker_scale", 200.0);
  const double marker_colour_range = pnh.param("marker_colour_range", 1.0e-3);
  double marker_period = 0.0, next_marker = 0.0;
  if (scene.effects.rviz_markers && track->flexible()) {
    marker_pub = nh.advertise<visualization_msgs::MarkerArray>("/markers", 2, true);
    if (window == nullptr) {
      markers.reset(new TrackMarkers(track->sceneTrack()->model, marker_frame, marker_scale, marker_colour_range));
    }
    marker_period = 1.0 / std::min(scene.output.rate, pnh.param("marker_rate", 25.0));
  }
  const bool draw_markers = scene.effects.rviz_markers && track->flexible();
  rail_msgs::ContactPoints points_msg;
  points_msg.header.frame_id = "world";
  points_msg.points.resize(2 * static_cast<std::size_t>(track->wheelCount()));
  std::vector<rail_msgs::RailDeflection> deflection_msgs(static_cast<std::size_t>(track->sectionCount()));
  for (rail_msgs::RailDeflection& m : deflection_msgs) m.header.frame_id = "track";
  rt::RailSectionDeflection deflection;

  auto publish = [&](const ros::Time& stamp, const cc::WheelStateFrame& states) {
    CostProfile::Scope timing(cost, CostProfile::kPublish);
    rail::core::timedOutput(&clock, rail::core::CostClock::kContactPointOutput, scene.effects.contact_point_output, [&] {
      points_msg.header.stamp = stamp;
      for (int id = 0; id < track->wheelCount(); ++id) {
        for (int k = 0; k < 2; ++k) {
          const rail::contact::ContactPointResult& c = track->contact(id).contact[k];
          rail_msgs::ContactPoint& p = points_msg.points[2 * static_cast<std::size_t>(id) + static_cast<std::size_t>(k)];
          rail::ros_glue::toMessage(c, id, id % 2, k, p);
        }
      }
      points_pub.publish(points_msg);
      if (rec_points && bag.isOpen()) {
        CostProfile::Scope bag_timing(cost, CostProfile::kBagWrite);
        bag.write("/contact_points", stamp, points_msg);
      }
    });
    for (int i = 0; i < track->sectionCount(); ++i) {
      track->sectionDeflection(i, deflection);
      rail_msgs::RailDeflection& m = deflection_msgs[static_cast<std::size_t>(i)];
      m.header.stamp = stamp;
      m.arc_length = deflection.s;
      fill(m.left_displacement, deflection.displacement[rt::kLeftRail]);
      fill(m.left_rotation, deflection.rotation[rt::kLeftRail]);
      fill(m.right_displacement, deflection.displacement[rt::kRightRail]);
      fill(m.right_rotation, deflection.rotation[rt::kRightRail]);
      deflection_pub.publish(m);
      if (rec_deflection && bag.isOpen()) {
        CostProfile::Scope bag_timing(cost, CostProfile::kBagWrite);
        bag.write("/rail_deflection", stamp, m);
      }
    }
    if (pads) {
      double s_min = 1e300, s_max = -1e300;
      for (std::uint32_t i = 0; i < states.count; ++i) {
        s_min = std::min(s_min, states.wheels[i].arc_length);
        s_max = std::max(s_max, states.wheels[i].arc_length);
      }
      const int n = track->padForces(s_min - scene.output.pad_force_margin, s_max + scene.output.pad_force_margin,
                                     pad_samples.data(), static_cast<int>(pad_samples.size()));
      pads_msg.header.stamp = stamp;
      const auto size = static_cast<std::size_t>(n);  // within the reserved capacity: no allocation
      pads_msg.arc_length.resize(size);
      pads_msg.left_pad_force.resize(size);
      pads_msg.right_pad_force.resize(size);
      pads_msg.left_rail_displacement.resize(size);
      pads_msg.right_rail_displacement.resize(size);
      for (std::size_t k = 0; k < size; ++k) {
        const rt::PadForceSample& p = pad_samples[k];
        pads_msg.arc_length[k] = p.s;
        fill(pads_msg.left_pad_force[k], p.force_in_track[rt::kLeftRail]);
        fill(pads_msg.right_pad_force[k], p.force_in_track[rt::kRightRail]);
        fill(pads_msg.left_rail_displacement[k], p.rail_displacement_in_track[rt::kLeftRail]);
        fill(pads_msg.right_rail_displacement[k], p.rail_displacement_in_track[rt::kRightRail]);
      }
      pads_pub.publish(pads_msg);
      if (rec_pads && bag.isOpen()) {
        CostProfile::Scope bag_timing(cost, CostProfile::kBagWrite);
        bag.write("/pad_forces", stamp, pads_msg);
      }
    }
    rail::core::timedOutput(&clock, rail::core::CostClock::kEnergyOutput, energy, [&] {
      track->energy(energy_msg.kinetic, energy_msg.potential);
      energy_msg.total = energy_msg.kinetic + energy_msg.potential;
      energy_msg.header.stamp = stamp;
      energy_pub.publish(energy_msg);
      if (rec_energy && bag.isOpen()) {
        CostProfile::Scope bag_timing(cost, CostProfile::kBagWrite);
        bag.write("/track_energy", stamp, energy_msg);
      }
    });
    rail::core::timedOutput(&clock, rail::core::CostClock::kMarkers, draw_markers && stamp.toSec() + 1e-12 >= next_marker, [&] {
      next_marker += marker_period;
      if (window == nullptr) {
        marker_pub.publish(markers->update(track->state()->d, stamp));
      } else {
        if (track->windowMoves() != marker_window_moves) {  // a new mesh: rebuild (allocates; rare)
          marker_window_moves = track->windowMoves();
          markers.reset(new TrackMarkers(window->model(), marker_frame, marker_scale, marker_colour_range));
          d_total.resize(window->staticState().size());
        }
        d_total = window->staticState() + window->state().d;
        marker_pub.publish(markers->update(d_total, stamp));
      }
    });
  };

  cc::TimedTransport timed_transport(*transport, cost);  // adds exchange waits to `cost`
  cc::TrackCoupling coupling(cc::couplingConfig(scene), timed_transport);
  const double h = scene.solver.track_step;
  const double period = 1.0 / scene.output.rate;
  std::uint64_t n_out = 0;
  int exit_code = kExitOk;
  bool stop_logged = false;  // the run loop said why it stopped
  const auto wall0 = std::chrono::steady_clock::now();
  cost.add(CostProfile::kSetUp, std::chrono::duration<double>(wall0 - setup0).count());
  const long long irregularity_stations0 = rail::contact::Irregularities::stationsEvaluated();
  for (;;) {
    // Step 0 waits for the vehicle's set-up (settling): the handshake timeout; later steps the exchange
    // timeout.
    const cc::Result r =
        coupling.nextStep() == 0
            ? coupling.receive(cc::Clock::now() + std::chrono::duration_cast<cc::Clock::duration>(
                                                      std::chrono::duration<double>(scene.solver.handshake_timeout)))
            : coupling.receive();
    if (r.status == cc::Status::kPeerClosed) {
      // The vehicle closes after the step that reaches solver.end; closing (or dying) earlier, with a time
      // end, is a peer that went away.
      const double t_last = coupling.nextStep() == 0 ? -1.0 : static_cast<double>(coupling.nextStep() - 1) * h;
      if (!replay && (coupling.nextStep() == 0 ||
                      (scene.solver.end.kind == EndKind::kTime && t_last < scene.solver.end.value - 0.5 * h))) {
        ROS_FATAL("%s: the vehicle node %s went away after step %lld (t = %.6f s), before solver.end: %s",
                  me.c_str(), peer.c_str(), static_cast<long long>(coupling.nextStep()) - 1, t_last,
                  r.message.c_str());
        exit_code = kExitPeerTimeout;
      }
      break;
    }
    if (!r) {
      ROS_FATAL("%s: exchange with the vehicle node %s failed at step %llu: %s", me.c_str(), peer.c_str(),
                static_cast<unsigned long long>(coupling.nextStep()), r.message.c_str());
      exit_code = cc::exitCode(r.status);
      break;
    }
    rt::CosimStepStatus st;
    {
      CostProfile::Scope timing(cost, CostProfile::kTrackStep);
      st = track->step(coupling.states(), coupling.wrenches());
    }
    if (st != rt::CosimStepStatus::kOk) {
      ROS_FATAL("%s: step %llu: the vehicle's frame was refused (%s)", me.c_str(),
                static_cast<unsigned long long>(coupling.states().step),
                st == rt::CosimStepStatus::kWrongWheelCount      ? "wrong wheel count"
                : st == rt::CosimStepStatus::kBadWheelId        ? "bad wheel id"
                : st == rt::CosimStepStatus::kWheelOutsideWindow ? "a wheel is outside the track window "
                                                                   "(solver.track_window: margins too small?)"
                                                                 : "the track window could not move");
      exit_code = kExitPeerRefused;
      break;
    }
    const cc::Result w = coupling.send();
    if (!w) {
      ROS_FATAL("%s: sending the wrenches of step %llu to the vehicle node %s failed: %s", me.c_str(),
                static_cast<unsigned long long>(coupling.states().step), peer.c_str(), w.message.c_str());
      exit_code = cc::exitCode(w.status);
      break;
    }
    const double t = static_cast<double>(coupling.states().step) * h;
    if (t + 1e-9 * h >= static_cast<double>(n_out) * period) {
      publish(ros::Time(std::max(t, 1e-9)), coupling.states());
      ++n_out;
    }
    if (g_stop || !ros::ok()) {
      ROS_WARN("%s: stopped at t = %.4f s (%s)", me.c_str(), t, stopReason());
      stop_logged = true;
      exit_code = kExitInterrupted;
      break;
    }
  }
  coupling.close();
  const double t_stop = coupling.nextStep() == 0 ? 0.0 : static_cast<double>(coupling.nextStep() - 1) * h;
  if (master_watch.lost()) {
    ROS_ERROR("%s: the ROS master %s went away: stopped at t = %.4f s", me.c_str(), master_watch.uri().c_str(),
              t_stop);
    exit_code = kExitInterrupted;
  } else if (g_signal != 0 && !stop_logged) {
    // The signal ended a wait for the peer (logged above as an interrupted exchange): say which signal.
    ROS_WARN("%s: stopped at t = %.4f s (%s)", me.c_str(), t_stop, stopReason());
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  const double t_end = coupling.nextStep() == 0 ? 0.0 : static_cast<double>(coupling.nextStep() - 1) * h;
  cost.add(CostProfile::kPublish, -cost.seconds(CostProfile::kBagWrite));  // bag writes are inside publishing
  cost.setCount("track_steps", static_cast<double>(coupling.nextStep()));
  cost.setCount("newmark_steps", static_cast<double>(track->newmarkSteps()));
  if (window != nullptr) {
    cost.setCount("window_moves", track->windowMoves());
    cost.setCount("window_rebuilds", track->windowRebuilds());
    cost.setCount("window_move_ms_total", 1e3 * track->windowMoveSeconds());
  }
  clock.counts[rail::core::CostClock::kIrregularityEvaluations] =
      rail::contact::Irregularities::stationsEvaluated() - irregularity_stations0;
  ROS_INFO_STREAM(cost.toText(me, wall, t_end, &clock));
  if (bag.isOpen()) {
    bag.close();
    ROS_INFO("%s: bag closed: %s", me.c_str(), bag_path.c_str());
    const std::string cost_path = bag_path.substr(0, bag_path.size() - 4) + ".cost.yaml";  // <stem>.track.cost.yaml
    if (std::FILE* f = std::fopen(cost_path.c_str(), "w")) {
      std::fputs(cost.toYaml(me, scene, wall, t_end, &clock).c_str(), f);
      std::fclose(f);
    }
  }
  ROS_INFO("%s: %s after %llu steps (t = %.4f s), %ld Newmark steps, %.2f s wall", me.c_str(),
           exit_code == kExitOk ? "finished" : "stopped", static_cast<unsigned long long>(coupling.nextStep()),
           coupling.nextStep() == 0 ? 0.0 : static_cast<double>(coupling.nextStep() - 1) * h,
           track->newmarkSteps(), wall);
  // How the contact was found, so that a run never hides approximate contact points.
  rail::contact::DetectionCounts detection;
  for (int id = 0; id < track->wheelCount(); ++id)
    for (const rail::contact::DetectionWork& d : track->contactWork(id).detection) detection.add(d);
  if (detection.approximations > 0)
    ROS_WARN("%s: %s", me.c_str(), rail::contact::describe(detection).c_str());
  else
    ROS_INFO("%s: %s", me.c_str(), rail::contact::describe(detection).c_str());
  return exit_code;
}

}  // namespace

int main(int argc, char** argv) {
  if (ros_glue::nodeHelpRequested(argc, argv, "rail_track", "the track side of a railsim run (FE track and the wheel-rail contact in co-simulation, moving loads, replay)")) return 0;
  ros::init(argc, argv, "rail_track", ros::init_options::NoSigintHandler);
  // Bags, cost profiles and their directories are the user's alone (the shm region is 0600 already).
  ::umask(077);
  ros_glue::installStopSignals();
  if (const int rc = ros_glue::waitForMaster(ros::this_node::getName(), g_signal); rc != 0) return rc;
  ros::NodeHandle nh, pnh("~");
  Scene scene;
  if (!ros_glue::readScene(pnh, scene)) return kExitBadInput;
  ROS_INFO_STREAM(ros::this_node::getName() << ": will simulate\n" << describe(scene, Role::kTrack));
  if (!scene.needsTrackNode()) {
    ROS_INFO("%s: track_model is rigid: the vehicle runs alone, nothing to do here",
             ros::this_node::getName().c_str());
    return kExitOk;
  }
  if (pnh.param("validate_only", false)) return kExitOk;
  try {
    const std::string replay_bag = pnh.param<std::string>("replay_bag", "");
    if (!replay_bag.empty()) {
      if (!scene.has_vehicle) {
        ROS_FATAL("%s: ~replay_bag: the scene has no vehicle to replay", ros::this_node::getName().c_str());
        return kExitBadInput;
      }
      return runCosim(nh, pnh, scene, "(replay)", 0.0, replay_bag);
    }
    if (scene.has_vehicle) {
      std::string peer;
      double wheel_span = 0.0;
      const int rc = ros_glue::handshakeAsTrack(nh, scene, peer, wheel_span);
      if (rc != kExitOk) return rc;
      return runCosim(nh, pnh, scene, peer, wheel_span);
    }
    return runMovingLoads(nh, pnh, scene);
  } catch (const std::exception& e) {
    ROS_FATAL("%s: internal error: %s", ros::this_node::getName().c_str(), e.what());
    return kExitInternal;
  }
}
