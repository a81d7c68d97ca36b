// rail_vehicle node: ROS wiring of the vehicle side. Reads the scene from the parameter server, validates
// it and reports what it will simulate. On the rigid track (effects.track_model: rigid) it runs the
// VehicleSimulator to solver.end, publishing /clock, wheel states, contact points and wrenches, wheelset
// kinematics and tf frames, and records output.topics to output.bag. In a co-simulation (rigid_fe or
// flexible) it checks with the track node that both run the same scene (handshake), opens the scene's
// transport (service, topic or shm) and runs the CosimVehicle in lockstep with the track to solver.end,
// with the same outputs and bag; the contact points are then the track node's. Physics lives in the core.
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosgraph_msgs/Clock.h>
#include <tf2_msgs/TFMessage.h>
#include <visualization_msgs/MarkerArray.h>
#include <tf2_ros/transform_broadcaster.h>

#include <rail_core/cost_profile.hpp>
#include <rail_core/coupling/timed_transport.hpp>
#include <rail_core/exit_codes.hpp>
#include <rail_ros/scene_param.hpp>
#include <rail_core/scene_loader.hpp>
#include <rail_msgs/ContactPoints.h>
#include <rail_msgs/ContactWrenches.h>
#include <rail_msgs/WheelStates.h>
#include <rail_msgs/WheelsetKinematics.h>
#include <rail_msgs/FloorAccelerations.h>
#include <rail_msgs/Energy.h>
#include <rail_vehicle_node/cosim_vehicle.hpp>
#include <rail_vehicle_node/vehicle_loader.hpp>
#include <rail_vehicle_node/vehicle_simulator.hpp>

#include <rail_ros/contact_point_message.hpp>
#include <rail_ros/cosim_transport.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <sys/stat.h>

#include "rail_ros/master_watch.hpp"
#include "rail_ros/node_scaffold.hpp"

using namespace rail::core;
namespace ros_glue = rail::ros_glue;
namespace rv = rail::vehicle;
namespace rc = rail::contact;

namespace {

// The stop request of this process (rail_ros/node_scaffold.hpp): SIGINT, SIGTERM or a lost master.
std::atomic<bool>& g_stop = rail::ros_glue::nodeStop().requested;
std::atomic<int>& g_signal = rail::ros_glue::nodeStop().signal;
const char* stopReason() { return rail::ros_glue::nodeStop().reason(); }

bool records(const Scene& scene, const char* topic) {
  return std::find(scene.output.topics.begin(), scene.output.topics.end(), topic) != scene.output.topics.end();
}

void fill(geometry_msgs::Vector3& out, const rv::Vector3& v) { out.x = v.x(), out.y = v.y(), out.z = v.z(); }
void fill(geometry_msgs::Point& out, const rv::Vector3& v) { out.x = v.x(), out.y = v.y(), out.z = v.z(); }
void fill(geometry_msgs::Quaternion& out, const rv::Vector4& p) { out.w = p[0], out.x = p[1], out.y = p[2], out.z = p[3]; }

// Messages of one output instant, sized once and refilled in place.
struct Outputs {
  rail_msgs::WheelStates wheel_states;
  rail_msgs::ContactPoints contact_points;
  rail_msgs::ContactWrenches contact_wrenches;
  rail_msgs::WheelsetKinematics kinematics;
  rail_msgs::FloorAccelerations floor;  // effects.floor_acceleration_output
  rail_msgs::Energy energy;             // effects.energy_output
  tf2_msgs::TFMessage tf;
  rosgraph_msgs::Clock clock;
  rail::contact::TrackPoint track_point_;  // scratch of Update

  Outputs(const rv::VehicleSimulator& sim, const Scene& scene) {
    const std::size_t n = sim.wheels().size();
    wheel_states.wheels.resize(n);
    wheel_states.scene_hash = scene.hash;
    contact_points.points.resize(2 * n);
    contact_wrenches.wrenches.resize(n);
    contact_wrenches.scene_hash = scene.hash;
    kinematics.wheelsets.resize(sim.wheelsets().size());
    const auto& points = sim.model().measurementPoints();
    floor.header.frame_id = "carbody";
    energy.header.frame_id = "world";
    floor.names.resize(points.size());
    floor.position.resize(points.size());
    floor.specific_force.resize(points.size());
    for (std::size_t m = 0; m < points.size(); ++m) {
      floor.names[m] = points[m].name;
      fill(floor.position[m], points[m].p_reference);
    }
    tf.transforms.resize(sim.bodies().size());
    for (auto& h : {&wheel_states.header, &contact_points.header, &contact_wrenches.header, &kinematics.header}) {
      h->frame_id = "world";
    }
    for (std::size_t b = 0; b < sim.bodies().size(); ++b) {
      tf.transforms[b].header.frame_id = "world";
      tf.transforms[b].child_frame_id = frameName(sim, static_cast<int>(b));
    }
  }

  // tf frame names: carbody, bogie_1..., wheelset_1... (by reference x, front first); other bodies keep
  // their data-file names.
  static std::string frameName(const rv::VehicleSimulator& sim, int b) {
    const auto& ws = sim.wheelsetBodies();
    const auto it = std::find(ws.begin(), ws.end(), b);
    if (it != ws.end()) return "wheelset_" + std::to_string(it - ws.begin() + 1);
    const std::string& name = sim.model().bodies()[static_cast<std::size_t>(b)].name;
    if (name.rfind("bogie", 0) == 0) {
      int rank = 1;
      const double x = sim.model().bodies()[static_cast<std::size_t>(b)].r_reference.x();
      for (const auto& other : sim.model().bodies()) {
        if (other.name.rfind("bogie", 0) == 0 && other.r_reference.x() > x) ++rank;
      }
      return "bogie_" + std::to_string(rank);
    }
    return name;
  }

  void update(const rv::VehicleSimulator& sim, const ros::Time& stamp, std::uint64_t step) {
    wheel_states.header.stamp = contact_points.header.stamp = contact_wrenches.header.stamp = stamp;
    kinematics.header.stamp = stamp;
    floor.header.stamp = stamp;
    energy.header.stamp = stamp;
    energy.kinetic = sim.energy().kinetic;
    energy.potential = sim.energy().potential;
    energy.total = energy.kinetic + energy.potential;
    clock.clock = stamp;
    wheel_states.step = contact_wrenches.step = step;
    for (std::size_t i = 0; i < sim.wheels().size(); ++i) {
      const rv::WheelOutput& w = sim.wheels()[i];
      rail_msgs::WheelState& m = wheel_states.wheels[i];
      m.wheel_id = static_cast<std::uint8_t>(w.wheel_id);
      m.wheelset = static_cast<std::uint8_t>(w.wheelset);
      m.side = static_cast<std::uint8_t>(w.side);
      m.arc_length = w.arc_length;
      fill(m.position, w.p_in_world);
      fill(m.orientation, w.orientation);
      fill(m.linear_velocity, w.v_in_world);
      fill(m.angular_velocity, w.omega_in_world);
      rail_msgs::ContactWrench& cw = contact_wrenches.wrenches[i];
      cw.wheel_id = m.wheel_id;
      fill(cw.force, w.force_in_world);
      fill(cw.moment, w.moment_in_world);
      for (int k = 0; k < 2; ++k) {
        const rc::ContactPointResult& c = sim.contacts()[i].contact[k];
        rail_msgs::ContactPoint& p = contact_points.points[2 * i + static_cast<std::size_t>(k)];
        rail::ros_glue::toMessage(c, m.wheel_id, m.side, k, p);
      }
    }
    for (std::size_t w = 0; w < sim.wheelsets().size(); ++w) {
      const rv::WheelsetTrackOutput& o = sim.wheelsets()[w];
      rail_msgs::WheelsetTrackState& m = kinematics.wheelsets[w];
      m.wheelset = static_cast<std::uint8_t>(o.wheelset);
      m.arc_length = o.arc_length;
      m.lateral_displacement = o.lateral;
      m.vertical_displacement = o.vertical;
      m.angle_of_attack = o.angle_of_attack;
      m.roll = o.roll;
      m.spin_speed = o.spin;
      // Wheel forces in the canted track frame at the wheelset's station (Y lateral, Q vertical).
      sim.track().centre(o.arc_length, track_point_);
      for (std::size_t i = 0; i < sim.wheels().size(); ++i) {
        const rv::WheelOutput& wheel = sim.wheels()[i];
        if (wheel.wheelset != o.wheelset) continue;
        const rv::Vector3 f_in_track = track_point_.R_track_to_world.transpose() * wheel.force_in_world;
        fill(wheel.side == 0 ? m.left_force_in_track : m.right_force_in_track, f_in_track);
      }
    }
    for (std::size_t m = 0; m < sim.measurements().size(); ++m) {
      fill(floor.specific_force[m], sim.measurements()[m].specific_force_in_body);
    }
    for (std::size_t b = 0; b < sim.bodies().size(); ++b) {
      geometry_msgs::TransformStamped& t = tf.transforms[b];
      t.header.stamp = stamp;
      t.transform.translation.x = sim.bodies()[b].p_in_world.x();
      t.transform.translation.y = sim.bodies()[b].p_in_world.y();
      t.transform.translation.z = sim.bodies()[b].p_in_world.z();
      fill(t.transform.rotation, sim.bodies()[b].orientation);
    }
  }
};

// rviz markers of the vehicle (effects.rviz_markers): a box per body sized by its kind (carbody, bogie
// frame, axlebox), each wheelset as its axle and two wheels, and the contact force on each wheel as an
// arrow from the wheel's lowest point (force scaled by `force_scale`, m/N). Built once; Update refills poses
// and arrows in place. Sizes are for the picture only (the model has no geometry beyond its points).
struct VehicleMarkers {
  visualization_msgs::MarkerArray array;
  std::vector<int> body_marker;         // per body: its marker, or -1 (wheelsets: the axle)
  std::vector<int> wheel_marker;        // per wheel: its disc
  std::vector<int> arrow_marker;        // per wheel: the force arrow
  double force_scale = 1e-5;            // m per N: 100 kN draws 1 m
  double wheel_radius = 0.445;          // m

  VehicleMarkers(const rv::VehicleSimulator& sim, double radius, double scale) : force_scale(scale), wheel_radius(radius) {
    const std::size_t nb = sim.bodies().size();
    body_marker.assign(nb, -1);
    auto add = [&](const std::string& ns, int type, double sx, double sy, double sz, float r, float g, float b) {
      visualization_msgs::Marker m;
      m.header.frame_id = "world";
      m.ns = ns;
      m.id = static_cast<int>(array.markers.size());
      m.type = type;
      m.action = visualization_msgs::Marker::ADD;
      m.scale.x = sx, m.scale.y = sy, m.scale.z = sz;
      m.color.r = r, m.color.g = g, m.color.b = b, m.color.a = 0.8f;
      m.pose.orientation.w = 1.0;
      array.markers.push_back(m);
      return static_cast<int>(array.markers.size()) - 1;
    };
    for (std::size_t b = 0; b < nb; ++b) {
      const std::string name = Outputs::frameName(sim, static_cast<int>(b));
      if (name == "carbody") {
        body_marker[b] = add("carbody", visualization_msgs::Marker::CUBE, 24.0, 2.9, 2.6, 0.7f, 0.7f, 0.75f);
        array.markers[static_cast<std::size_t>(body_marker[b])].color.a = 0.35f;
      } else if (name.rfind("bogie", 0) == 0) {
        body_marker[b] = add("bogie_frames", visualization_msgs::Marker::CUBE, 2.8, 2.0, 0.3, 0.2f, 0.3f, 0.6f);
      } else if (name.rfind("wheelset", 0) == 0) {
        body_marker[b] = add("wheelsets", visualization_msgs::Marker::CYLINDER, 0.16, 0.16, 1.9, 0.3f, 0.3f, 0.3f);
      } else {
        body_marker[b] = add("axleboxes", visualization_msgs::Marker::CUBE, 0.35, 0.25, 0.25, 0.5f, 0.5f, 0.2f);
      }
    }
    for (std::size_t i = 0; i < sim.wheels().size(); ++i) {
      wheel_marker.push_back(add("wheels", visualization_msgs::Marker::CYLINDER, 2 * radius, 2 * radius, 0.13,
                                 0.25f, 0.25f, 0.25f));
    }
    for (std::size_t i = 0; i < sim.wheels().size(); ++i) {
      arrow_marker.push_back(add("contact_forces", visualization_msgs::Marker::ARROW, 0.05, 0.12, 0.15,
                                 0.9f, 0.2f, 0.1f));
      array.markers.back().points.resize(2);
    }
  }

  // q * (rotation of +90 deg about x): a cylinder's axis (z) along the body's y (the axle).
  static void axleOrientation(const rv::Vector4& q, geometry_msgs::Quaternion& out) {
    const double c = std::sqrt(0.5), w = q[0], x = q[1], y = q[2], z = q[3];
    out.w = c * (w - x), out.x = c * (x + w), out.y = c * (y + z), out.z = c * (z - y);
  }

  const visualization_msgs::MarkerArray& update(const rv::VehicleSimulator& sim, const ros::Time& stamp) {
    for (auto& m : array.markers) m.header.stamp = stamp;
    for (std::size_t b = 0; b < sim.bodies().size(); ++b) {
      visualization_msgs::Marker& m = array.markers[static_cast<std::size_t>(body_marker[b])];
      fill(m.pose.position, sim.bodies()[b].p_in_world);
      if (m.ns == "wheelsets") {
        axleOrientation(sim.bodies()[b].orientation, m.pose.orientation);
      } else {
        fill(m.pose.orientation, sim.bodies()[b].orientation);
      }
    }
    for (std::size_t i = 0; i < sim.wheels().size(); ++i) {
      const rv::WheelOutput& w = sim.wheels()[i];
      visualization_msgs::Marker& disc = array.markers[static_cast<std::size_t>(wheel_marker[i])];
      fill(disc.pose.position, w.p_in_world);
      axleOrientation(w.orientation, disc.pose.orientation);
      visualization_msgs::Marker& arrow = array.markers[static_cast<std::size_t>(arrow_marker[i])];
      const rv::Vector3 foot = w.p_in_world - rv::Vector3(0.0, 0.0, wheel_radius);
      fill(arrow.points[0], foot - force_scale * w.force_in_world);
      fill(arrow.points[1], foot);
    }
    return array;
  }
};

// Writes a cost profile beside the bag: <bag stem><suffix>. Nothing without a bag.
void writeCost(const std::string& bag_path, const char* suffix, const std::string& yaml, const std::string& node) {
  if (bag_path.empty()) return;
  const std::size_t dot = bag_path.rfind(".bag");
  const std::string path = (dot != std::string::npos ? bag_path.substr(0, dot) : bag_path) + suffix;
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    ROS_WARN("%s: cannot write the cost profile %s", node.c_str(), path.c_str());
    return;
  }
  std::fputs(yaml.c_str(), f);
  std::fclose(f);
}

std::string outputDir(ros::NodeHandle& pnh) {
  std::string dir;
  if (pnh.getParam("output_dir", dir) && !dir.empty()) return dir;
  const char* ros_home = std::getenv("ROS_HOME");
  if (ros_home != nullptr && *ros_home != '\0') return std::string(ros_home) + "/railsim";
  const char* home = std::getenv("HOME");
  return std::string(home != nullptr ? home : ".") + "/.ros/railsim";
}

// mkdir -p
bool makeDirs(const std::string& path) {
  for (std::size_t pos = 1; pos <= path.size(); ++pos) {
    if (pos == path.size() || path[pos] == '/') {
      const std::string part = path.substr(0, pos);
      if (::mkdir(part.c_str(), 0755) != 0 && errno != EEXIST) return false;
    }
  }
  return true;
}

// The exit code of a run that stopped with status s (not kRunning/kFinished).
int exitCodeOf(rv::RunStatus s) {
  switch (s) {
    case rv::RunStatus::kDerailed:
    case rv::RunStatus::kLeftTrack: return kExitDerailed;
    case rv::RunStatus::kNonFinite:
    case rv::RunStatus::kIntegratorFailed: return kExitNumerical;
    default: return kExitInternal;
  }
}

const char* statusName(rv::RunStatus s) {
  switch (s) {
    case rv::RunStatus::kRunning: return "running";
    case rv::RunStatus::kFinished: return "finished";
    case rv::RunStatus::kDerailed: return "derailed";
    case rv::RunStatus::kNonFinite: return "non-finite state";
    case rv::RunStatus::kLeftTrack: return "left the track";
    case rv::RunStatus::kIntegratorFailed: return "integrator failure";
  }
  return "?";
}

// Runs the vehicle to solver.end: alone on the rigid track, or (scene.cosimulation()) as the vehicle side of
// the co-simulation over the scene's transport, after the handshake. Returns the exit code.
// peer: the track node's name (handshake).
int runVehicle(const Scene& scene, ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& peer) {
  const std::string node = ros::this_node::getName();
  const bool cosim = scene.cosimulation();
  CostProfile cost;
  rail::ros_glue::MasterWatch master_watch(g_stop);  // a lost master stops the run like a signal
  rail::core::CostClock clock;  // the finer split, filled by the simulator (cost_profile.hpp)
  rv::SimulatorSettings sim_settings;
  sim_settings.cost = &clock;
  const auto setup0 = std::chrono::steady_clock::now();
  std::unique_ptr<rail::core::coupling::FrameTransport> transport;
  std::unique_ptr<rail::core::coupling::TimedTransport> timed_transport;  // adds exchange waits to `cost`
  std::unique_ptr<rv::CosimVehicle> cosim_vehicle;
  std::unique_ptr<rv::VehicleSimulator> sim_alone;
  rv::VehicleSimulator* sim = nullptr;
  if (cosim) {
    try {
      transport = rail::ros_glue::makeTransport(scene, rail::core::coupling::Role::kVehicle, nh, pnh, peer,
                                              &g_stop);
    } catch (const rail::core::coupling::CouplingError& e) {
      ROS_FATAL("%s: cannot open the %s transport to the track node: %s", node.c_str(),
                toString(scene.solver.transport), e.what());
      return rail::core::coupling::exitCode(e.status());
    } catch (const std::exception& e) {
      ROS_FATAL("%s: cannot open the %s transport: %s", node.c_str(), toString(scene.solver.transport), e.what());
      return kExitBadInput;
    }
    try {
      timed_transport = std::make_unique<rail::core::coupling::TimedTransport>(*transport, cost);
      cosim_vehicle = std::make_unique<rv::CosimVehicle>(scene, *timed_transport, sim_settings);
    } catch (const std::exception& e) {
      ROS_FATAL("%s: cannot build the co-simulated vehicle: %s", node.c_str(), e.what());
      transport->close();
      return kExitBadInput;
    }
    sim = &cosim_vehicle->simulator();
  } else {
    try {
      sim_alone = std::make_unique<rv::VehicleSimulator>(scene, sim_settings);
    } catch (const std::exception& e) {
      ROS_FATAL("%s: cannot build the vehicle: %s", node.c_str(), e.what());
      return kExitBadInput;
    }
    sim = sim_alone.get();
  }
  ROS_INFO("%s: vehicle settled on the rails (lowered %.4f mm, wheel loads %.1f N of %.1f N); integrating with "
           "%s, rtol %g, atol %g, max step %g s (0: none)%s", node.c_str(), -sim->settleLift() * 1e3,
           sim->settledWheelLoadSum(), sim->staticLoad(),
           sim->method() == rv::IntegrationMethod::kBdf ? "BDF" : "Adams", scene.solver.vehicle_rtol,
           scene.solver.vehicle_atol, sim->maxStep(),
           cosim ? (std::string("; co-simulation with the track over ") + toString(scene.solver.transport) +
                    ", track step " + std::to_string(scene.solver.track_step) + " s").c_str() : "");

  ros::Publisher pub_clock = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  ros::Publisher pub_states = nh.advertise<rail_msgs::WheelStates>("wheel_states", 100);
  ros::Publisher pub_points;
  // In a co-simulation the contact is evaluated by the track node, which publishes the contact points.
  const bool own_points = scene.effects.contact_point_output && !cosim;
  if (own_points) pub_points = nh.advertise<rail_msgs::ContactPoints>("contact_points", 100);
  ros::Publisher pub_wrenches = nh.advertise<rail_msgs::ContactWrenches>("contact_wrenches", 100);
  ros::Publisher pub_kinematics = nh.advertise<rail_msgs::WheelsetKinematics>("wheelset_kinematics", 100);
  tf2_ros::TransformBroadcaster tf_broadcaster;
  // Carbody floor accelerations (effects.floor_acceleration_output), at the data file's measurement points.
  const bool own_floor = scene.effects.floor_acceleration_output;
  ros::Publisher pub_floor;
  if (own_floor) {
    pub_floor = nh.advertise<rail_msgs::FloorAccelerations>("floor_accelerations", 100);
  }
  // Mechanical energy of the vehicle (effects.energy_output).
  const bool own_energy = scene.effects.energy_output;
  ros::Publisher pub_energy;
  if (own_energy) pub_energy = nh.advertise<rail_msgs::Energy>("vehicle_energy", 100);
  // rviz markers (effects.rviz_markers): built only when on, published at ~marker_rate (default 25 Hz).
  ros::Publisher pub_markers;
  std::unique_ptr<VehicleMarkers> markers;
  double marker_period = 0.0, next_marker = 0.0;
  if (scene.effects.rviz_markers) {
    pub_markers = nh.advertise<visualization_msgs::MarkerArray>("/vehicle_markers", 2);
    markers.reset(new VehicleMarkers(*sim, scene.vehicle.nominal_radius, pnh.param("force_scale", 1e-5)));
    marker_period = 1.0 / std::min(scene.output.rate, pnh.param("marker_rate", 25.0));
  }

  rosbag::Bag bag;
  std::string bag_path;
  if (!scene.output.bag.empty()) {
    bag_path = scene.output.bag[0] == '/' ? scene.output.bag : outputDir(pnh) + "/" + scene.output.bag;
    const std::string dir = bag_path.substr(0, bag_path.find_last_of('/'));
    try {
      if (!makeDirs(dir)) throw std::runtime_error("cannot create the directory " + dir);
      bag.open(bag_path, rosbag::bagmode::Write);
    } catch (const std::exception& e) {
      ROS_FATAL("%s: output.bag: cannot write %s: %s", node.c_str(), bag_path.c_str(), e.what());
      return kExitBadInput;
    }
    ROS_INFO("%s: recording [%s] to %s", node.c_str(), [&] {
      std::string t;
      for (const auto& s : scene.output.topics) t += (t.empty() ? "" : ", ") + s;
      return t;
    }().c_str(), bag_path.c_str());
  }
  const bool rec_states = bag.isOpen() && records(scene, "wheel_states");
  const bool rec_points = bag.isOpen() && records(scene, "contact_points") && own_points;
  const bool rec_wrenches = bag.isOpen() && records(scene, "contact_wrenches");
  const bool rec_kinematics = bag.isOpen() && records(scene, "wheelset_kinematics");
  const bool rec_floor = bag.isOpen() && records(scene, "floor_accelerations") && own_floor;
  const bool rec_energy = bag.isOpen() && records(scene, "vehicle_energy") && own_energy;
  const bool rec_tf = bag.isOpen() && records(scene, "tf");
  const bool rec_clock = bag.isOpen() && records(scene, "clock");

  Outputs out(*sim, scene);
  const double dt = 1.0 / scene.output.rate;
  const double t_estimate = sim->endTimeEstimate();
  // A time end stops exactly there; an arc-length end when the leading wheelset passes it.
  const double t_limit = scene.solver.end.kind == EndKind::kTime ? scene.solver.end.value : 1e9;
  auto publish = [&](std::uint64_t step) {
    CostProfile::Scope timing(cost, CostProfile::kPublish);
    const ros::Time stamp(std::max(sim->time(), 1e-9));
    out.update(*sim, stamp, step);
    pub_clock.publish(out.clock);
    pub_states.publish(out.wheel_states);
    rail::core::timedOutput(&clock, rail::core::CostClock::kContactPointOutput, own_points,
                            [&] { pub_points.publish(out.contact_points); });
    pub_wrenches.publish(out.contact_wrenches);
    pub_kinematics.publish(out.kinematics);
    if (own_floor) pub_floor.publish(out.floor);
    if (own_energy) pub_energy.publish(out.energy);
    tf_broadcaster.sendTransform(out.tf.transforms);
    rail::core::timedOutput(&clock, rail::core::CostClock::kMarkers, markers && sim->time() + 1e-12 >= next_marker, [&] {
      next_marker += marker_period;
      pub_markers.publish(markers->update(*sim, stamp));
    });
    if (!bag.isOpen()) return;
    CostProfile::Scope bag_timing(cost, CostProfile::kBagWrite);
    if (rec_states) bag.write("/wheel_states", stamp, out.wheel_states);
    if (rec_points) bag.write("/contact_points", stamp, out.contact_points);
    if (rec_wrenches) bag.write("/contact_wrenches", stamp, out.contact_wrenches);
    if (rec_kinematics) bag.write("/wheelset_kinematics", stamp, out.kinematics);
    if (rec_floor) bag.write("/floor_accelerations", stamp, out.floor);
    if (rec_energy) bag.write("/vehicle_energy", stamp, out.energy);
    if (rec_tf) bag.write("/tf", stamp, out.tf);
    if (rec_clock) bag.write("/clock", stamp, out.clock);
  };

  int rc = kExitOk;
  bool stop_logged = false;  // the run loop said why it stopped
  const auto wall0 = std::chrono::steady_clock::now();
  cost.add(CostProfile::kSetUp, std::chrono::duration<double>(wall0 - setup0).count());
  const long long irregularity_stations0 = rail::contact::Irregularities::stationsEvaluated();
  auto last_report = wall0;
  auto report = [&] {
    const auto now = std::chrono::steady_clock::now();
    if (std::chrono::duration<double>(now - last_report).count() < 5.0) return;
    last_report = now;
    const double wall = std::chrono::duration<double>(now - wall0).count();
    const double rtf = sim->time() / std::max(wall, 1e-9);
    const double eta = (t_estimate - sim->time()) / std::max(rtf, 1e-12);
    ROS_INFO("%s: t = %.3f s (%.1f %%), leading wheelset at s = %.2f m, real-time factor %.3f, ETA %.0f s",
             node.c_str(), sim->time(), 100.0 * sim->time() / std::max(t_estimate, 1e-9),
             sim->leadingArcLength(), rtf, std::max(eta, 0.0));
  };
  try {
    if (!cosim) {
      publish(0);
      rv::RunStatus status = rv::RunStatus::kRunning;
      for (std::uint64_t step = 1; status == rv::RunStatus::kRunning; ++step) {
        if (g_stop || !ros::ok()) {
          ROS_WARN("%s: stopped at t = %.4f s (%s); closing the bag", node.c_str(), sim->time(), stopReason());
          stop_logged = true;
          rc = kExitInterrupted;
          break;
        }
        const double t_next = std::min(static_cast<double>(step) * dt, t_limit);
        {
          CostProfile::Scope timing(cost, CostProfile::kVehicleIntegration);
          status = sim->advanceTo(t_next);
        }
        publish(step);
        report();
        if (status != rv::RunStatus::kRunning && status != rv::RunStatus::kFinished) {
          ROS_ERROR("%s: run stopped (%s): %s", node.c_str(), statusName(status), sim->message().c_str());
          rc = exitCodeOf(status);
        }
      }
    } else {
      // Lockstep: every Step() is one track step h (one exchange); outputs at the exchange that reaches each
      // output time k / output.rate (the exchange times are k h exactly).
      rv::CosimVehicle& v = *cosim_vehicle;
      const double h = v.trackStep();
      std::uint64_t n_out = 0;
      rv::RunStatus status;
      {
        CostProfile::Scope timing(cost, CostProfile::kVehicleIntegration);
        status = v.start();
      }
      while (true) {
        if (status != rv::RunStatus::kRunning && status != rv::RunStatus::kFinished) {
          if (status == rv::RunStatus::kIntegratorFailed &&
              v.exchangeStatus() != rail::core::coupling::Status::kOk) {
            ROS_FATAL("%s: exchange with the track node failed at step %llu (t = %.6f s): %s (track node %s)",
                      node.c_str(), static_cast<unsigned long long>(v.stepsExchanged()), v.time(),
                      v.message().c_str(), peer.c_str());
            rc = rail::core::coupling::exitCode(v.exchangeStatus());
          } else {
            ROS_ERROR("%s: run stopped (%s) at t = %.6f s: %s", node.c_str(), statusName(status), v.time(),
                      v.message().c_str());
            rc = exitCodeOf(status);
          }
          break;
        }
        if (v.time() + 1e-9 * h >= static_cast<double>(n_out) * dt || status == rv::RunStatus::kFinished) {
          publish(n_out);
          ++n_out;
          report();
        }
        if (status == rv::RunStatus::kFinished) break;
        if (g_stop || !ros::ok()) {
          ROS_WARN("%s: stopped at t = %.4f s (%s); closing the bag", node.c_str(), v.time(), stopReason());
          stop_logged = true;
          rc = kExitInterrupted;
          break;
        }
        CostProfile::Scope timing(cost, CostProfile::kVehicleIntegration);
        status = v.step();
      }
      v.close();
      ROS_INFO("%s: %llu steps exchanged with the track node, largest CVODE step %.3g s", node.c_str(),
               static_cast<unsigned long long>(v.stepsExchanged()), v.maxInternalStep());
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    const rv::IntegratorCounters c = sim->counters();
    // The exchange waits were timed inside the steps too: the integration is what remains.
    if (cosim) {
      cost.add(CostProfile::kVehicleIntegration, -cost.seconds(CostProfile::kTransportWait));
    }
    // Bag writes happen inside the publishing scope: publishing is what remains.
    cost.add(CostProfile::kPublish, -cost.seconds(CostProfile::kBagWrite));
    cost.setCount("cvode_steps", static_cast<double>(c.steps));
    cost.setCount("rhs_evaluations", static_cast<double>(c.rhs_evals));
    cost.setCount("rhs_for_jacobians", static_cast<double>(c.rhs_evals_jacobian));
    cost.setCount("jacobians", static_cast<double>(c.jacobian_evals));
    cost.setCount("projections", static_cast<double>(c.projections));
    if (cosim) cost.setCount("exchanges", static_cast<double>(cosim_vehicle->stepsExchanged()));
    clock.counts[rail::core::CostClock::kIrregularityEvaluations] =
        rail::contact::Irregularities::stationsEvaluated() - irregularity_stations0;
    ROS_INFO_STREAM(cost.toText(node, wall, sim->time(), &clock));
    writeCost(bag_path, ".cost.yaml", cost.toYaml(node, scene, wall, sim->time(), &clock), node);
    ROS_INFO("%s: %s at t = %.4f s, leading wheelset at s = %.3f m; %.2f s wall (%.2f s per simulated s); CVODE "
             "%ld steps, %ld RHS + %ld for %ld Jacobians, %ld projections, %ld Adams fallbacks", node.c_str(),
             rc == kExitOk ? "finished" : "stopped", sim->time(), sim->leadingArcLength(), wall,
             wall / std::max(sim->time(), 1e-9), c.steps, c.rhs_evals, c.rhs_evals_jacobian, c.jacobian_evals,
             c.projections, c.adams_fallbacks);
    // How the contact was found (the vehicle's own contact on the rigid track), never hiding approximations.
    if (!cosim) {
      rail::contact::DetectionCounts detection;
      for (const rail::contact::WheelContactWork& w : sim->contactData().work)
        for (const rail::contact::DetectionWork& d : w.detection) detection.add(d);
      if (detection.approximations > 0)
        ROS_WARN("%s: %s", node.c_str(), rail::contact::describe(detection).c_str());
      else
        ROS_INFO("%s: %s", node.c_str(), rail::contact::describe(detection).c_str());
    }
  } catch (const std::exception& e) {
    ROS_FATAL("%s: internal error at t = %.4f s: %s", node.c_str(), sim->time(), e.what());
    rc = kExitInternal;
    if (cosim_vehicle) cosim_vehicle->close();
  }
  if (master_watch.lost()) {
    ROS_ERROR("%s: the ROS master %s went away: stopped at t = %.4f s", node.c_str(), master_watch.uri().c_str(),
              sim->time());
    rc = kExitInterrupted;
  } else if (g_signal != 0 && !stop_logged) {
    // The signal ended a wait for the peer (logged above as an interrupted exchange): say which signal.
    ROS_WARN("%s: stopped at t = %.4f s (%s); closing the bag", node.c_str(), sim->time(), stopReason());
  }
  if (bag.isOpen()) {
    bag.close();
    ROS_INFO("%s: bag closed: %s", node.c_str(), bag_path.c_str());
  }
  return rc;
}

}  // namespace

int main(int argc, char** argv) {
  if (ros_glue::nodeHelpRequested(argc, argv, "rail_vehicle", "the vehicle side of a railsim run (multibody vehicle on CVODE; alone on the rigid track or co-simulated with rail_track)")) return 0;
  ros::init(argc, argv, "rail_vehicle", ros::init_options::NoSigintHandler);
  // Bags, cost profiles and their directories are the user's alone (the shm region is 0600 already).
  ::umask(077);
  ros_glue::installStopSignals();
  if (const int rc = ros_glue::waitForMaster(ros::this_node::getName(), g_signal); rc != 0) return rc;
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  Scene scene;
  if (!ros_glue::readScene(pnh, scene)) return kExitBadInput;
  ROS_INFO_STREAM(ros::this_node::getName() << ": will simulate\n" << describe(scene, Role::kVehicle));
  if (!scene.has_vehicle) {
    ROS_INFO("%s: the scene has no vehicle (moving loads on the track alone): nothing to do",
             ros::this_node::getName().c_str());
    return kExitOk;
  }
  if (pnh.param("validate_only", false)) return kExitOk;
  std::string peer;
  if (scene.cosimulation()) {
    // The track sizes its window by the vehicle's wheel span: the vehicle's own data says it.
    double wheel_span = 0.0;
    try {
      wheel_span = rv::loadVehicleModel(scene.vehicle.data.path).wheelSpan();
    } catch (const std::exception& e) {
      ROS_FATAL("%s: %s", ros::this_node::getName().c_str(), e.what());
      return kExitBadInput;
    }
    const int rc = ros_glue::handshakeAsVehicle(scene, wheel_span, peer);
    if (rc != kExitOk) return rc;
  }
  const int rc = runVehicle(scene, nh, pnh, peer);
  ros::shutdown();
  return rc;
}
