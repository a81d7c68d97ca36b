#include "rail_contact/wheel_contact.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "rail_contact/format.hpp"

namespace rail {
namespace contact {

namespace {
[[noreturn]] void fail(const char* field, double value, const char* rule) {
  std::ostringstream m;
  m << "WheelContactOptions: " << field << " = " << formatNumber(value) << " " << rule;
  throw std::runtime_error(m.str());
}
}  // namespace

void validate(const WheelContactOptions& o) {
  if (!(o.friction > 0.0) || !(o.friction < 5.0)) fail("friction", o.friction, "must be in (0, 5)");
  if (o.creep_law != CreepLaw::kPolach) fail("creep_law", static_cast<double>(o.creep_law), "is not a known law");
  validate(o.wheel_material, "WheelContactOptions.wheel_material");
  validate(o.rail_material, "WheelContactOptions.rail_material");
  validate(o.damping);
  validate(o.polach);
  if (!(o.merge_distance >= 0.0)) fail("merge_distance", o.merge_distance, "m must not be negative");
  if (!(o.max_lateral_semi_axis >= 0.0))
    fail("max_lateral_semi_axis", o.max_lateral_semi_axis, "m must not be negative (0 = no limit)");
  if (!(o.creepage.v_eps > 0.0)) fail("creepage.v_eps", o.creepage.v_eps, "m/s must be positive");
}

WheelContactModel::WheelContactModel(const WheelProfile& wheel, double nominal_radius, const ProfileCurve& rail,
                                     const Eigen::Vector2d& rail_section_centre_yz, const WheelContactOptions& options)
    : options_(options), detector_(wheel, nominal_radius, rail, rail_section_centre_yz, options.detection) {
  validate(options_);
  polach_ = options_.polach;
  polach_.spin = options_.spin;
  E_star_ = contact::contactModulus(options_.wheel_material, options_.rail_material);
  G_ = combinedShearModulus(options_.wheel_material, options_.rail_material);
  nu_ = combinedPoissonRatio(options_.wheel_material, options_.rail_material);
  kalker_ = &KalkerTable::builtin();
}

template <class Deformation>
void WheelContactModel::evaluate(const WheelState& ws, RailSide side, const TrackGeometry& track,
                                 const Deformation& deformation, WheelContactWork& work, WheelContactResult& out,
                                 ContactCost* cost) const noexcept {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point t_begin = cost != nullptr ? Clock::now() : Clock::time_point();
  double detection_s = 0.0;  // this evaluation's search time
  WheelPose pose;
  pose.p_wheel_in_world = ws.p_wheel_in_world;
  pose.R_wheelset_to_world = ws.R_wheelset_to_world;
  pose.side = side;
  pose.arc_length = ws.arc_length;
  const bool input_ok = ws.v_wheel_in_world.allFinite() && ws.omega_wheelset_in_world.allFinite();
  const Eigen::Vector3d axle = ws.R_wheelset_to_world.col(1).normalized();
  const double ls = side == RailSide::kLeft ? -1.0 : 1.0;

  bool tread_on_own_surface = true;
  bool past_end[2] = {false, false};
  for (int k = 0; k < 2; ++k) {
    ContactPointResult& c = out.contact[k];
    c = ContactPointResult();
    if (k == kFlange && !options_.flange_contact) {
      c.searched = false;
      c.status = DetectionStatus::kOutOfBounds;
      work.impact[k] = work.impact_next[k] = ImpactMemory();
      continue;
    }
    c.searched = true;
    ImpactMemory& memory = work.hold_impact_memory ? (work.impact_next[k] = work.impact[k]) : work.impact[k];
    ContactGeometry g;
    if (cost != nullptr) {
      const Clock::time_point t0 = Clock::now();
      detector_.detect(static_cast<WheelSurface>(k), pose, track, deformation, work.detection[k], g);
      const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
      detection_s += dt;
      if (k == kFlange) {
        cost->flange_detection_seconds += dt;
        ++cost->flange_searches;
      }
    } else {
      detector_.detect(static_cast<WheelSurface>(k), pose, track, deformation, work.detection[k], g);
    }
    c.status = input_ok ? g.status : DetectionStatus::kInvalidInput;
    c.penetration = std::isfinite(g.penetration) ? g.penetration : -1.0;
    if (!g.valid || !input_ok) {
      updateImpactMemory(memory, -1.0, 0.0);
      continue;
    }
    if (k == kTread) tread_on_own_surface = g.on_own_surface;
    past_end[k] = g.past_end;
    c.s_r = g.s_r;
    c.p_wheel_in_world = g.p_wheel_in_world;
    c.p_rail_in_world = g.p_rail_in_world;
    c.p_contact_in_world = 0.5 * (g.p_wheel_in_world + g.p_rail_in_world);
    c.normal_in_world = g.n_in_world;
    c.p_section_centre_in_world = g.p_section_centre_in_world;
    c.rolling_radius = g.wheel_radius;
    const Eigen::Vector3d& n = g.n_in_world;
    const Eigen::Vector3d& t_w = g.t_rolling_in_world;
    c.R_contact_to_world.col(0) = t_w;
    c.R_contact_to_world.col(1) = n.cross(t_w);
    c.R_contact_to_world.col(2) = n;
    c.contact_angle = std::asin(std::clamp(n.dot(ls * axle), -1.0, 1.0));

    // Material-point velocities: wheel (rigid wheelset) and rail (section motion from the provider).
    const Eigen::Vector3d v_wheel =
        ws.v_wheel_in_world + ws.omega_wheelset_in_world.cross(g.p_wheel_in_world - ws.p_wheel_in_world);
    const Eigen::Vector3d v_rail =
        g.rail_motion.u_dot + g.rail_motion.theta_dot.cross(g.p_rail_in_world - g.p_section_centre_in_world);
    // Penetration rate: the wheel is a surface of revolution about its axle, so the spin about the axle moves
    // material along the surface and does not change the penetration. Only the wheelset's motion without
    // that spin enters: exact at a converged point pair (where the spin term is tangent anyway), and an
    // approximate pair (normals up to acos(min_normal_opposition) apart) no longer reads a part of the
    // rolling speed (~30 m/s at 108 km/h) as a penetration rate, which eq. 9's damping turned into
    // single-sample normal-force spikes of several MN.
    const Eigen::Vector3d omega_without_spin = ws.omega_wheelset_in_world - ws.omega_wheelset_in_world.dot(axle) * axle;
    const Eigen::Vector3d v_wheel_shape =
        ws.v_wheel_in_world + omega_without_spin.cross(g.p_wheel_in_world - ws.p_wheel_in_world);
    c.penetration_rate = -(v_wheel_shape - v_rail).dot(n);
    updateImpactMemory(memory, c.penetration, c.penetration_rate);
    if (!g.in_contact) continue;

    // Hertz (eq. 9): principal curvatures, rail longitudinal curvature ~ 0.
    PrincipalCurvatures kc;
    kc.wheel_rolling = g.cos_normal_radial / g.wheel_radius;
    kc.wheel_lateral = g.wheel_curvature;
    kc.rail_rolling = 0.0;
    kc.rail_lateral = g.rail_curvature;
    const HertzGeometry hz = limitLateralWidth(computeHertz(kc, E_star_, options_.hertz), c.penetration,
                                               options_.max_lateral_semi_axis, options_.hertz);
    c.hertz_flags = hz.flags;
    if (k == kFlange && out.contact[kTread].penetration > 0.0 &&
        (out.contact[kTread].p_wheel_in_world - g.p_wheel_in_world).norm() < options_.merge_distance) {
      // One patch across the split: keep one of the two. Each surface continues a little past the split
      // (DetectionOptions::split_overlap); a point found there belongs to the other surface, which keeps
      // its own point. Two points on their own surfaces (or both past the split): the deeper one.
      ContactPointResult& t = out.contact[kTread];
      const bool flange_keeps =
          g.on_own_surface != tread_on_own_surface ? g.on_own_surface : c.penetration > t.penetration;
      if (flange_keeps) {
        t.active = false;
        t.merged = true;
        t.N = t.F_long = t.F_lat = t.a = t.b = 0.0;
        t.force_on_wheel_in_world.setZero();
        t.rail_wrench = RailWrench();
      } else {
        c.merged = true;
        continue;
      }
    }
    c.N = dampedNormalForce(hz.K, c.penetration, c.penetration_rate, memory.impact_velocity, options_.damping);
    c.active = true;
    c.a = hz.a(c.N);
    c.b = hz.b(c.N);

    // Creepages (rolling speed: wheel centre relative to the rail section along t_rolling).
    const double V = (ws.v_wheel_in_world - g.rail_motion.u_dot).dot(t_w);
    const Creepages cr = computeCreepages(v_wheel, v_rail, ws.omega_wheelset_in_world, g.rail_motion.theta_dot,
                                          c.R_contact_to_world, V, options_.creepage);
    c.nu_x = cr.nu_x;
    c.nu_y = cr.nu_y;
    c.phi = options_.spin ? cr.phi : 0.0;

    if (c.N > 0.0 && c.a > 0.0 && c.b > 0.0) {
      PolachInput pin;
      pin.nu_x = c.nu_x;
      pin.nu_y = c.nu_y;
      pin.phi = c.phi;
      pin.N = c.N;
      pin.a = c.a;
      pin.b = c.b;
      pin.G = G_;
      pin.mu0 = options_.friction;
      pin.V = cr.V_ref;
      pin.c = kalker_->evaluate(c.a / c.b, nu_);
      const PolachResult pr = polachForces(pin, polach_);
      c.F_long = pr.Fx;
      c.F_lat = pr.Fy;
      if (cost != nullptr) {
        ++cost->creep_evaluations;
        if (polach_.spin) ++cost->spin_evaluations;  // polach_forces evaluated its spin terms (nu_C, F_yS)
      }
    }
    c.force_on_wheel_in_world = contactForceInWorld(c.R_contact_to_world, c.F_long, c.F_lat, c.N);
    c.rail_wrench = railSectionWrench(-c.force_on_wheel_in_world, Eigen::Vector3d::Zero(),
                                      c.p_rail_in_world - c.p_section_centre_in_world, Eigen::Vector3d::Zero());
  }

  for (int k = 0; k < 2; ++k) {
    if (past_end[k] && out.contact[k].active) ++work.detection[k].past_end_contacts;
  }

  // Eq. 13: both contacts to the wheel centre (inactive contacts carry zero force).
  const Eigen::Matrix3d& A = ws.R_wheelset_to_world;
  const ContactPointResult& tr = out.contact[kTread];
  const ContactPointResult& fl = out.contact[kFlange];
  out.wheel_centre = wheelCentreWrench(tr.force_on_wheel_in_world, fl.force_on_wheel_in_world,
                                       A.transpose() * (tr.p_wheel_in_world - ws.p_wheel_in_world),
                                       A.transpose() * (fl.p_wheel_in_world - ws.p_wheel_in_world), A);
  // Eq. 15: both contacts about one section centre (the tread contact's if active, else the flange's).
  const ContactPointResult& ref = tr.active || !fl.active ? tr : fl;
  out.rail_section_s = ref.s_r;
  out.rail_section = railSectionWrench(-tr.force_on_wheel_in_world, -fl.force_on_wheel_in_world,
                                       tr.p_rail_in_world - ref.p_section_centre_in_world,
                                       fl.p_rail_in_world - ref.p_section_centre_in_world);
  if (!out.wheel_centre.force_in_world.allFinite() || !out.wheel_centre.moment_in_wheelset.allFinite()) {
    out.wheel_centre = WheelsetWrench();
    out.rail_section = RailWrench();
  }
  if (cost != nullptr) {
    const double total = std::chrono::duration<double>(Clock::now() - t_begin).count();
    cost->detection_seconds += detection_s;
    cost->forces_seconds += total - detection_s;
    ++cost->evaluations;
  }
}

template void WheelContactModel::evaluate<RigidRailDeformation>(const WheelState&, RailSide, const TrackGeometry&,
                                                                const RigidRailDeformation&, WheelContactWork&,
                                                                WheelContactResult&, ContactCost*) const noexcept;
template void WheelContactModel::evaluate<BeamRailDeformation>(const WheelState&, RailSide, const TrackGeometry&,
                                                               const BeamRailDeformation&, WheelContactWork&,
                                                               WheelContactResult&, ContactCost*) const noexcept;
template void WheelContactModel::evaluate<RailDeformation>(const WheelState&, RailSide, const TrackGeometry&,
                                                           const RailDeformation&, WheelContactWork&,
                                                           WheelContactResult&, ContactCost*) const noexcept;

}  // namespace contact
}  // namespace rail
