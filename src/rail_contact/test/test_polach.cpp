// Tests of Kalker's coefficient table, Polach's creep force method and the creepages.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>

#include "rail_contact/creepage.hpp"
#include "rail_contact/hertz.hpp"
#include "rail_contact/kalker.hpp"
#include "rail_contact/polach.hpp"

namespace rc = rail::contact;

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string dataFile() {
  const std::string here = __FILE__;  // .../rail_contact/test/test_polach.cpp
  return here.substr(0, here.rfind("/test/")) + "/data/kalker_coefficients.csv";
}

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

std::string loadError(const std::string& path) {
  try {
    rc::KalkerTable::load(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

/// Typical wheel-on-rail tread contact used in the Polach tests (SI units).
rc::PolachInput treadContact() {
  rc::PolachInput in;
  in.N = 100.0e3;
  in.a = 7.0e-3;
  in.b = 5.0e-3;
  in.G = rc::combinedShearModulus(rc::ElasticMaterial{}, rc::ElasticMaterial{});
  in.mu0 = 0.4;
  in.V = 20.0;
  in.c = rc::KalkerTable::builtin().evaluate(in.a / in.b, 0.3);
  return in;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Kalker table

// The compiled-in table and the data file carry the same numbers, digit for digit.
TEST(KalkerTable, BuiltinEqualsDataFile) {
  const rc::KalkerTable file = rc::KalkerTable::load(dataFile());
  const rc::KalkerTable& builtin = rc::KalkerTable::builtin();
  ASSERT_EQ(file.rows().size(), 19u);
  ASSERT_EQ(builtin.rows().size(), file.rows().size());
  for (std::size_t k = 0; k < file.rows().size(); ++k) {
    EXPECT_EQ(file.rows()[k].a_over_b, builtin.rows()[k].a_over_b);
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 3; ++i) EXPECT_EQ(file.rows()[k].c[j][i], builtin.rows()[k].c[j][i]);
  }
}

// Interpolation returns tabulated values exactly at every tabulated (a/b, nu).
TEST(KalkerTable, HitsTabulatedValuesExactly) {
  const rc::KalkerTable& t = rc::KalkerTable::builtin();
  for (const auto& row : t.rows())
    for (int i = 0; i < 3; ++i) {
      const rc::KalkerCoefficients c = t.evaluate(row.a_over_b, rc::KalkerTable::kPoisson[i]);
      EXPECT_EQ(c.c11, row.c[0][i]);
      EXPECT_EQ(c.c22, row.c[1][i]);
      EXPECT_EQ(c.c23, row.c[2][i]);
      EXPECT_EQ(c.c33, row.c[3][i]);
      EXPECT_EQ(c.flags, 0u);
    }
  // Spot values typed from Kalker 1990 Table E.3 (circle, nu = 0.25; a/b = 0.5, nu = 0.5).
  rc::KalkerCoefficients c = t.evaluate(1.0, 0.25);
  EXPECT_EQ(c.c11, 4.12);
  EXPECT_EQ(c.c22, 3.67);
  EXPECT_EQ(c.c23, 1.47);
  EXPECT_EQ(c.c33, 1.19);
  c = t.evaluate(0.5, 0.5);
  EXPECT_EQ(c.c11, 4.83);
  EXPECT_EQ(c.c33, 2.22);
}

// Between nodes: linear in g at a tabulated nu (midpoint = mean), quadratic through the three
// nu values at a tabulated a/b (a quadratic is reproduced exactly). 1e-14: rounding only.
TEST(KalkerTable, InterpolationIsLinearInRatioAndQuadraticInNu) {
  const rc::KalkerTable& t = rc::KalkerTable::builtin();
  const rc::KalkerCoefficients mid = t.evaluate(0.55, 0.25);
  EXPECT_NEAR(mid.c11, 0.5 * (3.62 + 3.72), 1e-14);
  // b/a branch: a/b = 1/0.55 lies midway between b/a = 0.5 and 0.6.
  const rc::KalkerCoefficients mid2 = t.evaluate(1.0 / 0.55, 0.0);
  EXPECT_NEAR(mid2.c23, 0.5 * (2.35 + 2.01), 1e-14);
  // Lagrange quadratic through (0, 3.40), (0.25, 4.12), (0.5, 5.20) evaluated at nu = 0.3.
  const double nu = 0.3;
  const double expect =
      3.40 * (nu - 0.25) * (nu - 0.5) / 0.125 - 4.12 * nu * (nu - 0.5) / 0.0625 + 5.20 * nu * (nu - 0.25) / 0.125;
  EXPECT_NEAR(t.evaluate(1.0, nu).c11, expect, 1e-14);
}

// Known limits of the linear theory (Kalker 1990, Appendix E, asymptotic expressions):
//  a/b -> 0: c11 -> pi^2 / (4 (1 - nu)), c22 -> pi^2 / 4, and from strip theory
//            c33 -> pi^2 / (16 (1 - nu) g) with g = a/b;
//  b/a -> 0: c11 -> 2 pi / ((L - 2 nu) g) (1 + (3 - ln 4) / (L - 2 nu)), L = ln(16 / g^2).
// At the table end g = 0.1 the neglected higher-order terms are O(g ln g), so the first end is
// accepted within 3% (c11, c22) and 6% (c33), the second within 5%.
TEST(KalkerTable, TableEndsApproachAsymptotes) {
  const rc::KalkerTable& t = rc::KalkerTable::builtin();
  const double g = 0.1;
  for (double nu : {0.0, 0.25, 0.5}) {
    const rc::KalkerCoefficients c = t.evaluate(g, nu);
    const double c11 = kPi * kPi / (4.0 * (1.0 - nu));
    const double c22 = kPi * kPi / 4.0;
    const double c33 = kPi * kPi / (16.0 * (1.0 - nu) * g);
    EXPECT_NEAR(c.c11, c11, 0.03 * c11) << "nu=" << nu;
    EXPECT_NEAR(c.c22, c22, 0.03 * c22) << "nu=" << nu;
    EXPECT_NEAR(c.c33, c33, 0.06 * c33) << "nu=" << nu;
    const rc::KalkerCoefficients d = t.evaluate(1.0 / g, nu);
    const double L = std::log(16.0 / (g * g)) - 2.0 * nu;
    const double c11_long = 2.0 * kPi / (L * g) * (1.0 + (3.0 - std::log(4.0)) / L);
    EXPECT_NEAR(d.c11, c11_long, 0.05 * c11_long) << "nu=" << nu;
  }
  // c22 = c11 at nu = 0 (Kalker: the two coincide for nu = 0) - holds for every row.
  for (const auto& row : t.rows()) EXPECT_EQ(row.c[0][0], row.c[1][0]);
}

TEST(KalkerTable, OutOfRangeIsClampedAndFlagged) {
  const rc::KalkerTable& t = rc::KalkerTable::builtin();
  rc::KalkerCoefficients c = t.evaluate(0.01, 0.3);
  EXPECT_TRUE(c.flags & rc::kKalkerAxisRatioClamped);
  EXPECT_DOUBLE_EQ(c.c11, t.evaluate(0.1, 0.3).c11);
  c = t.evaluate(50.0, 0.7);
  EXPECT_TRUE(c.flags & rc::kKalkerAxisRatioClamped);
  EXPECT_TRUE(c.flags & rc::kKalkerPoissonClamped);
  c = t.evaluate(std::nan(""), std::nan(""));
  EXPECT_TRUE(c.flags & rc::kKalkerBadInput);
  EXPECT_TRUE(std::isfinite(c.c11) && std::isfinite(c.c33));
}

TEST(KalkerTable, LoaderReportsFileAndLine) {
  const std::string header =
      "# comment\nkind,g,c11_nu0,c11_nu025,c11_nu05,c22_nu0,c22_nu025,c22_nu05,"
      "c23_nu0,c23_nu025,c23_nu05,c33_nu0,c33_nu025,c33_nu05\n";
  const std::string good1 = "a/b,0.1,2.51,3.31,4.85,2.51,2.52,2.53,0.334,0.473,0.731,6.42,8.28,11.7\n";
  const std::string good2 = "a/b,0.2,2.59,3.37,4.81,2.59,2.63,2.66,0.483,0.603,0.809,3.46,4.27,5.66\n";
  std::string p = writeTemp(
      "k_bad_number.csv", header + good1 + "a/b,0.2,2.59,x3.37,4.81,2.59,2.63,2.66,0.483,0.603,0.809,3.46,4.27,5.66\n");
  std::string msg = loadError(p);
  EXPECT_NE(msg.find(p + ":4:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("c11_nu025"), std::string::npos) << msg;
  p = writeTemp("k_order.csv", header + good2 + good1);
  msg = loadError(p);
  EXPECT_NE(msg.find(p + ":4: a/b not increasing (0.1 after 0.2)"), std::string::npos) << msg;
  p = writeTemp("k_fields.csv", header + good1 + "a/b,0.2,2.59\n");
  msg = loadError(p);
  EXPECT_NE(msg.find(p + ":4: expected 14"), std::string::npos) << msg;
  p = writeTemp("k_kind.csv", header + good1 + "x/y" + good2.substr(3));
  msg = loadError(p);
  EXPECT_NE(msg.find(p + ":4: kind"), std::string::npos) << msg;
  p = writeTemp("k_neg.csv",
                header + good1 + "a/b,0.2,2.59,3.37,4.81,2.59,2.63,2.66,0.483,0.603,0.809,3.46,4.27,-5.66\n");
  msg = loadError(p);
  EXPECT_NE(msg.find(p + ":4: c33_nu05 must be > 0 (got -5.66)"), std::string::npos) << msg;
  msg = loadError("/nonexistent/kalker.csv");
  EXPECT_NE(msg.find("/nonexistent/kalker.csv"), std::string::npos) << msg;
}

// ---------------------------------------------------------------------------------------------
// Polach

// Small creepage: Polach's law reduces to Kalker's linear theory
//   Fx = -G a b c11 nu_x, Fy = -G a b c22 nu_y - G (ab)^1.5 c23 phi
// (the method is built on it: F ~ (4 mu N/pi) eps for eps -> 0). At nu = 1e-5 the relative
// deviation is O(eps^2) ~ 1e-6; the required tolerance is 1%.
TEST(Polach, SmallCreepageTendsToKalkerLinearLaw) {
  const rc::PolachOptions opt;  // kA = kS = 1, constant friction
  rc::PolachInput in = treadContact();
  const double Gab = in.G * in.a * in.b;
  in.nu_x = 1e-5;
  rc::PolachResult r = rc::polachForces(in, opt);
  EXPECT_NEAR(r.Fx, -Gab * in.c.c11 * in.nu_x, 0.01 * Gab * in.c.c11 * in.nu_x);
  EXPECT_NEAR(r.Fy, 0.0, 1e-12);
  in.nu_x = 0.0;
  in.nu_y = -1e-5;
  r = rc::polachForces(in, opt);
  EXPECT_NEAR(r.Fy, -Gab * in.c.c22 * in.nu_y, 0.01 * Gab * in.c.c22 * 1e-5);
  in.nu_y = 0.0;
  in.phi = 1e-5 / in.a;  // spin creepage [1/m] giving phi * a = 1e-5
  r = rc::polachForces(in, opt);
  const double Fy_lin = -Gab * std::sqrt(in.a * in.b) * in.c.c23 * in.phi;
  EXPECT_NEAR(r.Fy, Fy_lin, 0.01 * std::abs(Fy_lin));
  EXPECT_NEAR(r.Fy_spin, r.Fy, 1e-12 * std::abs(Fy_lin));
}

// Large creepage: the force saturates at the friction limit |F| -> mu N. With nu = 1 here
// eps ~ 4e2 and the analytic deficit is (2/pi)(1/eps - 1/eps) ~ 1e-6, so 1e-3 is ample.
TEST(Polach, LargeCreepageSaturatesAtMuN) {
  rc::PolachOptions opt;
  opt.spin = false;
  rc::PolachInput in = treadContact();
  for (double s : {1.0, -1.0}) {
    in.nu_x = s;
    const rc::PolachResult r = rc::polachForces(in, opt);
    EXPECT_NEAR(std::abs(r.Fx), in.mu0 * in.N, 1e-3 * in.mu0 * in.N);
    EXPECT_LT(r.Fx * s, 0.0);  // opposes the creepage
  }
  in.nu_x = 0.6;
  in.nu_y = 0.8;
  const rc::PolachResult r = rc::polachForces(in, opt);
  EXPECT_NEAR(std::hypot(r.Fx, r.Fy), in.mu0 * in.N, 1e-3 * in.mu0 * in.N);
}

// Closed-form point of Polach's function: at eps = 1, F = 2 mu N / pi (1/2 + pi/4)
// = mu N (1/pi + 1/2). Tolerance 1e-12 relative (analytic value, rounding only).
TEST(Polach, ClosedFormAtUnitEpsilon) {
  rc::PolachOptions opt;
  opt.spin = false;
  rc::PolachInput in = treadContact();
  in.c.c11 = in.c.c22 = 4.0;
  in.nu_x = 4.0 * in.mu0 * in.N / (in.G * kPi * in.a * in.b * in.c.c11);  // gives eps = 1
  const rc::PolachResult r = rc::polachForces(in, opt);
  EXPECT_NEAR(r.epsilon, 1.0, 1e-14);
  EXPECT_NEAR(-r.Fx, in.mu0 * in.N * (1.0 / kPi + 0.5), 1e-12 * in.mu0 * in.N);
}

// Reduction factors: initial slope is (kA + kS)/2 times Kalker's (expansion of
// kA eps/(1+kA^2 eps^2) + atan(kS eps) at eps -> 0). Tolerance 1e-4 covers O(eps^2).
TEST(Polach, ReductionFactorsScaleInitialSlope) {
  rc::PolachOptions opt;
  opt.spin = false;
  opt.kA = 0.3;
  opt.kS = 0.1;
  rc::PolachInput in = treadContact();
  in.nu_x = 1e-7;
  const rc::PolachResult r = rc::polachForces(in, opt);
  const double lin = in.G * in.a * in.b * in.c.c11 * in.nu_x * 0.5 * (opt.kA + opt.kS);
  EXPECT_NEAR(-r.Fx, lin, 1e-4 * lin);
}

// Falling friction: mu = mu0 [(1 - A) exp(-B w) + A]; at large slip velocity the creep force
// tends to A mu0 N (Polach 2005). Dry parameter set, nu = 20 at V = 20 m/s: w = 400 m/s and
// exp(-B w) = exp(-240) ~ 0. For eps -> inf Polach's function approaches 1 as
// 1 - (2/pi)(1/kS - 1/kA)/eps, i.e. a deficit of ~1e-4 at eps ~ 9e3, so 1e-3 relative.
TEST(Polach, FallingFrictionLimit) {
  const rc::PolachOptions opt = rc::polach2005DryOptions();
  rc::PolachInput in = treadContact();
  in.mu0 = rc::kPolach2005DryMu0;
  in.nu_x = 20.0;
  const rc::PolachResult r = rc::polachForces(in, opt);
  EXPECT_NEAR(r.mu, opt.A * in.mu0, 1e-12);
  EXPECT_NEAR(-r.Fx, opt.A * in.mu0 * in.N, 1e-3 * opt.A * in.mu0 * in.N);
}

// Shape of the creep force-creepage curve with Polach's 2005 parameter sets (dry and wet):
// as in the paper's curves for traction vehicles, the force rises linearly, reaches a
// maximum (adhesion optimum) below mu0 N and above A mu0 N, then falls while the friction
// coefficient falls with the slip velocity. (Beyond nu ~ 0.5 at 20 m/s, where mu has settled
// at A mu0, the model rises again by O(1/eps) towards A mu0 N; the sweep stops at 0.3.)
// The wet curve lies below the dry curve at every creepage.
TEST(Polach, CurveWithFallingFrictionHasAdhesionOptimum) {
  for (int wet = 0; wet < 2; ++wet) {
    const rc::PolachOptions opt = wet ? rc::polach2005WetOptions() : rc::polach2005DryOptions();
    rc::PolachInput in = treadContact();
    in.mu0 = wet ? rc::kPolach2005WetMu0 : rc::kPolach2005DryMu0;
    double F_max = 0.0, s_max = 0.0, prev = 0.0;
    bool falling = false, rose_after_fall = false;
    for (int i = 1; i <= 4000; ++i) {
      in.nu_x = 1e-5 * std::pow(3.0e4, i / 4000.0);  // 1e-5 .. 0.3
      const double F = -rc::polachForces(in, opt).Fx;
      if (F > F_max) {
        F_max = F;
        s_max = in.nu_x;
      }
      if (F < prev)
        falling = true;
      else if (falling && F > prev)
        rose_after_fall = true;
      prev = F;
    }
    EXPECT_LT(F_max, in.mu0 * in.N);
    EXPECT_GT(F_max, opt.A * in.mu0 * in.N);
    EXPECT_GT(s_max, 1e-3);
    EXPECT_LT(s_max, 0.2);
    EXPECT_TRUE(falling);
    EXPECT_FALSE(rose_after_fall);
    EXPECT_LT(prev, 0.85 * F_max);
  }
  rc::PolachInput dry = treadContact(), wet = treadContact();
  dry.mu0 = rc::kPolach2005DryMu0;
  wet.mu0 = rc::kPolach2005WetMu0;
  for (double s : {1e-4, 1e-3, 1e-2, 1e-1, 1.0}) {
    dry.nu_x = wet.nu_x = s;
    EXPECT_LT(-rc::polachForces(wet, rc::polach2005WetOptions()).Fx,
              -rc::polachForces(dry, rc::polach2005DryOptions()).Fx);
  }
}

// Zero creepage gives zero, finite forces (no division by zero), with and without spin;
// zero or negative normal load gives zero forces.
TEST(Polach, FiniteAtZeroCreepageAndNoLoad) {
  rc::PolachInput in = treadContact();
  for (bool spin : {true, false}) {
    rc::PolachOptions opt;
    opt.spin = spin;
    const rc::PolachResult r = rc::polachForces(in, opt);
    EXPECT_EQ(r.Fx, 0.0);
    EXPECT_EQ(r.Fy, 0.0);
    EXPECT_TRUE(std::isfinite(r.mu));
  }
  in.nu_x = 0.01;
  in.N = 0.0;
  const rc::PolachResult r = rc::polachForces(in, rc::PolachOptions{});
  EXPECT_EQ(r.Fx, 0.0);
  EXPECT_EQ(r.Fy, 0.0);
}

// Spin off: spin terms are not computed; nu_C equals the translational creepage.
// Spin on: nu_C uses the shifted lateral creepage only when it increases |nu_y| (Polach 1999).
TEST(Polach, SpinSwitchAndModifiedCreepage) {
  rc::PolachInput in = treadContact();
  in.nu_x = 1e-3;
  in.nu_y = 2e-3;
  in.phi = 0.5;  // 1/m, phi a = 3.5e-3
  rc::PolachOptions off;
  off.spin = false;
  rc::PolachResult r = rc::polachForces(in, off);
  EXPECT_EQ(r.Fy_spin, 0.0);
  EXPECT_DOUBLE_EQ(r.nu_C, std::hypot(1e-3, 2e-3));
  r = rc::polachForces(in, rc::PolachOptions{});
  EXPECT_DOUBLE_EQ(r.nu_C, std::hypot(1e-3, 2e-3 + 0.5 * in.a));
  EXPECT_LT(r.Fy_spin, 0.0);
  in.phi = -0.1;  // |nu_y + phi a| = 1.3e-3 < |nu_y|: no shift
  r = rc::polachForces(in, rc::PolachOptions{});
  EXPECT_DOUBLE_EQ(r.nu_C, std::hypot(1e-3, 2e-3));
  EXPECT_GT(r.Fy_spin, 0.0);
}

// Pure large spin in full sliding gives no net lateral force (a rotation of the slip field
// about the contact centre has zero resultant), so Polach's F_yS must rise and then decay
// towards zero: at phi a = 1 it is below 1% of its maximum over the sweep.
TEST(Polach, PureSpinForceDecaysInFullSliding) {
  rc::PolachInput in = treadContact();
  double F_peak = 0.0, F_last = 0.0;
  for (int i = 0; i <= 600; ++i) {
    in.phi = 1e-6 * std::pow(10.0, 6.0 * i / 600.0) / in.a;  // phi a from 1e-6 to 1
    const rc::PolachResult r = rc::polachForces(in, rc::PolachOptions{});
    EXPECT_TRUE(std::isfinite(r.Fy));
    F_peak = std::max(F_peak, std::abs(r.Fy));
    F_last = std::abs(r.Fy);
  }
  EXPECT_GT(F_peak, 0.0);
  EXPECT_LT(F_last, 0.01 * F_peak);
  EXPECT_LT(F_peak, in.mu0 * in.N);
}

TEST(Polach, OptionValidation) {
  rc::PolachOptions o;
  o.kA = 0.0;
  EXPECT_THROW(rc::validate(o), std::runtime_error);
  o = {};
  o.B = -1.0;
  EXPECT_THROW(rc::validate(o), std::runtime_error);
  EXPECT_NO_THROW(rc::validate(rc::polach2005DryOptions()));
  EXPECT_NO_THROW(rc::validate(rc::polach2005WetOptions()));
}

// ---------------------------------------------------------------------------------------------
// Creepages

// World-frame overload: rotating the velocities into the contact frame gives the same result
// as the contact-frame overload (1e-15: rounding). Above v_eps the creepages approach the
// plain definitions v_rel / V.
TEST(Creepage, DefinitionAndFrames) {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized())).toRotationMatrix();
  const Eigen::Vector3d v_rel_c(0.02, -0.01, 0.0);
  const double w_rel_n = 0.4;
  const Eigen::Vector3d v_rail(1.0, -2.0, 0.5);
  const Eigen::Vector3d w_rail(0.1, 0.2, 0.3);
  const Eigen::Vector3d w_wheel = w_rail + R.col(2) * w_rel_n + R.col(0) * 7.0;  // + rolling spin
  rc::CreepageOptions opt;
  opt.mode = rc::SpeedRegularisation::kMax;
  const rc::Creepages a = rc::computeCreepages(v_rel_c, w_rel_n, 30.0, opt);
  const rc::Creepages b = rc::computeCreepages(v_rail + R * v_rel_c, v_rail, w_wheel, w_rail, R, 30.0, opt);
  EXPECT_NEAR(a.nu_x, 0.02 / 30.0, 1e-15);
  EXPECT_NEAR(a.nu_y, -0.01 / 30.0, 1e-15);
  EXPECT_NEAR(a.phi, 0.4 / 30.0, 1e-15);
  EXPECT_NEAR(b.nu_x, a.nu_x, 1e-15);
  EXPECT_NEAR(b.nu_y, a.nu_y, 1e-15);
  EXPECT_NEAR(b.phi, a.phi, 1e-14);
  // Smooth regularisation: V_ref = sqrt(V^2 + v_eps^2), relative change (v_eps/V)^2/2 ~ 5.6e-6.
  const rc::Creepages s = rc::computeCreepages(v_rel_c, w_rel_n, 30.0, rc::CreepageOptions{});
  EXPECT_NEAR(s.V_ref, std::sqrt(900.0 + 0.01), 1e-12);
}

// Standstill: finite creepages and forces.
TEST(Creepage, StandstillIsFinite) {
  for (auto mode : {rc::SpeedRegularisation::kSmooth, rc::SpeedRegularisation::kMax}) {
    rc::CreepageOptions opt;
    opt.mode = mode;
    const rc::Creepages c = rc::computeCreepages(Eigen::Vector3d(1e-3, 0, 0), 0.01, 0.0, opt);
    EXPECT_DOUBLE_EQ(c.V_ref, opt.v_eps);
    EXPECT_DOUBLE_EQ(c.nu_x, 1e-3 / opt.v_eps);
    rc::PolachInput in = treadContact();
    in.nu_x = c.nu_x;
    in.phi = c.phi;
    in.V = c.V_ref;
    const rc::PolachResult r = rc::polachForces(in, rc::PolachOptions{});
    EXPECT_TRUE(std::isfinite(r.Fx) && std::isfinite(r.Fy));
  }
  const rc::Creepages n = rc::computeCreepages(Eigen::Vector3d(1, 1, 1), 1.0, std::nan(""), rc::CreepageOptions{});
  EXPECT_TRUE(std::isfinite(n.nu_x) && std::isfinite(n.phi));
}
