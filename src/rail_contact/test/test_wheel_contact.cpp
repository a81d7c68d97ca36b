// Tests of the per-wheel contact evaluation (wheel_contact.hpp): normal force from the Hertz stiffness and
// the hysteresis law, creepages of a rolling wheel in closed form, creep forces in Kalker's linear limit,
// equivalent wrenches (eqs. 13 and 15), and finite results at zero speed, zero load, with flange contact
// and spin switched off.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>

#include "rail_contact/contact_geometry_table.hpp"
#include "rail_contact/wheel_contact.hpp"

namespace rc = rail::contact;
using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace {

constexpr double kR0 = 0.46;

struct Setup {
  rc::WheelProfile wheel = rc::makeS1002();
  rc::ProfileCurve rail = rc::makeUic60Rail(1.0 / 40.0);
  rc::WheelsetTrackSpec spec;
  rc::ContactGeometryTable table{wheel, rail, spec};
  double z0 = table.row(0.0).z;  // centred, zero-gap height of the wheelset centre
};
Setup& setup() {
  static Setup s;
  return s;
}

rc::WheelState leftWheel(double y, double dz, double V, double omega) {
  rc::WheelState w;
  const double e = setup().table.wheelHalfDistance();
  w.p_wheel_in_world = Vector3d(10.0, y + e, setup().z0 + dz);
  w.v_wheel_in_world = Vector3d(V, 0.0, 0.0);
  w.omega_wheelset_in_world = Vector3d(0.0, omega, 0.0);
  w.arc_length = 10.0;
  return w;
}

rc::WheelContactModel makeModel(bool flange, bool spin) {
  rc::WheelContactOptions o;
  o.flange_contact = flange;
  o.spin = spin;
  o.friction = 0.4;
  o.damping.restitution = 0.5;
  return rc::WheelContactModel(setup().wheel, kR0, setup().rail, Eigen::Vector2d(0.0, -0.09), o);
}

}  // namespace

TEST(WheelContact, StaticNormalForceIsHertzOfThePenetration) {
  const rc::WheelContactModel m = makeModel(true, true);
  rc::WheelContactWork work;
  rc::WheelContactResult out;
  m.evaluate(leftWheel(0.0, -50e-6, 0.0, 0.0), rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(),
             work, out);
  const rc::ContactPointResult& c = out.contact[rc::kTread];
  ASSERT_TRUE(c.active);
  EXPECT_FALSE(out.contact[rc::kFlange].active);
  // Level wheelset lowered by 50 um: penetration 50 um times the normal's vertical component (~1 at 1:40).
  EXPECT_NEAR(c.penetration, 50e-6 * c.normal_in_world.z(), 1e-9);
  // Hertz stiffness from the principal curvatures at the contact, computed here from the profiles.
  // Hertz stiffness from the principal curvatures at the contact, computed here from the profiles at the
  // reported contact points (closest-point projections, independent of the detection's parameters).
  const rc::ProfileCurve& tread = setup().wheel.tread;
  rc::WheelPose pose;
  const rc::WheelState w0 = leftWheel(0.0, -50e-6, 0.0, 0.0);
  pose.p_wheel_in_world = w0.p_wheel_in_world;
  pose.side = rc::RailSide::kLeft;
  pose.arc_length = 10.0;
  rc::DetectionWork dw;
  rc::ContactGeometry g;
  m.detector().detect(rc::WheelSurface::kTread, pose, setup().table.track(), rc::RigidRailDeformation(), dw, g);
  rc::PrincipalCurvatures k;
  k.wheel_rolling = std::abs(c.normal_in_world.z()) / c.rolling_radius;  // Meusnier: cos(angle) / radius
  k.wheel_lateral = tread.curvature(tread.closestParameter(Eigen::Vector2d(g.wheel_y, g.wheel_z)));
  k.rail_lateral = setup().rail.curvature(setup().rail.closestParameter(Eigen::Vector2d(g.rail_y, g.rail_z)));
  const rc::HertzGeometry hz = rc::computeHertz(k, m.contactModulus());
  // Zero penetration rate: the damping term vanishes, N = K delta^1.5 (1e-6 relative: the curvatures
  // here come from closest-point projections of the reported points).
  EXPECT_NEAR(c.N, hz.K * std::pow(c.penetration, 1.5), 1e-6 * c.N);
  EXPECT_NEAR(c.a, hz.a(c.N), 1e-6 * c.a);
  EXPECT_NEAR(c.b, hz.b(c.N), 1e-6 * c.b);
  // Plausible wheel-rail magnitudes (a 50 um approach carries tens of kN; ellipse of several mm).
  EXPECT_GT(c.N, 1e4);
  EXPECT_LT(c.N, 2e5);
}

TEST(WheelContact, HysteresisDampingFollowsEquation9) {
  const rc::WheelContactModel m = makeModel(true, true);
  rc::WheelContactWork work;
  rc::WheelContactResult out;
  // First touch with an approach speed of 0.05 m/s: impact velocity stored.
  rc::WheelState w = leftWheel(0.0, -10e-6, 0.0, 0.0);
  w.v_wheel_in_world.z() = -0.05;
  m.evaluate(w, rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(), work, out);
  const rc::ContactPointResult& c = out.contact[rc::kTread];
  ASSERT_TRUE(c.active);
  const double nz = c.normal_in_world.z();
  EXPECT_NEAR(c.penetration_rate, 0.05 * nz, 1e-12);
  EXPECT_NEAR(work.impact[rc::kTread].impact_velocity, 0.05 * nz, 1e-12);
  // Deeper, now separating at 0.02 m/s: N = K d^1.5 (1 + 3 (1 - e^2) / 4 * ddot / ddot_impact).
  rc::WheelState w2 = leftWheel(0.0, -40e-6, 0.0, 0.0);
  w2.v_wheel_in_world.z() = 0.02;
  m.evaluate(w2, rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(), work, out);
  rc::WheelContactWork fresh;
  rc::WheelContactResult elastic;
  m.evaluate(leftWheel(0.0, -40e-6, 0.0, 0.0), rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(),
             fresh, elastic);
  const double factor = 1.0 + 0.75 * (1.0 - 0.25) * (-0.02 * nz) / (0.05 * nz);
  // 1e-6 relative: the normal (hence nz) differs by ~1e-7 rad between the two depths.
  EXPECT_NEAR(out.contact[rc::kTread].N, elastic.contact[rc::kTread].N * factor, 1e-6 * elastic.contact[rc::kTread].N);
}

TEST(WheelContact, AHeldImpactMemoryTakesOnlyTheCommittedEvaluations) {
  // An implicit integrator evaluates trial states (Newton iterates, rejected steps) before it accepts one.
  // With hold_impact_memory, a trial that pushes the wheel in fast must not change the force at another
  // state until it is committed; without it, it does (the memory keeps the largest approach rate).
  const rc::WheelContactModel m = makeModel(true, true);
  const auto& track = setup().table.track();
  rc::WheelState accepted = leftWheel(0.0, -20e-6, 0.0, 0.0);
  accepted.v_wheel_in_world.z() = -0.01;  // onset at 0.01 m/s
  rc::WheelState trial = leftWheel(0.0, -60e-6, 0.0, 0.0);
  trial.v_wheel_in_world.z() = -0.5;  // a trial state far deeper and fifty times faster
  rc::WheelState later = leftWheel(0.0, -30e-6, 0.0, 0.0);
  later.v_wheel_in_world.z() = 0.005;  // separating: eq. 9's damping divides by the remembered rate
  rc::WheelContactResult out;

  rc::WheelContactWork held;
  held.hold_impact_memory = true;
  m.evaluate(accepted, rc::RailSide::kLeft, track, rc::RigidRailDeformation(), held, out);
  EXPECT_FALSE(held.impact[rc::kTread].in_contact);  // not committed yet
  held.commitImpactMemory();
  ASSERT_TRUE(held.impact[rc::kTread].in_contact);
  const double onset = held.impact[rc::kTread].impact_velocity;
  EXPECT_GT(onset, 0.009);
  m.evaluate(later, rc::RailSide::kLeft, track, rc::RigidRailDeformation(), held, out);
  const double n_before_trial = out.contact[rc::kTread].N;
  m.evaluate(trial, rc::RailSide::kLeft, track, rc::RigidRailDeformation(), held, out);
  EXPECT_GT(held.impact_next[rc::kTread].impact_velocity, 0.4);  // the trial's own force used its rate
  m.evaluate(later, rc::RailSide::kLeft, track, rc::RigidRailDeformation(), held, out);
  // The trial left no trace in the memory; the detection's warm start (another start point) moves the
  // converged point within its tolerance only (1e-8 relative in N seen), hence 1e-7 relative: the trial
  // would move it by 38 %.
  EXPECT_NEAR(out.contact[rc::kTread].N, n_before_trial, 1e-7 * n_before_trial);
  EXPECT_EQ(held.impact[rc::kTread].impact_velocity, onset);

  // Without holding, the same sequence remembers the trial: the damping at `later` shrinks by ~50 times.
  rc::WheelContactWork every;
  m.evaluate(accepted, rc::RailSide::kLeft, track, rc::RigidRailDeformation(), every, out);
  m.evaluate(later, rc::RailSide::kLeft, track, rc::RigidRailDeformation(), every, out);
  EXPECT_NEAR(out.contact[rc::kTread].N, n_before_trial, 1e-7 * n_before_trial);  // as held, committed at `accepted`
  m.evaluate(trial, rc::RailSide::kLeft, track, rc::RigidRailDeformation(), every, out);
  m.evaluate(later, rc::RailSide::kLeft, track, rc::RigidRailDeformation(), every, out);
  EXPECT_GT(out.contact[rc::kTread].N, n_before_trial * 1.1);

  // reset() keeps the caller's choice.
  held.reset();
  EXPECT_TRUE(held.hold_impact_memory);
  EXPECT_FALSE(held.impact[rc::kTread].in_contact);
}

TEST(WheelContact, PenetrationRateIgnoresTheSpinAboutTheAxle) {
  // A surface of revolution spinning about its axis keeps its shape: the penetration rate (and with it eq. 9's
  // damping) must be the same with and without the wheel's spin, also for an approximate point pair whose
  // normals are not parallel (the search's estimate after a failed Newton: one iteration allowed here, from
  // a cold start on a flanging pose at an angle of attack of 20 mrad, which puts the flange contact ahead of
  // the axle, where the rolling velocity has a component along a misaligned normal). Before the spin was
  // removed, 70 rad/s of spin changed the rate of such a pair by metres per second.
  rc::WheelContactOptions o;
  o.detection.max_iterations = 1;
  const rc::WheelContactModel m(setup().wheel, kR0, setup().rail, Eigen::Vector2d(0.0, -0.09), o);
  const Matrix3d yaw = Eigen::AngleAxisd(0.02, Vector3d::UnitZ()).toRotationMatrix();
  int approximate = 0, compared = 0;
  double largest_rate = 0.0;
  for (double y : {0.0, 0.004, 0.006, 0.007, 0.008}) {  // towards the left flange
    rc::WheelState w = leftWheel(y, -60e-6, 30.0, 0.0);
    w.R_wheelset_to_world = yaw;
    w.v_wheel_in_world.z() = -0.01;
    w.v_wheel_in_world.y() = 0.05;
    rc::WheelState spinning = w;
    spinning.omega_wheelset_in_world = 70.0 * yaw.col(1);  // about the axle (the wheelset frame's y)
    rc::WheelContactWork work_a, work_b;
    rc::WheelContactResult still, rolling;
    m.evaluate(w, rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(), work_a, still);
    m.evaluate(spinning, rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(), work_b, rolling);
    for (int k = 0; k < 2; ++k) {
      const rc::ContactPointResult& a = still.contact[k];
      const rc::ContactPointResult& b = rolling.contact[k];
      if (!(a.penetration > 0.0) || a.status == rc::DetectionStatus::kOutOfBounds) continue;
      ++compared;
      approximate += a.status == rc::DetectionStatus::kApproximate;
      EXPECT_NEAR(a.penetration_rate, b.penetration_rate, 1e-12) << "y = " << y << ", contact " << k;
      largest_rate = std::max(largest_rate, std::abs(a.penetration_rate));
      EXPECT_NEAR(a.N, b.N, 1e-9 * a.N) << "y = " << y << ", contact " << k;
    }
  }
  EXPECT_GT(compared, 4);
  EXPECT_GT(approximate, 0);     // the case that matters was exercised
  EXPECT_LT(largest_rate, 0.1);  // the wheelset's own approach (0.05 m/s lateral, 0.01 m/s down) bounds it
}

TEST(WheelContact, CreepagesOfARollingWheelInClosedForm) {
  const rc::WheelContactModel m = makeModel(true, true);
  const double V = 20.0, omega = V / kR0 * 1.001, vy = 0.05;
  rc::WheelState w = leftWheel(0.0, -30e-6, V, omega);
  w.v_wheel_in_world.y() = vy;
  rc::WheelContactWork work;
  rc::WheelContactResult out;
  m.evaluate(w, rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(), work, out);
  const rc::ContactPointResult& c = out.contact[rc::kTread];
  ASSERT_TRUE(c.active);
  const double Vref = std::hypot(V, m.options().creepage.v_eps);
  // Distance of the contact point from the axle (level wheelset, contact below the axle).
  const Vector3d rel = c.p_wheel_in_world - w.p_wheel_in_world;
  const double rho = (rel - rel.y() * Vector3d::UnitY()).norm();
  const double gamma = c.contact_angle;
  // Wheel point velocity V - omega rho (forward), lateral vy; spin about the normal omega . n.
  EXPECT_NEAR(c.nu_x, (V - omega * rho) / Vref, 1e-9);
  EXPECT_NEAR(c.nu_y, vy * std::cos(gamma) / Vref, 1e-9);
  EXPECT_NEAR(c.phi, -omega * std::sin(gamma) / Vref, 1e-9);  // left wheel: normal leans to -y
  EXPECT_NEAR(c.rolling_radius, rho, 1e-12);
}

TEST(WheelContact, CreepForceTendsToKalkerLinearTheory) {
  // Small creepage: Polach's force tends to Kalker's linear law F_x = -G a b c11 nu_x (Kalker 1967; the
  // Polach small-creepage limit). Tolerance 1 %: at nu_x = 1e-5 the saturation term is ~1e-3 relative.
  const rc::WheelContactModel m = makeModel(true, false);
  const double V = 20.0;
  rc::WheelContactWork work;
  rc::WheelContactResult out;
  rc::WheelState w0 = leftWheel(0.0, -40e-6, V, 0.0);
  m.evaluate(w0, rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(), work, out);
  const double rho = out.contact[rc::kTread].rolling_radius;
  rc::WheelState w = leftWheel(0.0, -40e-6, V, V / rho * (1.0 - 1e-5));
  m.evaluate(w, rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(), work, out);
  const rc::ContactPointResult& c = out.contact[rc::kTread];
  ASSERT_TRUE(c.active);
  EXPECT_NEAR(c.nu_x, 1e-5 * V / std::hypot(V, 0.1), 1e-8);
  const rc::KalkerCoefficients kc = rc::KalkerTable::builtin().evaluate(c.a / c.b, m.poissonRatio());
  const double F_lin = -m.shearModulus() * c.a * c.b * kc.c11 * c.nu_x;
  EXPECT_NEAR(c.F_long, F_lin, 0.01 * std::abs(F_lin));
  EXPECT_EQ(c.phi, 0.0);  // spin off
}

TEST(WheelContact, WrenchesAtWheelCentreAndRailSection) {
  const rc::WheelContactModel m = makeModel(true, true);
  rc::WheelState w = leftWheel(0.0, -40e-6, 15.0, 15.0 / kR0 * 0.999);
  w.R_wheelset_to_world = Eigen::AngleAxisd(0.004, Vector3d::UnitZ()).toRotationMatrix();
  w.v_wheel_in_world.y() = 0.1;
  rc::WheelContactWork work;
  rc::WheelContactResult out;
  m.evaluate(w, rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(), work, out);
  const rc::ContactPointResult& c = out.contact[rc::kTread];
  ASSERT_TRUE(c.active);
  // Eq. 12: f = N n + F_long t_w + F_lat t_u.
  const Vector3d f =
      c.N * c.normal_in_world + c.F_long * c.R_contact_to_world.col(0) + c.F_lat * c.R_contact_to_world.col(1);
  EXPECT_LT((c.force_on_wheel_in_world - f).norm(), 1e-9 * f.norm());
  // Eq. 13 about the wheel centre, moment in the wheelset frame; eq. 15 opposite force on the rail.
  const Matrix3d& A = w.R_wheelset_to_world;
  const Vector3d m_ws = (A.transpose() * (c.p_wheel_in_world - w.p_wheel_in_world)).cross(A.transpose() * f);
  EXPECT_LT((out.wheel_centre.force_in_world - f).norm(), 1e-9 * f.norm());
  EXPECT_LT((out.wheel_centre.moment_in_wheelset - m_ws).norm(), 1e-9 * m_ws.norm());
  EXPECT_LT((out.rail_section.force_in_world + f).norm(), 1e-9 * f.norm());
  const Vector3d m_r = (c.p_rail_in_world - c.p_section_centre_in_world).cross(-f);
  EXPECT_LT((out.rail_section.moment_in_world - m_r).norm(), 1e-9 * m_r.norm());
  // The section centre lies 90 mm below the rail origin (given), under the contact.
  EXPECT_NEAR(out.rail_section_s, c.s_r, 0.0);
}

TEST(WheelContact, ZeroSpeedZeroLoadFlangeOffAreFiniteAndFlagged) {
  const rc::WheelContactModel m = makeModel(false, true);
  rc::WheelContactWork work;
  rc::WheelContactResult out;
  // Standstill, in contact: creepages finite (regularised), creep forces zero without relative motion.
  m.evaluate(leftWheel(0.0, -30e-6, 0.0, 0.0), rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(),
             work, out);
  const rc::ContactPointResult& c = out.contact[rc::kTread];
  ASSERT_TRUE(c.active);
  EXPECT_EQ(c.nu_x, 0.0);
  EXPECT_EQ(c.F_long, 0.0);
  EXPECT_FALSE(out.contact[rc::kFlange].searched);  // flange contact off: not run
  EXPECT_EQ(work.detection[rc::kFlange].calls, 0);
  // Standstill with a small slip velocity: finite (viscous) creep force.
  m.evaluate(leftWheel(0.0, -30e-6, 0.0, 0.01), rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(),
             work, out);
  EXPECT_TRUE(std::isfinite(out.contact[rc::kTread].F_long));
  EXPECT_NE(out.contact[rc::kTread].F_long, 0.0);
  // Lifted: zero load, nothing active, zero wrench.
  m.evaluate(leftWheel(0.0, 2e-3, 10.0, 10.0 / kR0), rc::RailSide::kLeft, setup().table.track(),
             rc::RigidRailDeformation(), work, out);
  EXPECT_FALSE(out.contact[rc::kTread].active);
  EXPECT_EQ(out.contact[rc::kTread].N, 0.0);
  EXPECT_EQ(out.wheel_centre.force_in_world.norm(), 0.0);
  EXPECT_NEAR(out.contact[rc::kTread].penetration, -2e-3, 1e-6);
  // Far off the rail and invalid input: flags, zeros, no throw.
  m.evaluate(leftWheel(0.5, 0.0, 10.0, 0.0), rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(),
             work, out);
  EXPECT_FALSE(out.contact[rc::kTread].active);
  EXPECT_TRUE(out.wheel_centre.moment_in_wheelset.allFinite());
  rc::WheelState bad = leftWheel(0.0, 0.0, 10.0, 0.0);
  bad.omega_wheelset_in_world.x() = std::numeric_limits<double>::infinity();
  m.evaluate(bad, rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(), work, out);
  EXPECT_EQ(out.contact[rc::kTread].status, rc::DetectionStatus::kInvalidInput);
  EXPECT_EQ(out.wheel_centre.force_in_world.norm(), 0.0);
}

TEST(WheelContact, OptionsAreValidated) {
  rc::WheelContactOptions o;
  o.friction = -0.1;
  EXPECT_THROW(rc::validate(o), std::runtime_error);
  o.friction = 0.3;
  o.damping.restitution = 1.5;
  EXPECT_THROW(rc::validate(o), std::runtime_error);
  o.damping.restitution = 0.5;
  EXPECT_NO_THROW(rc::validate(o));
  o.patch_dip = 1.0;
  try {
    rc::validate(o);
    ADD_FAILURE() << "patch_dip = 1 accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("patch_dip = 1 must be in [0, 1)"), std::string::npos) << e.what();
  }
  o.patch_dip = 0.1;
  o.detection.scan_skip_clearance = 2e-6;  // below patch_min_dip (5 um)
  try {
    rc::validate(o);
    ADD_FAILURE() << "scan_skip_clearance below patch_min_dip accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("detection.scan_skip_clearance = 2e-06 m must be 0 or above patch_min_dip"),
              std::string::npos)
        << e.what();
  }
  o.detection.scan_skip_clearance = 0.0;
  EXPECT_NO_THROW(rc::validate(o));
}
