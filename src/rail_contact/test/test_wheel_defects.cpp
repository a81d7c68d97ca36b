// Tests of the wheel defects (wheel_defects.hpp): the new flat's depth against the wheel's own outline
// rolled on a line (an independent construction), the rounded flat and out-of-roundness in closed form,
// slopes against central differences, and their effect on one wheel's contact (wheel_contact.hpp): the
// penetration and its rate as the wheel turns over a flat, other wheels untouched.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "rail_contact/contact_geometry_table.hpp"
#include "rail_contact/wheel_contact.hpp"
#include "rail_contact/wheel_defects.hpp"

namespace rc = rail::contact;
using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kR0 = 0.46;

rc::WheelDefect flat(std::uint32_t wheel, double length, double angle) {
  rc::WheelDefect d;
  d.shape = rc::WheelDefectShape::kFlat;
  d.wheel = wheel;
  d.length = length;
  d.angle = angle;
  return d;
}

// Lowest point of the wheel outline (circle of radius r with the chord of length L cut off, centred at
// angle 0 from -z) turned by psi: sampled on the arc and the chord, 200k points and the two edges.
double lowestPointDrop(double r, double L, double psi) {
  const double theta0 = std::asin(0.5 * L / r);
  double lowest = 0.0;  // depth of the lowest point below the centre
  const int n = 200000;
  for (int i = 0; i <= n + 2; ++i) {
    // material angle from the flat's centre
    const double t = i == n + 1 ? -theta0 : i == n + 2 ? theta0 : -kPi + 2.0 * kPi * i / n;
    double radius = r;
    if (std::abs(t) <= theta0) radius = r * std::cos(theta0) / std::cos(t);
    lowest = std::max(lowest, radius * std::cos(t + psi));  // height below the centre after the turn
  }
  return r - lowest;
}

}  // namespace

TEST(WheelDefects, NewFlatDepthIsTheDropOfTheRolledOutline) {
  const double L = 0.06;
  const rc::WheelDefects defects({flat(0, L, 0.0)}, kR0);
  const double theta0 = std::asin(0.5 * L / kR0);
  double depth = 0.0, slope = 0.0;
  defects.evaluate(0, 0.0, depth, slope);
  // The chord's sagitta, ~ L^2 / (8 r) for a short flat (0.978 mm here).
  EXPECT_NEAR(depth, kR0 - std::sqrt(kR0 * kR0 - 0.25 * L * L), 1e-15);
  EXPECT_NEAR(depth, L * L / (8.0 * kR0), 2e-3 * depth);
  EXPECT_DOUBLE_EQ(depth, rc::WheelDefects::newFlatDepth(L, kR0));
  // Against the outline sampled every 31 urad and at the edges (on the arc its error is ~ r (31e-6)^2 / 8 =
  // 6e-11 m; on the flat the lowest point is an edge, sampled exactly).
  for (double f : {-1.2, -0.9, -0.5, -0.1, 0.1, 0.3, 0.7, 0.99, 1.5}) {
    const double psi = f * theta0;
    defects.evaluate(0, psi, depth, slope);
    EXPECT_NEAR(depth, lowestPointDrop(kR0, L, psi), 1e-10) << "psi/theta0 = " << f;
  }
  // The edges: slope r sin(theta0) = L / 2 per radian on either side of the centre, pointing up the ramps.
  defects.evaluate(0, 1e-9, depth, slope);
  EXPECT_NEAR(slope, -0.5 * L, 1e-9);
  defects.evaluate(0, -1e-9, depth, slope);
  EXPECT_NEAR(slope, 0.5 * L, 1e-9);
}

TEST(WheelDefects, RoundedFlatOutOfRoundnessAndSlopes) {
  rc::WheelDefect rounded = flat(3, 0.1, 0.4);
  rounded.rounded = true;
  rounded.depth = 0.8e-3;
  rc::WheelDefect oor;
  oor.shape = rc::WheelDefectShape::kOutOfRound;
  oor.wheel = 3;
  oor.order = 3;
  oor.amplitude = 50e-6;
  oor.angle = 1.0;
  const rc::WheelDefects defects({rounded, oor, flat(5, 0.05, 0.0)}, kR0);
  const rc::WheelDefects only_oor({oor}, kR0);
  const rc::WheelDefects only_rounded({rounded}, kR0);
  double depth = 0.0, slope = 0.0;
  // Rounded: d at the centre, d/2 half-way (a quarter of the length), 0 at and beyond its ends.
  only_rounded.evaluate(3, 0.4, depth, slope);
  EXPECT_NEAR(depth, 0.8e-3, 1e-15);
  only_rounded.evaluate(3, 0.4 + 0.025 / kR0, depth, slope);
  EXPECT_NEAR(depth, 0.4e-3, 1e-12);
  only_rounded.evaluate(3, 0.4 - 0.05 / kR0 - 1e-9, depth, slope);
  EXPECT_EQ(depth, 0.0);
  // Out of round: A cos(n (beta - angle)), the same a revolution later.
  for (double beta : {-2.0, 0.0, 1.0, 2.5, 3.1}) {
    only_oor.evaluate(3, beta, depth, slope);
    EXPECT_NEAR(depth, 50e-6 * std::cos(3.0 * (beta - 1.0)), 1e-15);
    double later = 0.0;
    only_oor.evaluate(3, beta + 2.0 * kPi, later, slope);
    EXPECT_NEAR(later, depth, 1e-15);
  }
  // A wheel's defects add up; slopes match central differences (h = 1e-7 rad).
  for (double beta = -3.0; beta < 3.0; beta += 0.0371) {
    double a = 0.0, b = 0.0, sa = 0.0, sb = 0.0, sum = 0.0;
    only_oor.evaluate(3, beta, a, sa);
    only_rounded.evaluate(3, beta, b, sb);
    defects.evaluate(3, beta, sum, slope);
    EXPECT_NEAR(sum, a + b, 1e-15);
    double lo = 0.0, hi = 0.0, unused = 0.0;
    const double h = 1e-7;
    defects.evaluate(3, beta - h, lo, unused);
    defects.evaluate(3, beta + h, hi, unused);
    EXPECT_NEAR(slope, (hi - lo) / (2.0 * h), 1e-8) << "beta = " << beta;
  }
  // Other wheels: nothing (wheel 4 between two with defects, 9 past the last).
  for (std::uint32_t w : {0u, 4u, 9u}) {
    defects.evaluate(w, 0.0, depth, slope);
    EXPECT_EQ(depth, 0.0);
    EXPECT_EQ(slope, 0.0);
  }
  EXPECT_NEAR(rc::WheelDefects::roundedFlatMaxDepth(0.1, kR0), 0.01 / (2.0 * kPi * kPi * kR0), 1e-18);
}

namespace {

struct Setup {
  rc::WheelProfile wheel = rc::makeS1002();
  rc::ProfileCurve rail = rc::makeUic60Rail(1.0 / 40.0);
  rc::WheelsetTrackSpec spec;
  rc::ContactGeometryTable table{wheel, rail, spec};
  double z0 = table.row(0.0).z;
};
Setup& setup() {
  static Setup s;
  return s;
}

// The left wheel, 100 um into the rail, turned by alpha about its axle, spinning at omega.
rc::WheelState turnedWheel(std::uint32_t id, double alpha, double omega) {
  rc::WheelState w;
  w.id = id;
  w.p_wheel_in_world = Vector3d(10.0, setup().table.wheelHalfDistance(), setup().z0 - 100e-6);
  w.R_wheelset_to_world = Eigen::AngleAxisd(alpha, Vector3d::UnitY()).toRotationMatrix();
  w.v_wheel_in_world = Vector3d(omega * kR0, 0.0, 0.0);
  w.omega_wheelset_in_world = Vector3d(0.0, omega, 0.0);
  w.arc_length = 10.0;
  return w;
}

rc::WheelContactModel model(const rc::WheelDefects& defects) {
  rc::WheelContactOptions o;
  o.wheel_defects = defects;
  return rc::WheelContactModel(setup().wheel, kR0, setup().rail, Eigen::Vector2d(0.0, -0.09), o);
}

}  // namespace

TEST(WheelDefects, AFlatTurnsWithTheWheelAndLowersItsContact) {
  // A 40 mm new flat (depth 0.43 mm) on the left wheel of wheelset 0; the wheel 100 um into the rail.
  const double L = 0.04;
  const rc::WheelDefects defects({flat(0, L, 0.0)}, kR0);
  const rc::WheelContactModel round = model(rc::WheelDefects());
  const rc::WheelContactModel flatted = model(defects);
  const double omega = 60.0;  // rad/s, 99 km/h
  const double theta0 = std::asin(0.5 * L / kR0);
  for (double alpha : {-1.5 * theta0, -0.6 * theta0, -0.2 * theta0, 0.3 * theta0, 0.8 * theta0, 2.0}) {
    rc::WheelContactWork wa, wb;
    rc::WheelContactResult a, b;
    round.evaluate(turnedWheel(0, alpha, omega), rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(),
                   wa, a);
    flatted.evaluate(turnedWheel(0, alpha, omega), rc::RailSide::kLeft, setup().table.track(),
                     rc::RigidRailDeformation(), wb, b);
    const rc::ContactPointResult& ca = a.contact[rc::kTread];
    const rc::ContactPointResult& cb = b.contact[rc::kTread];
    ASSERT_TRUE(ca.active);
    // The contact is below the centre, so turned by alpha the flat's centre is alpha from the contact; the
    // depth counts along the contact normal, at most 0.03 rad off the radius on the tread (1 - cos < 5e-4).
    double depth = 0.0, slope = 0.0;
    defects.evaluate(0, alpha, depth, slope);
    EXPECT_NEAR(ca.penetration - cb.penetration, depth, 5e-4 * depth + 1e-15) << "alpha = " << alpha;
    EXPECT_EQ(cb.active, cb.penetration > 0.0);
    if (depth == 0.0) {
      EXPECT_EQ(ca.N, cb.N);
    }
    // The rate against the penetration's change over a turn of +-1e-6 rad (time 1e-6 / omega).
    if (std::abs(std::abs(alpha) - theta0) > 1e-3 && std::abs(alpha) > 1e-3) {
      const double h = 1e-6;
      rc::WheelContactWork w1, w2;
      rc::WheelContactResult r1, r2;
      flatted.evaluate(turnedWheel(0, alpha - h, omega), rc::RailSide::kLeft, setup().table.track(),
                       rc::RigidRailDeformation(), w1, r1);
      flatted.evaluate(turnedWheel(0, alpha + h, omega), rc::RailSide::kLeft, setup().table.track(),
                       rc::RigidRailDeformation(), w2, r2);
      const double rate = (r2.contact[rc::kTread].penetration - r1.contact[rc::kTread].penetration) / (2.0 * h / omega);
      EXPECT_NEAR(cb.penetration_rate, rate, 1e-3 * std::max(1.0, std::abs(rate))) << "alpha = " << alpha;
    }
    // The right-hand wheel of the same wheelset (id 1) has no defect: bitwise the round wheel's result.
    rc::WheelContactWork wc, wd;
    rc::WheelContactResult c, d;
    round.evaluate(turnedWheel(1, alpha, omega), rc::RailSide::kLeft, setup().table.track(), rc::RigidRailDeformation(),
                   wc, c);
    flatted.evaluate(turnedWheel(1, alpha, omega), rc::RailSide::kLeft, setup().table.track(),
                     rc::RigidRailDeformation(), wd, d);
    EXPECT_EQ(c.contact[rc::kTread].penetration, d.contact[rc::kTread].penetration);
    EXPECT_EQ(c.contact[rc::kTread].N, d.contact[rc::kTread].N);
    EXPECT_EQ(c.contact[rc::kTread].penetration_rate, d.contact[rc::kTread].penetration_rate);
  }
}
