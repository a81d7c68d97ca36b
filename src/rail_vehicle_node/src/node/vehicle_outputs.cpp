#include "vehicle_outputs.hpp"

#include <rosgraph_msgs/Clock.h>
#include <tf2_msgs/TFMessage.h>
#include <visualization_msgs/MarkerArray.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <sstream>
#include <thread>
#include <utility>
#include <vector>

#include <rail_msgs/ContactPoints.h>
#include <rail_msgs/ContactWrenches.h>
#include <rail_msgs/Energy.h>
#include <rail_msgs/FloorAccelerations.h>
#include <rail_msgs/WheelStates.h>
#include <rail_msgs/WheelsetKinematics.h>
#include <Eigen/Geometry>

#include <rail_core/exit_codes.hpp>
#include <rail_core/geometry_builder.hpp>
#include <rail_ros/contact_point_message.hpp>

namespace rail::vehicle {

namespace {

void fill(geometry_msgs::Vector3& out, const Vector3& v) { out.x = v.x(), out.y = v.y(), out.z = v.z(); }
void fill(geometry_msgs::Point& out, const Vector3& v) { out.x = v.x(), out.y = v.y(), out.z = v.z(); }
void fill(geometry_msgs::Quaternion& out, const Vector4& p) { out.w = p[0], out.x = p[1], out.y = p[2], out.z = p[3]; }

}  // namespace

// Messages of one output instant, sized once and refilled in place.
struct OutputMessages {
  rail_msgs::WheelStates wheel_states;
  rail_msgs::ContactPoints contact_points;
  rail_msgs::ContactWrenches contact_wrenches;
  rail_msgs::WheelsetKinematics kinematics;
  rail_msgs::FloorAccelerations floor;  // effects.floor_acceleration_output
  rail_msgs::Energy energy;             // effects.energy_output
  tf2_msgs::TFMessage tf;
  rosgraph_msgs::Clock clock;
  rail::contact::TrackPoint track_point_;  // scratch of Update

  OutputMessages(const VehicleSimulator& sim, std::uint64_t scene_hash) {
    const std::size_t n = sim.wheels().size();
    wheel_states.wheels.resize(n);
    wheel_states.scene_hash = scene_hash;
    contact_points.points.resize(contact::kContactSlots * n);
    contact_wrenches.wrenches.resize(n);
    contact_wrenches.scene_hash = scene_hash;
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
  static std::string frameName(const VehicleSimulator& sim, int b) {
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

  void update(const VehicleSimulator& sim, const ros::Time& stamp, std::uint64_t step) {
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
      const WheelOutput& w = sim.wheels()[i];
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
      for (int k = 0; k < contact::kContactSlots; ++k) {
        const contact::ContactPointResult& c = sim.contacts()[i].contact[k];
        rail_msgs::ContactPoint& p = contact_points.points[contact::kContactSlots * i + static_cast<std::size_t>(k)];
        rail::ros_glue::toMessage(c, m.wheel_id, m.side, p);
      }
    }
    for (std::size_t w = 0; w < sim.wheelsets().size(); ++w) {
      const WheelsetTrackOutput& o = sim.wheelsets()[w];
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
        const WheelOutput& wheel = sim.wheels()[i];
        if (wheel.wheelset != o.wheelset) continue;
        const Vector3 f_in_track = track_point_.R_track_to_world.transpose() * wheel.force_in_world;
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
  std::vector<int> body_marker;   // per body: its marker, or -1 (wheelsets: the axle)
  std::vector<int> wheel_marker;  // per wheel: its disc
  std::vector<int> arrow_marker;  // per wheel: the force arrow
  double force_scale = 1e-5;      // m per N: 100 kN draws 1 m
  double wheel_radius = 0.445;    // m

  std::vector<int> flat_marker;             // per wheel flat: the spot on its wheel's rim
  std::vector<contact::WheelDefect> flats;  // the flats, in flat_marker's order

  VehicleMarkers(const VehicleSimulator& sim, const std::vector<core::DefectOutline>& outlines,
                 const std::vector<contact::WheelDefect>& wheel_defects, double radius, double scale)
      : force_scale(scale), wheel_radius(radius) {
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
      const std::string name = OutputMessages::frameName(sim, static_cast<int>(b));
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
      wheel_marker.push_back(
          add("wheels", visualization_msgs::Marker::CYLINDER, 2 * radius, 2 * radius, 0.13, 0.25f, 0.25f, 0.25f));
    }
    for (std::size_t i = 0; i < sim.wheels().size(); ++i) {
      arrow_marker.push_back(
          add("contact_forces", visualization_msgs::Marker::ARROW, 0.05, 0.12, 0.15, 0.9f, 0.2f, 0.1f));
      array.markers.back().points.resize(2);
    }
    // Local defects where they are (static): rail defects along the rail heads, support zones as a band at
    // the sleepers, each labelled; wheel flats as a spot on their wheel's rim (turning with it).
    for (const core::DefectOutline& o : outlines) {
      const bool rail = o.kind == core::DefectOutline::Kind::kRailDefect;
      const Vector3 lift(0.0, 0.0, rail ? 0.02 : -0.25);
      const int line = rail ? add("rail_defects", visualization_msgs::Marker::LINE_STRIP, 0.12, 0, 0, 1.0f, 0.5f, 0.0f)
                            : add("support_zones", visualization_msgs::Marker::LINE_STRIP, 2.6, 0, 0, 0.2f, 0.7f, 0.3f);
      visualization_msgs::Marker& m = array.markers[static_cast<std::size_t>(line)];
      if (!rail) m.color.a = 0.4f;
      m.points.resize(o.points.size());
      for (std::size_t k = 0; k < o.points.size(); ++k) fill(m.points[k], o.points[k] + lift);
      const int text = add("defect_labels", visualization_msgs::Marker::TEXT_VIEW_FACING, 0, 0, 0.3, 1.0f, 1.0f, 1.0f);
      visualization_msgs::Marker& t = array.markers[static_cast<std::size_t>(text)];
      t.text = o.label;
      fill(t.pose.position, o.points[o.points.size() / 2] + Vector3(0.0, 0.0, rail ? 1.2 : 0.8));
    }
    for (const contact::WheelDefect& d : wheel_defects) {
      if (d.shape != contact::WheelDefectShape::kFlat || d.wheel >= sim.wheels().size()) continue;
      flats.push_back(d);
      flat_marker.push_back(
          add("wheel_defects", visualization_msgs::Marker::SPHERE, 0.09, 0.09, 0.09, 1.0f, 0.1f, 0.1f));
    }
  }

  // q * (rotation of +90 deg about x): a cylinder's axis (z) along the body's y (the axle).
  static void axleOrientation(const Vector4& q, geometry_msgs::Quaternion& out) {
    const double c = std::sqrt(0.5), w = q[0], x = q[1], y = q[2], z = q[3];
    out.w = c * (w - x), out.x = c * (x + w), out.y = c * (y + z), out.z = c * (z - y);
  }

  const visualization_msgs::MarkerArray& update(const VehicleSimulator& sim, const ros::Time& stamp) {
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
      const WheelOutput& w = sim.wheels()[i];
      visualization_msgs::Marker& disc = array.markers[static_cast<std::size_t>(wheel_marker[i])];
      fill(disc.pose.position, w.p_in_world);
      axleOrientation(w.orientation, disc.pose.orientation);
      visualization_msgs::Marker& arrow = array.markers[static_cast<std::size_t>(arrow_marker[i])];
      const Vector3 foot = w.p_in_world - Vector3(0.0, 0.0, wheel_radius);
      fill(arrow.points[0], foot - force_scale * w.force_in_world);
      fill(arrow.points[1], foot);
    }
    for (std::size_t k = 0; k < flats.size(); ++k) {
      // The flat's centre on the rim: angle from the wheelset's -z toward +x, turned with the wheelset.
      const WheelOutput& w = sim.wheels()[flats[k].wheel];
      const Eigen::Quaterniond q(w.orientation[0], w.orientation[1], w.orientation[2], w.orientation[3]);
      const Vector3 rim(wheel_radius * std::sin(flats[k].angle), 0.0, -wheel_radius * std::cos(flats[k].angle));
      fill(array.markers[static_cast<std::size_t>(flat_marker[k])].pose.position,
           w.p_in_world + q.normalized().toRotationMatrix() * rim);
    }
    return array;
  }
};

VehicleOutputs::VehicleOutputs(ros::NodeHandle& nh, ros::NodeHandle& pnh, core::OutputSettings settings,
                               const std::vector<core::DefectOutline>& defect_outlines, const VehicleSimulator& sim,
                               bool cosim, core::CostProfile& cost, core::CostClock& clock)
    : settings_(std::move(settings)),
      sim_(sim),
      cost_(cost),
      clock_(clock),
      out_(std::make_unique<OutputMessages>(sim, settings_.scene_hash)) {
  // In a co-simulation the contact is evaluated by the track node, which publishes the contact points.
  own_points_ = settings_.effects.contact_point_output && !cosim;
  own_floor_ = settings_.effects.floor_acceleration_output;  // at the data file's measurement points
  own_energy_ = settings_.effects.energy_output;
  pub_clock_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  pub_states_ = nh.advertise<rail_msgs::WheelStates>("wheel_states", 100);
  if (own_points_) pub_points_ = nh.advertise<rail_msgs::ContactPoints>("contact_points", 100);
  pub_wrenches_ = nh.advertise<rail_msgs::ContactWrenches>("contact_wrenches", 100);
  pub_kinematics_ = nh.advertise<rail_msgs::WheelsetKinematics>("wheelset_kinematics", 100);
  if (own_floor_) pub_floor_ = nh.advertise<rail_msgs::FloorAccelerations>("floor_accelerations", 100);
  if (own_energy_) pub_energy_ = nh.advertise<rail_msgs::Energy>("vehicle_energy", 100);
  // rviz markers (effects.rviz_markers): built only when on, published at ~marker_rate (default 25 Hz).
  if (settings_.effects.rviz_markers) {
    pub_markers_ = nh.advertise<visualization_msgs::MarkerArray>("/vehicle_markers", 2);
    const rail::ros_glue::MarkerParams m = rail::ros_glue::markerParams(pnh);
    markers_ = std::make_unique<VehicleMarkers>(sim, defect_outlines, settings_.wheel_defects, settings_.nominal_radius,
                                                m.force_scale);
    marker_period_ = m.period(settings_.output.rate);
  }
}

VehicleOutputs::~VehicleOutputs() = default;

bool VehicleOutputs::waitForSubscribers(const std::string& node, ros::NodeHandle& nh, ros::NodeHandle& pnh,
                                        const std::atomic<bool>& stop) {
  XmlRpc::XmlRpcValue value;
  if (!pnh.getParam("wait_for_subscribers", value)) return true;
  std::vector<std::string> names;
  if (value.getType() == XmlRpc::XmlRpcValue::TypeString) {
    // roscpp passes `_wait_for_subscribers:=[a, b]` from its command line as a string: split it.
    std::string text = static_cast<std::string>(value);
    std::replace_if(
        text.begin(), text.end(), [](char c) { return c == '[' || c == ']' || c == ','; }, ' ');
    std::istringstream words(text);
    for (std::string word; words >> word;) names.push_back(word);
  } else if (value.getType() == XmlRpc::XmlRpcValue::TypeArray) {
    for (int i = 0; i < value.size(); ++i) {
      if (value[i].getType() != XmlRpc::XmlRpcValue::TypeString) {
        ROS_FATAL("%s: ~wait_for_subscribers: entry %d is not a topic name", node.c_str(), i);
        return false;
      }
      names.push_back(static_cast<std::string>(value[i]));
    }
  } else {
    ROS_FATAL("%s: ~wait_for_subscribers must be a topic name or a list of them", node.c_str());
    return false;
  }
  const ros::Publisher* published[] = {&pub_clock_,      &pub_states_, &pub_points_, &pub_wrenches_,
                                       &pub_kinematics_, &pub_floor_,  &pub_energy_, &pub_markers_};
  std::vector<const ros::Publisher*> waited;
  std::string offered;
  for (const ros::Publisher* pub : published) {
    if (*pub) offered += (offered.empty() ? "" : ", ") + pub->getTopic();
  }
  for (const std::string& name : names) {
    std::string topic;
    try {
      topic = nh.resolveName(name);
    } catch (const ros::InvalidNameException& e) {
      ROS_FATAL("%s: ~wait_for_subscribers: %s", node.c_str(), e.what());
      return false;
    }
    const auto it = std::find_if(std::begin(published), std::end(published),
                                 [&](const ros::Publisher* pub) { return *pub && pub->getTopic() == topic; });
    if (it == std::end(published)) {
      ROS_FATAL(
          "%s: ~wait_for_subscribers names %s, which this node does not publish with this scene (it "
          "publishes %s)",
          node.c_str(), topic.c_str(), offered.c_str());
      return false;
    }
    waited.push_back(*it);
  }
  const double timeout = pnh.param("subscriber_timeout", 30.0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(std::max(timeout, 0.0));
  const auto missing = [&] {
    std::string list;
    for (const ros::Publisher* pub : waited) {
      if (pub->getNumSubscribers() == 0) list += (list.empty() ? "" : ", ") + pub->getTopic();
    }
    return list;
  };
  std::string still = missing();
  if (!still.empty()) ROS_INFO("%s: waiting for a subscriber on %s", node.c_str(), still.c_str());
  while (!still.empty() && !stop && ros::ok() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    still = missing();
  }
  if (!still.empty() && !stop && ros::ok()) {
    ROS_WARN("%s: no subscriber on %s after %g s (~subscriber_timeout); running without", node.c_str(), still.c_str(),
             timeout);
  }
  return true;
}

bool VehicleOutputs::openBag(const std::string& node, ros::NodeHandle& pnh) {
  if (settings_.output.bag.empty()) return true;
  if (!bag_.open(node, settings_.source, rail::ros_glue::bagPath(pnh, settings_.output.bag))) return false;
  std::string topics;
  for (const std::string& t : settings_.output.topics) topics += (topics.empty() ? "" : ", ") + t;
  ROS_INFO("%s: recording [%s] to %s", node.c_str(), topics.c_str(), bag_.path().c_str());
  rec_states_ = settings_.records("wheel_states");
  rec_points_ = settings_.records("contact_points") && own_points_;
  rec_wrenches_ = settings_.records("contact_wrenches");
  rec_kinematics_ = settings_.records("wheelset_kinematics");
  rec_floor_ = settings_.records("floor_accelerations") && own_floor_;
  rec_energy_ = settings_.records("vehicle_energy") && own_energy_;
  rec_tf_ = settings_.records("tf");
  rec_clock_ = settings_.records("clock");
  return true;
}

void VehicleOutputs::publish(std::uint64_t index) {
  core::CostProfile::Scope timing(cost_, core::CostProfile::kPublish);
  OutputMessages& out = *out_;
  const ros::Time stamp(std::max(sim_.time(), 1e-9));
  out.update(sim_, stamp, index);
  pub_clock_.publish(out.clock);
  pub_states_.publish(out.wheel_states);
  core::timedOutput(&clock_, core::CostClock::kContactPointOutput, own_points_,
                    [&] { pub_points_.publish(out.contact_points); });
  pub_wrenches_.publish(out.contact_wrenches);
  pub_kinematics_.publish(out.kinematics);
  if (own_floor_) pub_floor_.publish(out.floor);
  if (own_energy_) pub_energy_.publish(out.energy);
  tf_broadcaster_.sendTransform(out.tf.transforms);
  core::timedOutput(&clock_, core::CostClock::kMarkers, markers_ && sim_.time() + 1e-12 >= next_marker_, [&] {
    next_marker_ += marker_period_;
    pub_markers_.publish(markers_->update(sim_, stamp));
  });
  if (!bag_.isOpen()) return;
  core::CostProfile::Scope bag_timing(cost_, core::CostProfile::kBagWrite);
  if (rec_states_) bag_.write("/wheel_states", stamp, out.wheel_states);
  if (rec_points_) bag_.write("/contact_points", stamp, out.contact_points);
  if (rec_wrenches_) bag_.write("/contact_wrenches", stamp, out.contact_wrenches);
  if (rec_kinematics_) bag_.write("/wheelset_kinematics", stamp, out.kinematics);
  if (rec_floor_) bag_.write("/floor_accelerations", stamp, out.floor);
  if (rec_energy_) bag_.write("/vehicle_energy", stamp, out.energy);
  if (rec_tf_) bag_.write("/tf", stamp, out.tf);
  if (rec_clock_) bag_.write("/clock", stamp, out.clock);
}

void VehicleOutputs::close(const std::string& node, const CosimVehicle* cosim, double wall, int exit_code) {
  const IntegratorCounters c = sim_.counters();
  // The exchange waits were timed inside the steps too: the integration is what remains.
  if (cosim != nullptr)
    cost_.add(core::CostProfile::kVehicleIntegration, -cost_.seconds(core::CostProfile::kTransportWait));
  // Bag writes happen inside the publishing scope: publishing is what remains.
  cost_.add(core::CostProfile::kPublish, -cost_.seconds(core::CostProfile::kBagWrite));
  cost_.setCount("cvode_steps", static_cast<double>(c.steps));
  cost_.setCount("rhs_evaluations", static_cast<double>(c.rhs_evals));
  cost_.setCount("rhs_for_jacobians", static_cast<double>(c.rhs_evals_jacobian));
  cost_.setCount("jacobians", static_cast<double>(c.jacobian_evals));
  cost_.setCount("jacobians_carried", static_cast<double>(c.jacobian_carries));
  cost_.setCount("projections", static_cast<double>(c.projections));
  if (cosim != nullptr) cost_.setCount("exchanges", static_cast<double>(cosim->stepsExchanged()));
  ROS_INFO_STREAM(cost_.toText(node, wall, sim_.time(), &clock_));
  bag_.writeBeside(node, ".cost.yaml",
                   cost_.toYaml(node, settings_.source, settings_.effects, wall, sim_.time(), &clock_));
  ROS_INFO(
      "%s: %s at t = %.4f s, leading wheelset at s = %.3f m; %.2f s wall (%.2f s per simulated s); CVODE "
      "%ld steps, %ld RHS + %ld for %ld Jacobians (%ld carried with the wheelsets' spin), %ld projections, %ld "
      "Adams fallbacks",
      node.c_str(), exit_code == core::kExitOk ? "finished" : "stopped", sim_.time(), sim_.leadingArcLength(), wall,
      wall / std::max(sim_.time(), 1e-9), c.steps, c.rhs_evals, c.rhs_evals_jacobian, c.jacobian_evals,
      c.jacobian_carries, c.projections, c.adams_fallbacks);
  // How the contact was found (the vehicle's own contact on the rigid track), never hiding approximations.
  if (cosim == nullptr) {
    contact::DetectionCounts detection;
    for (const contact::WheelContactWork& w : sim_.contactData().work)
      for (const contact::DetectionWork& d : w.detection) detection.add(d);
    rail::ros_glue::logDetection(node, detection);
  }
  bag_.close(node);
}

}  // namespace rail::vehicle
