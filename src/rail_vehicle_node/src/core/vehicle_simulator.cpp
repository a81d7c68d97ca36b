#include "rail_vehicle_node/vehicle_simulator.hpp"

#include <rail_core/geometry_builder.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "rail_vehicle_node/multibody_dynamics.hpp"
#include "rail_vehicle_node/vehicle_loader.hpp"

namespace rail::vehicle {

namespace rc = rail::contact;

namespace {

// Axial vector of a (numerically) skew-symmetric matrix W: W x = w x x.
Vector3 axial(const Matrix3& W) { return 0.5 * Vector3(W(2, 1) - W(1, 2), W(0, 2) - W(2, 0), W(1, 0) - W(0, 1)); }

const char* sideName(rc::RailSide side) { return side == rc::RailSide::kLeft ? "left" : "right"; }

// The wheel-centre wrenches of a WheelWrenchSource at the right-hand side's time (data.time), applied at
// each wheel's centre as the co-simulation frames define it (the axle point in the taping-line plane, the
// point the moment is taken about) while *active is true.
class ExternalWheelWrenchElement : public ForceElement {
 public:
  ExternalWheelWrenchElement(const WheelRailContactModel* model, const WheelWrenchSource* source, const bool* active)
      : ForceElement("external_wheel_wrenches", model->wheels().front().body, kGround),
        model_(model),
        source_(source),
        active_(active) {}
  void addForces(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> g) const override {
    if (!*active_) return;
    Vector3 f, n;
    for (int k = 0; k < model_->nWheels(); ++k) {
      const WheelDefinition& w = model_->wheels()[static_cast<std::size_t>(k)];
      const BodyKinematics& b = data.bodies[static_cast<std::size_t>(w.body)];
      source_->wheelWrenchAt(data.time, k, f, n);
      applyForceAt(data, w.body, f, b.r + b.A * w.s_taping_in_body, g);
      applyMoment(data, w.body, n, g);
    }
  }
  double potentialEnergy(const VehicleData& /*data*/) const override { return 0.0; }

 private:
  const WheelRailContactModel* model_;
  const WheelWrenchSource* source_;
  const bool* active_;
};

}  // namespace

contact::WheelContactOptions defaultVehicleContactOptions() {
  // rail_contact's defaults include the 5 mm split overlap (the track node uses the same).
  return contact::WheelContactOptions{};
}

IntegrationMethod chooseMethod(const core::Solver& solver, double speed, bool external_wrenches) {
  switch (solver.vehicle_method) {
    case core::VehicleMethod::kBdf:
      return IntegrationMethod::kBdf;
    case core::VehicleMethod::kAdams:
      return IntegrationMethod::kAdams;
    case core::VehicleMethod::kAuto:
      break;
  }
  if (external_wrenches) return IntegrationMethod::kAdams;  // suspension only: not stiff (see the header)
  if (std::abs(speed) < kStiffCreepSpeed) return IntegrationMethod::kBdf;
  return (solver.vehicle_max_step > 0.0 && solver.vehicle_max_step <= 5e-5) ? IntegrationMethod::kAdams
                                                                            : IntegrationMethod::kBdf;
}

double projectOnTrack(const rc::TrackGeometry& track, const Vector3& p_in_world, double s_guess,
                      rc::TrackPoint& tp) noexcept {
  const double lo = track.sStart(), hi = track.sEnd();
  double s = std::isfinite(s_guess) ? std::clamp(s_guess, lo, hi) : lo;
  for (int it = 0; it < 8; ++it) {
    track.centre(s, tp);
    // f(s) = (p - c(s)) . c'(s) = 0; f'(s) ~ -|c'|^2 (the curvature term, offset x curvature, is left out:
    // the iteration then converges linearly at a rate of about offset / radius).
    const double f = (p_in_world - tp.p_center_in_world).dot(tp.dp_ds);
    const double ds = f / tp.dp_ds.squaredNorm();
    const double s_new = std::clamp(s + ds, lo, hi);
    const bool done = std::abs(s_new - s) < 1e-10;
    s = s_new;
    if (done) break;
  }
  track.centre(s, tp);
  return s;
}

Eigen::VectorXd placeOnTrack(const VehicleModel& model, const rc::TrackGeometry& track,
                             const std::vector<int>& wheelset_bodies, double start_arc_length, double speed,
                             double lift, const std::vector<double>& rolling_radius) {
  const int n = model.nBodies();
  const auto& bodies = model.bodies();
  const double x_lead = bodies[static_cast<std::size_t>(wheelset_bodies.front())].r_reference.x();
  auto station = [&](double x) { return start_arc_length - (x_lead - x); };
  std::vector<double> s_of(static_cast<std::size_t>(n));
  for (int b = 0; b < n; ++b) {
    const double s = station(bodies[static_cast<std::size_t>(b)].r_reference.x());
    if (s < track.sStart() || s > track.sEnd()) {
      std::ostringstream os;
      os << "vehicle.start_arc_length: body " << bodies[static_cast<std::size_t>(b)].name << " would be at s = " << s
         << " m, outside the track [" << track.sStart() << ", " << track.sEnd() << "] m";
      throw std::runtime_error(os.str());
    }
    s_of[static_cast<std::size_t>(b)] = s;
  }

  // Topology: bodies linked by a joint or a force element; level = graph distance from the wheelsets.
  std::vector<std::vector<int>> neighbours(static_cast<std::size_t>(n));
  auto link = [&](int i, int j) {
    if (i < 0 || j < 0 || i == j) return;
    neighbours[static_cast<std::size_t>(i)].push_back(j);
    neighbours[static_cast<std::size_t>(j)].push_back(i);
  };
  for (const auto& j : model.joints()) link(j->bodyI(), j->bodyJ());
  for (const auto& f : model.forceElements()) link(f->bodyI(), f->bodyJ());
  std::vector<int> level(static_cast<std::size_t>(n), -1);
  std::vector<int> queue;
  for (int w : wheelset_bodies) level[static_cast<std::size_t>(w)] = 0, queue.push_back(w);
  for (std::size_t q = 0; q < queue.size(); ++q) {
    for (int m : neighbours[static_cast<std::size_t>(queue[q])]) {
      if (level[static_cast<std::size_t>(m)] < 0) {
        level[static_cast<std::size_t>(m)] = level[static_cast<std::size_t>(queue[q])] + 1;
        queue.push_back(m);
      }
    }
  }

  // Frame of each body: origin on the centre line at the body's station and rotation (x along the track).
  std::vector<Vector3> origin(static_cast<std::size_t>(n));
  std::vector<Matrix3> frame(static_cast<std::size_t>(n));
  std::vector<int> kind(static_cast<std::size_t>(n), 0);  // 0 own station, 1 chord, 2 from its support
  rc::TrackPoint tp, tf, tr;
  for (int b = 0; b < n; ++b) {
    track.centre(s_of[static_cast<std::size_t>(b)], tp);
    origin[static_cast<std::size_t>(b)] = tp.p_center_in_world;
    frame[static_cast<std::size_t>(b)] = tp.R_track_to_world;
  }
  // A suspended body resting on supports at different stations (a bogie frame on its axleboxes, a carbody
  // on its bogies) lies on the chord between the foremost and rearmost supports, as a rigid body in a curve
  // does; a body whose supports share its station (an axlebox) takes its support's frame.
  std::vector<int> support_of(static_cast<std::size_t>(n), -1);
  for (int b : queue) {
    const int lb = level[static_cast<std::size_t>(b)];
    if (lb <= 0) continue;
    double x_f = -1e300, x_r = 1e300;
    for (int m : neighbours[static_cast<std::size_t>(b)]) {
      if (level[static_cast<std::size_t>(m)] != lb - 1) continue;
      const double x = bodies[static_cast<std::size_t>(m)].r_reference.x();
      x_f = std::max(x_f, x), x_r = std::min(x_r, x);
      if (support_of[static_cast<std::size_t>(b)] < 0) support_of[static_cast<std::size_t>(b)] = m;
    }
    if (x_f - x_r < 0.1) {
      kind[static_cast<std::size_t>(b)] = 2;
      continue;
    }
    const double s_f = station(x_f), s_r = station(x_r);
    if (s_f > track.sEnd() || s_r < track.sStart()) continue;
    track.centre(s_f, tf);
    track.centre(s_r, tr);
    const Vector3 u = (tf.p_center_in_world - tr.p_center_in_world).normalized();
    Vector3 up = tf.R_track_to_world.col(2) + tr.R_track_to_world.col(2);
    up = (up - up.dot(u) * u).normalized();
    Matrix3 R;
    R.col(0) = u, R.col(1) = up.cross(u), R.col(2) = up;
    frame[static_cast<std::size_t>(b)] = R;
    origin[static_cast<std::size_t>(b)] =
        tr.p_center_in_world + (bodies[static_cast<std::size_t>(b)].r_reference.x() - x_r) / (x_f - x_r) *
                                   (tf.p_center_in_world - tr.p_center_in_world);
    kind[static_cast<std::size_t>(b)] = 1;
  }
  // A wheelset keeps its own station, cant and elevation but is yawed parallel to the chord of the frame it
  // is suspended from (the stiff primary suspension holds it so): its angle of attack in a curve.
  for (int w : wheelset_bodies) {
    int chord_body = -1;
    for (int m : neighbours[static_cast<std::size_t>(w)]) {
      for (int k : neighbours[static_cast<std::size_t>(m)]) {
        if (chord_body < 0 && kind[static_cast<std::size_t>(k)] == 1) chord_body = k;
      }
      if (chord_body < 0 && kind[static_cast<std::size_t>(m)] == 1) chord_body = m;
    }
    if (chord_body < 0) continue;
    const Matrix3& Rw = frame[static_cast<std::size_t>(w)];
    const Vector3 u = frame[static_cast<std::size_t>(chord_body)].col(0);
    const double yaw = std::atan2(u.dot(Rw.col(1)), u.dot(Rw.col(0)));
    frame[static_cast<std::size_t>(w)] = Rw * Eigen::AngleAxisd(yaw, Vector3::UnitZ()).toRotationMatrix();
  }
  for (int b : queue) {
    if (kind[static_cast<std::size_t>(b)] != 2) continue;
    const int m = support_of[static_cast<std::size_t>(b)];
    frame[static_cast<std::size_t>(b)] = frame[static_cast<std::size_t>(m)];
    origin[static_cast<std::size_t>(b)] =
        origin[static_cast<std::size_t>(m)] +
        (bodies[static_cast<std::size_t>(b)].r_reference.x() - bodies[static_cast<std::size_t>(m)].r_reference.x()) *
            frame[static_cast<std::size_t>(m)].col(0);
  }

  Eigen::VectorXd y = model.referenceState();
  for (int b = 0; b < n; ++b) {
    const RigidBody& body = bodies[static_cast<std::size_t>(b)];
    const Matrix3& R = frame[static_cast<std::size_t>(b)];
    const Vector3 p =
        origin[static_cast<std::size_t>(b)] + R * Vector3(0.0, body.r_reference.y(), body.r_reference.z() + lift);
    const Matrix3 A = R * rotationFromEulerParameters(body.p_reference);
    // Velocity field of the track frame moving at `speed` along the track, taken at the body's station.
    track.centre(s_of[static_cast<std::size_t>(b)], tp);
    const Vector3 omega_track = speed * axial(tp.dR_ds * tp.R_track_to_world.transpose());
    Vector3 omega = omega_track;
    for (std::size_t w = 0; w < wheelset_bodies.size(); ++w) {
      if (wheelset_bodies[w] == b) omega += speed / rolling_radius[w] * A.col(1);
    }
    y.segment<3>(VehicleModel::positionOffset(b)) = p;
    y.segment<4>(VehicleModel::eulerOffset(b)) = eulerParametersFromRotation(A);
    y.segment<3>(model.velocityOffset(b)) = speed * tp.dp_ds.normalized() + omega_track.cross(p - tp.p_center_in_world);
    y.segment<3>(model.angularVelocityOffset(b)) = A.transpose() * omega;
  }
  return y;
}

VehicleSetup resolveVehicle(const core::Scene& scene) {
  if (!scene.has_vehicle) throw std::runtime_error(scene.file + ": the scene has no vehicle");
  VehicleSetup v;
  v.source = scene.file;
  v.data_file = scene.vehicle.data.path;
  v.wheelsets = scene.vehicle.wheelsets;
  v.start_arc_length = scene.vehicle.start_arc_length;
  v.speed = scene.vehicle.speed;
  v.nominal_radius = scene.vehicle.nominal_radius;
  v.back_to_back = scene.vehicle.back_to_back;
  v.end = scene.solver.end;
  v.solver = scene.solver;
  v.track = core::buildTrackGeometry(scene);
  v.wheel_profile = core::wheelProfile(scene);
  v.rail_profile = core::railProfileCurve(scene);
  v.contact = core::sceneContact(scene);
  v.floor_acceleration_output = scene.effects.floor_acceleration_output;
  v.energy_output = scene.effects.energy_output;
  return v;
}

VehicleSimulator::VehicleSimulator(VehicleSetup setup, const SimulatorSettings& settings) {
  build(std::move(setup), nullptr, settings);
}

VehicleSimulator::VehicleSimulator(VehicleSetup setup, const std::function<void(VehicleModel&)>& build_model,
                                   const SimulatorSettings& settings) {
  build(std::move(setup), build_model, settings);
}

VehicleSimulator::~VehicleSimulator() = default;

void VehicleSimulator::build(VehicleSetup setup, const std::function<void(VehicleModel&)>& build_model,
                             const SimulatorSettings& settings) {
  if (!setup.track) throw std::invalid_argument(setup.source + ": the vehicle setup has no track geometry");
  end_ = setup.end;
  start_arc_length_ = setup.start_arc_length;
  speed_ = setup.speed;
  settings_ = settings;
  const std::string& data_file = setup.data_file;

  // Track, profiles.
  track_ = std::make_unique<rc::TrackGeometry>(std::move(*setup.track));
  wheel_profile_ = std::move(setup.wheel_profile);
  rail_profile_ = std::move(setup.rail_profile);

  // Vehicle.
  if (build_model) {
    build_model(model_);
  } else {
    loadVehicleInto(data_file, model_);
  }
  const std::string source = build_model ? std::string("vehicle model") : data_file;

  // Wheels: every load point is a wheel centre; a wheelset body carries two (y > 0 left, y < 0 right).
  std::map<int, std::vector<int>> points_of_body;
  for (std::size_t k = 0; k < model_.loadPoints().size(); ++k) {
    points_of_body[model_.loadPoints()[k].body].push_back(static_cast<int>(k));
  }
  for (const auto& [body, points] : points_of_body) {
    const std::string& name = model_.bodies()[static_cast<std::size_t>(body)].name;
    if (points.size() != 2) {
      throw std::runtime_error(source + ": load_points: body " + name + " carries " + std::to_string(points.size()) +
                               " wheel centres, a wheelset needs 2");
    }
    const double y0 = model_.loadPoints()[static_cast<std::size_t>(points[0])].s_in_body.y();
    const double y1 = model_.loadPoints()[static_cast<std::size_t>(points[1])].s_in_body.y();
    if (!(y0 * y1 < 0.0)) {
      throw std::runtime_error(source + ": load_points: the wheel centres of " + name +
                               " must lie on either side of its centre (y > 0 left, y < 0 right)");
    }
    wheelset_bodies_.push_back(body);
  }
  std::sort(wheelset_bodies_.begin(), wheelset_bodies_.end(), [this](int a, int b) {
    return model_.bodies()[static_cast<std::size_t>(a)].r_reference.x() >
           model_.bodies()[static_cast<std::size_t>(b)].r_reference.x();
  });
  if (static_cast<int>(wheelset_bodies_.size()) != setup.wheelsets) {
    throw std::runtime_error(source + ": " + std::to_string(wheelset_bodies_.size()) +
                             " wheelsets (bodies with two wheel centres), the scene says vehicle.wheelsets: " +
                             std::to_string(setup.wheelsets));
  }
  const double taping_y = 0.5 * setup.back_to_back + rc::kTapingLineFromFlangeBack;
  std::vector<WheelDefinition> wheels;
  for (std::size_t w = 0; w < wheelset_bodies_.size(); ++w) {
    const int body = wheelset_bodies_[w];
    const auto& points = points_of_body[body];
    for (int side = 0; side < 2; ++side) {
      WheelDefinition d;
      d.wheelset = static_cast<int>(w);
      d.side = side == 0 ? rc::RailSide::kLeft : rc::RailSide::kRight;
      d.body = body;
      for (int p : points) {
        const double y = model_.loadPoints()[static_cast<std::size_t>(p)].s_in_body.y();
        if ((side == 0) == (y > 0.0)) d.load_point = p;
      }
      d.s_load_point_in_body = model_.loadPoints()[static_cast<std::size_t>(d.load_point)].s_in_body;
      d.s_taping_in_body =
          Vector3(d.s_load_point_in_body.x(), side == 0 ? taping_y : -taping_y, d.s_load_point_in_body.z());
      wheels.push_back(d);
    }
  }

  // Contact: the scene's effects and contact section over the caller's numerical settings.
  const rc::WheelContactOptions options = setup.contact.over(settings.contact);
  nominal_height_ = setup.nominal_radius;
  contact_model_ =
      std::make_unique<WheelRailContactModel>(*track_, wheel_profile_, setup.nominal_radius, rail_profile_,
                                              rc::railSectionCentre(rail_profile_), options, std::move(wheels));
  contact_data_ = std::make_unique<WheelRailContactData>(*contact_model_);
  skip_far_searches_ = settings.skip_far_searches;
  contact_data_->setExactGaps(!skip_far_searches_);
  model_.addForceElement(std::make_unique<WheelRailContactElement>(contact_model_.get(), contact_data_.get()));
  if (settings.wheel_wrench_source != nullptr) {
    model_.addForceElement(std::make_unique<ExternalWheelWrenchElement>(
        contact_model_.get(), settings.wheel_wrench_source, &external_active_));
  }
  model_.finalize();
  data_ = std::make_unique<VehicleData>(model_);
  derailment_lift_ = settings.derailment_lift > 0.0 ? settings.derailment_lift : rc::flangeHeight(wheel_profile_);

  // Load the rails carry at rest: minus the vertical sum of the applied forces without contact.
  const int n_ws = static_cast<int>(wheelset_bodies_.size());
  rolling_radius_.assign(static_cast<std::size_t>(n_ws), setup.nominal_radius);
  const double s0 = setup.start_arc_length;
  const double speed = setup.speed;
  Eigen::VectorXd y = placeOnTrack(model_, *track_, wheelset_bodies_, s0, speed, 0.0, rolling_radius_);
  contact_data_->enabled = false;
  computeKinematics(model_, y, *data_);
  computeAppliedForces(model_, *data_);
  contact_data_->enabled = true;
  double fz = 0.0;
  for (int b = 0; b < model_.nBodies(); ++b) fz += data_->generalized_forces[6 * b + 2];
  static_load_ = -fz;
  const double x_lead = model_.bodies()[static_cast<std::size_t>(wheelset_bodies_.front())].r_reference.x();
  for (int k = 0; k < contact_model_->nWheels(); ++k) {
    const auto& w = contact_model_->wheels()[static_cast<std::size_t>(k)];
    contact_data_->s_hint[static_cast<std::size_t>(k)] =
        s0 - (x_lead - model_.bodies()[static_cast<std::size_t>(w.body)].r_reference.x());
  }

  // Static vertical solve: lower the whole vehicle along the track normal until the wheel loads sum to the
  // static load. A uniform lowering leaves every suspension force unchanged, so when the data file's
  // preloads balance its reference pose (paper_coach.yaml does) each wheel then carries its static share.
  auto residual = [&](double lift) {
    y = placeOnTrack(model_, *track_, wheelset_bodies_, s0, speed, lift, rolling_radius_);
    return sumWheelLoads(y) - static_load_;
  };
  double hi = 0.0, f_hi = residual(hi);
  double lo = -0.5e-3, f_lo = residual(lo);
  for (int i = 0; i < 6 && f_lo < 0.0; ++i) {
    hi = lo, f_hi = f_lo;
    lo *= 2.0, f_lo = residual(lo);
  }
  for (int i = 0; i < 12 && f_hi > 0.0; ++i) {
    lo = hi, f_lo = f_hi;
    hi += 1e-3 * (i + 1), f_hi = residual(hi);
  }
  if (!(f_lo >= 0.0 && f_hi <= 0.0)) {
    std::ostringstream os;
    os << setup.source << ": the vehicle cannot be settled on the rails at vehicle.start_arc_length = " << s0
       << " m (wheel loads " << f_lo + static_load_ << " N at " << lo * 1e3 << " mm, " << f_hi + static_load_
       << " N at " << hi * 1e3 << " mm, static load " << static_load_ << " N)";
    throw std::runtime_error(os.str());
  }
  // Illinois (regula falsi with halving) on the monotone residual.
  int side = 0;
  double lift = hi;
  for (int it = 0; it < 100; ++it) {
    lift = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
    const double f = residual(lift);
    if (std::abs(f) < 1e-9 * static_load_ || hi - lo < 1e-13) break;
    if (f > 0.0) {
      lo = lift, f_lo = f;
      if (side == -1) f_hi *= 0.5;
      side = -1;
    } else {
      hi = lift, f_hi = f;
      if (side == 1) f_lo *= 0.5;
      side = 1;
    }
  }
  lift_ = lift;
  // Spin each wheelset at speed / its rolling radius at the settled, centred position (pure rolling).
  residual(lift_);
  for (int w = 0; w < n_ws; ++w) {
    double r_sum = 0.0;
    int n = 0;
    for (int side_k = 0; side_k < 2; ++side_k) {
      const auto& c = contact_data_->result[static_cast<std::size_t>(2 * w + side_k)].contact[rc::kTread];
      if (c.active && c.rolling_radius > 0.0) r_sum += c.rolling_radius, ++n;
    }
    if (n > 0) rolling_radius_[static_cast<std::size_t>(w)] = r_sum / n;
  }
  settled_load_sum_ = residual(lift_) + static_load_;

  // Integrator.
  IntegratorSettings is;
  is.rtol = setup.solver.vehicle_rtol;
  is.atol = setup.solver.vehicle_atol;
  // The track step caps the vehicle step in co-simulation only; alone, the physics (error control) decides.
  const bool cosimulation = settings.wheel_wrench_source != nullptr;
  max_step_ = cosimulation ? setup.solver.vehicle_max_step : setup.solver.standalone_max_step;
  is.max_step = max_step_;
  is.jacobian = settings.jacobian;
  // Where BDF gives up (some flange onsets below rtol 1e-6), Adams at the scene's step cap finishes the
  // output interval: the former setting of the vehicle alone.
  is.fallback_max_step = setup.solver.vehicle_max_step;
  // Rotations use p / |p| and p_dot = 1/2 p (x) (0, omega') is the same rotation rate at any |p|, so the norm's
  // drift has no physical effect; BDF's damping of the spinning wheelsets' p shrinks it by ~6e-6 per ms, and a
  // 1e-6 threshold re-initialised CVODE (a new Jacobian, order 1) every output interval.
  is.projection_euler_threshold = 1e-3;
  is.linear_solver = settings.linear_solver;
  is.direct_linear_system = settings.direct_linear_system;
  if (settings.carry_jacobian_with_spin) {
    // Only a wheelset whose inertia is symmetric about its axle (body y) keeps its dynamics when it turns.
    for (int body : wheelset_bodies_) {
      const Matrix3& inertia = model_.bodies()[static_cast<std::size_t>(body)].inertia_in_body;
      const double scale = inertia.cwiseAbs().maxCoeff();
      const bool symmetric =
          std::abs(inertia(0, 0) - inertia(2, 2)) <= 1e-12 * scale &&
          std::abs(inertia(0, 1)) + std::abs(inertia(1, 2)) + std::abs(inertia(0, 2)) <= 1e-12 * scale;
      if (symmetric) is.spin_bodies.push_back(body);
    }
  }
  core::Solver solver = setup.solver;
  solver.vehicle_max_step = max_step_;
  method_ = chooseMethod(solver, setup.speed, cosimulation);
  is.method = method_;
  is.max_order = method_ == IntegrationMethod::kBdf ? 5 : 12;
  is.accept_steps =
      (settings.impact_memory_at_accepted_steps || settings.warm_starts_at_accepted_steps) && !cosimulation;
  for (auto& work : contact_data_->work) {
    for (auto& impact : work.impact) impact = rc::ImpactMemory();
    work.hold_impact_memory = settings.impact_memory_at_accepted_steps && is.accept_steps;
    for (auto& d : work.detection) d.hold_warm_start = settings.warm_starts_at_accepted_steps && is.accept_steps;
  }
  if (settings.wheel_wrench_source != nullptr) {
    // Settled on the rigid contact; from here on the wheel wrenches come from the source.
    contact_data_->enabled = false;
    external_active_ = true;
  }
  is.cost = settings.cost;  // no right-hand side is evaluated before the first advanceTo
  integrator_ = std::make_unique<VehicleIntegrator>(model_, *data_, y, 0.0, is);

  // Output buffers.
  y_scratch_ = Eigen::VectorXd::Zero(model_.stateSize());
  ydot_scratch_ = Eigen::VectorXd::Zero(model_.stateSize());
  wheel_out_.assign(static_cast<std::size_t>(contact_model_->nWheels()), WheelOutput());
  wheel_s_.assign(wheel_out_.size(), 0.0);
  for (std::size_t k = 0; k < wheel_out_.size(); ++k) wheel_s_[k] = contact_data_->s_hint[k];
  wheelset_out_.assign(static_cast<std::size_t>(n_ws), WheelsetTrackOutput());
  wheelset_s_.assign(static_cast<std::size_t>(n_ws), 0.0);
  for (int w = 0; w < n_ws; ++w) {
    wheelset_s_[static_cast<std::size_t>(w)] =
        s0 - (x_lead -
              model_.bodies()[static_cast<std::size_t>(wheelset_bodies_[static_cast<std::size_t>(w)])].r_reference.x());
  }
  body_out_.assign(static_cast<std::size_t>(model_.nBodies()), BodyPose());
  measurement_out_.assign(model_.measurementPoints().size(), MeasurementOutput());
  measure_ = setup.floor_acceleration_output;
  energy_ = setup.energy_output;
  if (measure_ && measurement_out_.empty()) {
    throw std::runtime_error(setup.source + ": effects.floor_acceleration_output is on but the vehicle data file " +
                             setup.data_file + " has no measurement_points");
  }
  for (int b = 0; b < model_.nBodies(); ++b) {
    body_out_[static_cast<std::size_t>(b)].name = model_.bodies()[static_cast<std::size_t>(b)].name;
  }
  updateOutputs();
  // Timing from here on (the build's evaluations are set-up).
  cost_ = settings.cost;
  contact_data_->cost = cost_ != nullptr ? &cost_->contact : nullptr;
}

double VehicleSimulator::sumWheelLoads(const Eigen::VectorXd& y) {
  computeKinematics(model_, y, *data_);
  double sum = 0.0;
  for (int k = 0; k < contact_model_->nWheels(); ++k) {
    evaluateWheel(*contact_model_, *data_, k, *contact_data_);
    for (const auto& c : contact_data_->result[static_cast<std::size_t>(k)].contact) {
      if (c.active) sum += c.N * c.normal_in_world.z();
    }
  }
  return sum;
}

double VehicleSimulator::time() const { return integrator_->time(); }

double VehicleSimulator::endTimeEstimate() const {
  if (end_.kind == core::EndKind::kTime) return end_.value;
  return speed_ > 0.0 ? (end_.value - start_arc_length_) / speed_ : 0.0;
}

bool VehicleSimulator::finished() const {
  if (end_.kind == core::EndKind::kTime) return time() >= end_.value - 1e-12;
  return leading_s_ >= end_.value;
}

void VehicleSimulator::resetState(const Eigen::VectorXd& y) {
  integrator_->reset(y, integrator_->time());
  updateOutputs();
}

void VehicleSimulator::updateOutputs() { evaluateOutputs(true); }

// The outputs at the current state. Without the derivatives (the co-simulation's check at every exchange):
// the kinematics and the positions the checks read; the rest waits for completeOutputs (one output instant
// in many exchanges).
void VehicleSimulator::evaluateOutputs(bool derivatives) {
  y_scratch_ = integrator_->state();
  t_outputs_ = integrator_->time();
  derivatives_current_ = false;
  if (derivatives) {
    completeOutputs();  // kinematics and contact, then the outputs they give
  } else {
    computeKinematics(model_, y_scratch_, *data_);
  }
  fillPositionOutputs();
}

void VehicleSimulator::fillPositionOutputs() {
  rc::TrackPoint tp;
  for (std::size_t w = 0; w < wheelset_out_.size(); ++w) {
    const int body = wheelset_bodies_[w];
    const BodyKinematics& k = data_->bodies[static_cast<std::size_t>(body)];
    const double s = projectOnTrack(*track_, k.r, wheelset_s_[w], tp);
    wheelset_s_[w] = s;
    const Matrix3& R = tp.R_track_to_world;
    const Vector3 d = R.transpose() * (k.r - tp.p_center_in_world);
    const Vector3 axle = R.transpose() * k.A.col(1);
    WheelsetTrackOutput& o = wheelset_out_[w];
    o.wheelset = static_cast<int>(w);
    o.arc_length = s;
    o.lateral = d.y();
    o.vertical = d.z() - nominal_height_;
    o.angle_of_attack = std::atan2(-axle.x(), axle.y());
    o.roll = std::atan2(axle.z(), axle.y());
    o.spin = k.omega_body.y();
  }
  leading_s_ = wheelset_s_.front();
  for (std::size_t i = 0; i < wheel_out_.size(); ++i) {
    const WheelDefinition& wd = contact_model_->wheels()[i];
    const BodyKinematics& k = data_->bodies[static_cast<std::size_t>(wd.body)];
    WheelOutput& o = wheel_out_[i];
    o.wheel_id = static_cast<int>(i);
    o.wheelset = wd.wheelset;
    o.side = wd.side == rc::RailSide::kLeft ? 0 : 1;
    const Vector3 arm = k.A * wd.s_load_point_in_body;
    o.p_in_world = k.r + arm;
    o.v_in_world = k.r_dot + k.omega_world.cross(arm);
    o.omega_in_world = k.omega_world;
    o.orientation = eulerParametersFromRotation(k.A);
    wheel_s_[i] = projectOnTrack(*track_, o.p_in_world, wheel_s_[i], tp);
    o.arc_length = wheel_s_[i];
    if (external_active_) {
      settings_.wheel_wrench_source->wheelWrenchAt(integrator_->time(), static_cast<int>(i), o.force_in_world,
                                                   o.moment_in_world);
    } else {
      o.force_in_world = contact_data_->force_in_world[i];
      o.moment_in_world = contact_data_->moment_in_world[i];
    }
  }
  for (std::size_t b = 0; b < body_out_.size(); ++b) {
    const BodyKinematics& k = data_->bodies[b];
    body_out_[b].p_in_world = k.r;
    body_out_[b].orientation = eulerParametersFromRotation(k.A);
  }
}

void VehicleSimulator::completeOutputs() const {
  if (derivatives_current_) return;
  derivatives_current_ = true;
  {
    core::CostClock::Scope timing(cost_, core::CostClock::kVehicleRhs);
    contact_data_->setExactGaps(true);  // the published gaps are the searched ones
    computeDerivatives(model_, t_outputs_, y_scratch_, ydot_scratch_, *data_);
    contact_data_->setExactGaps(!skip_far_searches_);
  }
  if (energy_) {
    core::CostClock::Scope timing(cost_, core::CostClock::kEnergyOutput);
    // From the bodies' kinematics evaluated above (multibody_dynamics.hpp).
    energy_out_.kinetic = kineticEnergy(model_, *data_);
    energy_out_.potential = potentialEnergy(model_, *data_);
  }
  if (!measure_) return;
  core::CostClock::Scope floor_timing(cost_, core::CostClock::kFloorAccelerations);
  // Accelerations from the derivatives evaluated above: v_dot_b = [r_ddot (world); omega_dot' (body)].
  // A point s' of the body: a_P = r_ddot + A (omega_dot' x s' + omega' x (omega' x s')); the accelerometer
  // reads A^T (a_P - g).
  for (std::size_t m = 0; m < measurement_out_.size(); ++m) {
    const MeasurementPoint& p = model_.measurementPoints()[m];
    const BodyKinematics& k = data_->bodies[static_cast<std::size_t>(p.body)];
    const Vector3 r_ddot = ydot_scratch_.segment<3>(model_.velocityOffset(p.body));
    const Vector3 omega_dot_body = ydot_scratch_.segment<3>(model_.angularVelocityOffset(p.body));
    const Vector3& w = k.omega_body;
    const Vector3 a_rel_body = omega_dot_body.cross(p.s_in_body) + w.cross(w.cross(p.s_in_body));
    measurement_out_[m].specific_force_in_body = k.A.transpose() * (r_ddot - model_.gravity()) + a_rel_body;
  }
}

RunStatus VehicleSimulator::advanceTo(double t) {
  try {
    integrator_->advanceTo(t);
  } catch (const std::exception& e) {
    const bool finite = integrator_->state().allFinite();
    updateOutputs();
    std::ostringstream os;
    os << "the vehicle integration failed at t = " << integrator_->time()
       << " s, leading wheelset at s = " << leading_s_ << " m: " << e.what();
    message_ = os.str();
    return finite ? RunStatus::kIntegratorFailed : RunStatus::kNonFinite;
  }
  return check();
}

RunStatus VehicleSimulator::check() {
  const double t = integrator_->time();
  if (!integrator_->state().allFinite()) {
    // Name the first wheel whose wheelset state is not finite.
    const auto y = integrator_->state();
    for (const WheelDefinition& w : contact_model_->wheels()) {
      const bool ok = y.segment<7>(VehicleModel::positionOffset(w.body)).allFinite() &&
                      y.segment<6>(model_.velocityOffset(w.body)).allFinite();
      if (!ok) {
        std::ostringstream os;
        os << "non-finite state at wheel " << 2 * w.wheelset + (w.side == rc::RailSide::kLeft ? 0 : 1) << " (wheelset "
           << w.wheelset + 1 << ", " << sideName(w.side)
           << ") near s = " << wheel_s_[static_cast<std::size_t>(2 * w.wheelset)] << " m, t = " << t << " s";
        message_ = os.str();
        return RunStatus::kNonFinite;
      }
    }
    std::ostringstream os;
    os << "non-finite state (a suspended body) at t = " << t << " s, leading wheelset near s = " << leading_s_ << " m";
    message_ = os.str();
    return RunStatus::kNonFinite;
  }
  evaluateOutputs(!external_active_);
  // Derailment: a wheelset far off the centre line, a wheel lifted by more than the flange height, or a
  // wheel whose contact search finds no rail at all.
  for (const WheelsetTrackOutput& o : wheelset_out_) {
    if (std::abs(o.lateral) > settings_.derailment_lateral) {
      std::ostringstream os;
      os << "derailment: wheelset " << o.wheelset + 1 << " is " << o.lateral * 1e3
         << " mm off the track centre line (limit " << settings_.derailment_lateral * 1e3
         << " mm) at s = " << o.arc_length << " m, t = " << t << " s";
      message_ = os.str();
      return RunStatus::kDerailed;
    }
  }
  rc::TrackPoint tp;
  for (std::size_t i = 0; i < wheel_out_.size(); ++i) {
    const WheelOutput& o = wheel_out_[i];
    track_->centre(o.arc_length, tp);
    const double height = tp.R_track_to_world.col(2).dot(o.p_in_world - tp.p_center_in_world);
    const double rise = height - (nominal_height_ + lift_);
    const auto& r = contact_data_->result[i];
    const bool off_rail = r.contact[rc::kTread].status == rc::DetectionStatus::kOutOfBounds &&
                          r.contact[rc::kFlange].status == rc::DetectionStatus::kOutOfBounds;
    if (rise > derailment_lift_ || off_rail) {
      std::ostringstream os;
      os << "derailment: wheel " << o.wheel_id << " (wheelset " << o.wheelset + 1 << ", "
         << (o.side == 0 ? "left" : "right") << ") ";
      if (off_rail) {
        os << "has no contact point on its rail";
      } else {
        os << "lifted " << rise * 1e3 << " mm (limit " << derailment_lift_ * 1e3 << " mm)";
      }
      os << " at s = " << o.arc_length << " m, t = " << t << " s";
      message_ = os.str();
      return RunStatus::kDerailed;
    }
  }
  // The track's end: the leading wheel must stay on the tabulated track.
  const double s_max = track_->sEnd() - 0.05;
  const double s_min = track_->sStart() + 0.05;
  if (finished()) return RunStatus::kFinished;
  for (const WheelOutput& o : wheel_out_) {
    if (o.arc_length > s_max || o.arc_length < s_min) {
      std::ostringstream os;
      os << "wheel " << o.wheel_id << " reached the end of the track at s = " << o.arc_length << " m, t = " << t
         << " s";
      message_ = os.str();
      return RunStatus::kLeftTrack;
    }
  }
  return RunStatus::kRunning;
}

}  // namespace rail::vehicle
