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
  if (!(o.patch_dip >= 0.0) || !(o.patch_dip < 1.0)) fail("patch_dip", o.patch_dip, "must be in [0, 1)");
  if (!(o.patch_min_dip >= 0.0) || !(o.patch_min_dip < 1e-3))
    fail("patch_min_dip", o.patch_min_dip, "m must be in [0, 1e-3)");
  // A scan sample not taken must hold a value that no patch decision tells from its distance.
  if (!(o.detection.scan_skip_clearance == 0.0 || o.detection.scan_skip_clearance > o.patch_min_dip))
    fail("detection.scan_skip_clearance", o.detection.scan_skip_clearance, "m must be 0 or above patch_min_dip");
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

void sumContactWrenches(const Eigen::Vector3d& p_wheel_in_world, const Eigen::Matrix3d& R_wheelset_to_world,
                        WheelContactResult& out) noexcept {
  // Eq. 15 about one section centre: the first active contact's (the tread's if active).
  int ref = kTread;
  for (int k = 0; k < kContactSlots; ++k) {
    if (out.contact[k].active) {
      ref = k;
      break;
    }
  }
  const Eigen::Vector3d& c_section = out.contact[ref].p_section_centre_in_world;
  out.rail_section_s = out.contact[ref].s_r;
  out.wheel_centre = WheelsetWrench();
  out.rail_section = RailWrench();
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  for (const ContactPointResult& c : out.contact) {
    if (!c.active) continue;
    // Eq. 13: to the wheel centre.
    accumulate(out.wheel_centre,
               wheelCentreWrench(c.force_on_wheel_in_world, zero,
                                 R_wheelset_to_world.transpose() * (c.p_wheel_in_world - p_wheel_in_world), zero,
                                 R_wheelset_to_world));
    const RailWrench one = railSectionWrench(-c.force_on_wheel_in_world, zero, c.p_rail_in_world - c_section, zero);
    out.rail_section.force_in_world += one.force_in_world;
    out.rail_section.moment_in_world += one.moment_in_world;
  }
  if (!out.wheel_centre.force_in_world.allFinite() || !out.wheel_centre.moment_in_wheelset.allFinite()) {
    out.wheel_centre = WheelsetWrench();
    out.rail_section = RailWrench();
  }
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

  ContactGeometry geometry[kContactSlots];
  int surface_of[kContactSlots] = {kTread, kFlange, kTread, kFlange};
  bool searched[kContactSlots] = {false, false, false, false};
  bool merged[kContactSlots] = {false, false, false, false};
  auto timedDetect = [&](int k) {
    DetectionWork& dw = work.detection[k];
    const WheelSurface surface = static_cast<WheelSurface>(surface_of[k]);
    if (cost != nullptr) {
      const Clock::time_point t0 = Clock::now();
      detector_.detect(surface, pose, track, deformation, dw, geometry[k]);
      const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
      detection_s += dt;
      if (surface == WheelSurface::kFlange) {
        cost->flange_detection_seconds += dt;
        ++cost->flange_searches;
      }
    } else {
      detector_.detect(surface, pose, track, deformation, dw, geometry[k]);
    }
  };
  auto touching = [&](int k) { return searched[k] && input_ok && geometry[k].valid && geometry[k].in_contact; };

  // The tread and flange contacts.
  for (int k = kTread; k <= kFlange; ++k) {
    if (k == kFlange && !options_.flange_contact) continue;
    searched[k] = true;
    work.detection[k].seeded = false;
    timedDetect(k);
  }
  // The profile's distance to the rail, for the patches: the flange's part while the flange has a point.
  ProfileScan scan;
  scan.n = 0;
  const bool scanning = options_.second_contacts && input_ok;
  if (scanning) {
    const Clock::time_point t0 = cost != nullptr ? Clock::now() : Clock::time_point();
    detector_.scanProfile(pose, track, deformation, searched[kFlange] && geometry[kFlange].valid, scan);
    if (cost != nullptr) detection_s += std::chrono::duration<double>(Clock::now() - t0).count();
  }
  auto samePatch = [&](double U_a, double U_b) {
    return scan.samePatch(U_a, U_b, options_.patch_dip, options_.patch_min_dip);
  };
  // A tread or flange point clearly inside the rail but not at its patch's deepest interpenetration (no
  // maximum within two samples of it, or a deeper one in the same patch by more than the patch dip) stands
  // for the patch only by the path that led there: it is dropped, its surface searches afresh next time,
  // and the patch is taken from its deepest sample below.
  if (scanning) {
    for (int k = kTread; k <= kFlange; ++k) {
      if (!touching(k)) continue;
      const double U = geometry[k].profile_u;
      const int i = scan.nearest(U);
      const double d = scan.distance[i];
      const double margin = std::max(options_.patch_dip * std::abs(d), options_.patch_min_dip);
      // Within the scan's resolution of the rail a shallow point need not sit on a sampled maximum.
      bool at_maximum = !(d < -options_.patch_min_dip), deeper = false;
      for (int m = 0; m < scan.n_minima && !deeper; ++m) {
        const int j = scan.minima[m].sample;
        if (std::abs(j - i) <= 2) {
          at_maximum = true;
        } else if (scan.distance[j] < d - margin && samePatch(U, scan.profile_u[j])) {
          deeper = true;
        }
      }
      if (at_maximum && !deeper) continue;
      geometry[k] = ContactGeometry();
      geometry[k].penetration = -1.0;
      work.detection[k].has_warm_start = false;
    }
  }
  auto onePatch = [&](double U_a, const Eigen::Vector3d& p_a, double U_b, const Eigen::Vector3d& p_b) {
    return (p_a - p_b).norm() < options_.merge_distance || (scanning && samePatch(U_a, U_b));
  };
  // The same with the distance taken along the profile (points of the scan, not yet detected).
  auto onePatchAlong = [&](double U_a, double U_b) {
    return std::abs(U_a - U_b) < options_.merge_distance || samePatch(U_a, U_b);
  };
  if (touching(kTread) && touching(kFlange)) {
    const ContactGeometry& t = geometry[kTread];
    const ContactGeometry& f = geometry[kFlange];
    const bool close = (t.p_wheel_in_world - f.p_wheel_in_world).norm() < options_.merge_distance;
    if (close || (scanning && samePatch(t.profile_u, f.profile_u))) {
      // One patch: keep one of the two. Each surface continues a little past the split
      // (DetectionOptions::split_overlap); of one point reported by both, the surface whose own part it lies
      // on keeps it. Otherwise (both on their own parts, both past the split, or two points of one patch
      // apart) the deeper one.
      const bool flange_keeps =
          close && f.on_own_surface != t.on_own_surface ? f.on_own_surface : f.penetration > t.penetration;
      merged[flange_keeps ? kTread : kFlange] = true;
    }
  }
  // Further patches, the deepest first, each apart from the held contacts and from one another; a slot
  // whose warm start lies in a patch keeps it (its impact memory stays that patch's).
  int patch_of_slot[2] = {-1, -1};
  if (scanning) {
    int chosen[2];
    int n_chosen = 0;
    for (int m = 0; m < scan.n_minima && n_chosen < 2; ++m) {
      const ProfileScan::Minimum& mm = scan.minima[m];
      const double U = scan.profile_u[mm.sample];
      bool apart = true;
      for (int k = kTread; k <= kFlange && apart; ++k) {
        if (touching(k) && !merged[k] && onePatchAlong(U, geometry[k].profile_u)) apart = false;
      }
      for (int c = 0; c < n_chosen && apart; ++c) {
        if (samePatch(U, scan.profile_u[scan.minima[chosen[c]].sample])) apart = false;
      }
      if (apart) chosen[n_chosen++] = m;
    }
    bool taken[2] = {false, false};
    for (int j = 0; j < 2; ++j) {
      const DetectionWork& dw = work.detection[kTreadSecond + j];
      const bool has = dw.hold_warm_start ? dw.has_committed_warm_start : dw.has_warm_start;
      if (!has) continue;
      const double U_w = detector_.profileU(dw.hold_warm_start ? dw.x_surface_committed : dw.x_surface,
                                            dw.hold_warm_start ? dw.x_committed[1] : dw.x[1]);
      for (int c = 0; c < n_chosen; ++c) {
        const double U = scan.profile_u[scan.minima[chosen[c]].sample];
        if (!taken[c] && onePatchAlong(U_w, U)) {
          patch_of_slot[j] = c;
          taken[c] = true;
          break;
        }
      }
    }
    for (int c = 0; c < n_chosen; ++c) {
      for (int j = 0; j < 2 && !taken[c]; ++j) {
        if (patch_of_slot[j] >= 0) continue;
        patch_of_slot[j] = c;
        taken[c] = true;
      }
    }
    for (int j = 0; j < 2; ++j) {
      if (patch_of_slot[j] >= 0) patch_of_slot[j] = chosen[patch_of_slot[j]];
    }
  }
  for (int j = 0; j < 2; ++j) {
    const int k = kTreadSecond + j;
    if (patch_of_slot[j] < 0) continue;
    const ProfileScan::Minimum& mm = scan.minima[patch_of_slot[j]];
    DetectionWork& dw = work.detection[k];
    dw.seeded = true;
    dw.seed = mm.seed;
    surface_of[k] = mm.surface;
    searched[k] = true;
    timedDetect(k);
    // Newton may leave the patch for a held one: then it is not a further contact.
    const ContactGeometry& g = geometry[k];
    bool apart = g.valid && g.in_contact;
    for (int h = 0; h < k && apart; ++h) {
      if (touching(h) && !merged[h] &&
          onePatch(g.profile_u, g.p_wheel_in_world, geometry[h].profile_u, geometry[h].p_wheel_in_world))
        apart = false;
    }
    if (!apart) {
      geometry[k] = ContactGeometry();
      dw.has_warm_start = false;
    }
  }

  bool past_end[kContactSlots] = {false, false, false, false};
  for (int k = 0; k < kContactSlots; ++k) {
    ContactPointResult& c = out.contact[k];
    c = ContactPointResult();
    c.surface = surface_of[k];
    if (!searched[k]) {
      c.status = DetectionStatus::kOutOfBounds;
      (work.hold_impact_memory ? work.impact_next[k] : work.impact[k]) = ImpactMemory();
      if (k >= kTreadSecond) {
        c.searched = scanning;
        work.detection[k].has_warm_start = false;
      } else {
        work.impact[k] = work.impact_next[k] = ImpactMemory();
      }
      continue;
    }
    c.searched = true;
    ImpactMemory& memory = work.hold_impact_memory ? (work.impact_next[k] = work.impact[k]) : work.impact[k];
    const ContactGeometry& g = geometry[k];
    c.status = input_ok ? g.status : DetectionStatus::kInvalidInput;
    c.penetration = std::isfinite(g.penetration) ? g.penetration : -1.0;
    if (!g.valid || !input_ok) {
      updateImpactMemory(memory, -1.0, 0.0);
      continue;
    }
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
    bool in_contact = g.in_contact;
    if (!options_.wheel_defects.empty()) {
      // The defect lowers the surface along the wheel radius where the contact is; its angle in the
      // wheelset frame advances with the spin about the axle.
      const Eigen::Vector3d r_in_wheelset =
          ws.R_wheelset_to_world.transpose() * (g.p_wheel_in_world - ws.p_wheel_in_world);
      const double beta = std::atan2(r_in_wheelset.x(), -r_in_wheelset.z());
      double depth = 0.0, d_depth_d_beta = 0.0;
      options_.wheel_defects.evaluate(ws.id, beta, depth, d_depth_d_beta);
      const double spin = ws.omega_wheelset_in_world.dot(axle);
      c.penetration -= depth * g.cos_normal_radial;
      c.penetration_rate -= d_depth_d_beta * spin * g.cos_normal_radial;
      in_contact = c.penetration > 0.0;
      // The wheel bears on the defect's edge, d depth / d beta ahead of or behind the round wheel's point
      // (a flat's edge lies exactly there): the force's moment about the axle turns the drop into spin and
      // back, as the rolling angle's share of the contact's potential energy requires.
      const Eigen::Vector3d shift = -d_depth_d_beta * t_w;
      c.p_wheel_in_world += shift;
      c.p_rail_in_world += shift;
      c.p_contact_in_world += shift;
    }
    updateImpactMemory(memory, c.penetration, c.penetration_rate);
    if (!in_contact) continue;

    // Hertz (eq. 9): principal curvatures, rail longitudinal curvature ~ 0.
    PrincipalCurvatures kc;
    kc.wheel_rolling = g.cos_normal_radial / g.wheel_radius;
    kc.wheel_lateral = g.wheel_curvature;
    kc.rail_rolling = 0.0;
    kc.rail_lateral = g.rail_curvature;
    const HertzGeometry hz = limitLateralWidth(computeHertz(kc, E_star_, options_.hertz), c.penetration,
                                               options_.max_lateral_semi_axis, options_.hertz);
    c.hertz_flags = hz.flags;
    if (merged[k]) {
      c.merged = true;
      continue;
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
        if (polach_.spin) ++cost->spin_evaluations;  // polachForces evaluated its spin terms (nu_C, F_yS)
      }
    }
    c.force_on_wheel_in_world = contactForceInWorld(c.R_contact_to_world, c.F_long, c.F_lat, c.N);
    c.rail_wrench = railSectionWrench(-c.force_on_wheel_in_world, Eigen::Vector3d::Zero(),
                                      c.p_rail_in_world - c.p_section_centre_in_world, Eigen::Vector3d::Zero());
  }

  for (int k = 0; k < kContactSlots; ++k) {
    if (past_end[k] && out.contact[k].active) ++work.detection[k].past_end_contacts;
  }
  sumContactWrenches(ws.p_wheel_in_world, ws.R_wheelset_to_world, out);
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
