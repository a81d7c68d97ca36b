// Tests of the Hertz contact solution and the damped normal force (paper eq. 9).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "rail_contact/hertz.hpp"
#include "rail_contact/illinois.hpp"

namespace rc = rail::contact;

namespace {

constexpr double kPi = 3.14159265358979323846;

double steelEStar() {
  const rc::ElasticMaterial steel;  // E = 210 GPa, nu = 0.3
  return rc::contactModulus(steel, steel);
}

/// Normal surface displacement (sum of both bodies) at (x0, y0) produced by the Hertz pressure
/// p = p0 sqrt(1 - x^2/a^2 - y^2/b^2) acting on an elastic half-space (Boussinesq):
///   u(P) = 1/(pi E*) * integral p / |P - Q| dQ   (Johnson, Contact Mechanics, eq. 3.20 ff.).
/// Polar coordinates centred at P cancel the 1/r singularity; the radial integral of the
/// square root of a quadratic is done in closed form, the angular one by the trapezoidal rule
/// (spectrally accurate for a smooth periodic integrand). Independent of the library.
double boussinesqDisplacement(double a, double b, double p0, double E_star, double x0, double y0) {
  const int n = 4096;
  double sum = 0.0;
  for (int k = 0; k < n; ++k) {
    const double th = 2.0 * kPi * k / n;
    const double c = std::cos(th), s = std::sin(th);
    const double alpha = c * c / (a * a) + s * s / (b * b);
    const double beta = x0 * c / (a * a) + y0 * s / (b * b);
    const double q0 = x0 * x0 / (a * a) + y0 * y0 / (b * b);
    // 1 - Q(rho) = alpha (h^2 - (rho - m)^2), m = -beta/alpha
    const double m = -beta / alpha;
    const double h2 = (beta * beta - alpha * (q0 - 1.0)) / (alpha * alpha);
    const double h = std::sqrt(h2);
    const double t0 = -m;  // rho = 0
    const double integral = 0.25 * kPi * h2 - 0.5 * (t0 * std::sqrt(h2 - t0 * t0) + h2 * std::asin(t0 / h));
    sum += p0 * std::sqrt(alpha) * integral;
  }
  return sum * (2.0 * kPi / n) / (kPi * E_star);
}

}  // namespace

// Two equal spheres (A = B, circular contact) against the closed form
// a = (3 N R / (4 E*))^(1/3), delta = a^2 / R, K = 4/3 E* sqrt(R) with 1/R = 1/R1 + 1/R2
// (Johnson, Contact Mechanics, eqs. 4.22-4.23). Tolerance 1e-12 relative: same closed form,
// only rounding differs.
TEST(Hertz, EqualSpheresMatchClosedForm) {
  const double R1 = 0.05, N = 1000.0;
  const double E_star = steelEStar();
  rc::PrincipalCurvatures k;
  k.wheel_rolling = k.wheel_lateral = 1.0 / R1;
  k.rail_rolling = k.rail_lateral = 1.0 / R1;
  const rc::HertzGeometry g = rc::computeHertz(k, E_star);
  const double R = R1 / 2.0;
  const double a = std::cbrt(3.0 * N * R / (4.0 * E_star));
  EXPECT_TRUE(g.flags & rc::kHertzCircular);
  EXPECT_NEAR(g.a(N), a, 1e-12 * a);
  EXPECT_NEAR(g.b(N), a, 1e-12 * a);
  EXPECT_NEAR(g.approach(N), a * a / R, 1e-12 * a * a / R);
  EXPECT_NEAR(g.K, 4.0 / 3.0 * E_star * std::sqrt(R), 1e-12 * g.K);
}

// Two equal cylinders crossed at right angles: A = B = 1/(2 R1), equivalent sphere R = R1.
TEST(Hertz, CrossedCylindersMatchClosedForm) {
  const double R1 = 0.46, N = 80.0e3;
  const double E_star = steelEStar();
  rc::PrincipalCurvatures k;
  k.wheel_rolling = 1.0 / R1;  // wheel: cylinder along lateral axis
  k.rail_lateral = 1.0 / R1;   // rail: cylinder along track
  const rc::HertzGeometry g = rc::computeHertz(k, E_star);
  const double a = std::cbrt(3.0 * N * R1 / (4.0 * E_star));
  EXPECT_NEAR(g.a(N), a, 1e-12 * a);
  EXPECT_NEAR(g.b(N), a, 1e-12 * a);
  EXPECT_NEAR(g.approach(N), a * a / R1, 1e-12 * a * a / R1);
  EXPECT_NEAR(g.load(g.approach(N)), N, 1e-10 * N);
}

// a, b scale with N^(1/3), delta with N^(2/3), and N = K delta^1.5 (Hertz). 1e-13: rounding.
TEST(Hertz, LoadScaling) {
  const rc::HertzGeometry g = rc::computeHertz(1.0 / (2 * 0.46), 1.0 / (2 * 0.3), steelEStar());
  const double N = 50.0e3;
  EXPECT_NEAR(g.a(8 * N), 2 * g.a(N), 1e-13 * g.a(N));
  EXPECT_NEAR(g.b(8 * N), 2 * g.b(N), 1e-13 * g.b(N));
  EXPECT_NEAR(g.approach(8 * N), 4 * g.approach(N), 1e-13 * g.approach(N));
  for (double n : {1.0, 1.0e3, 1.0e5}) EXPECT_NEAR(g.load(g.approach(n)), n, 1e-10 * n);
  EXPECT_EQ(g.a(0.0), 0.0);
  EXPECT_EQ(g.approach(-1.0), 0.0);
  EXPECT_EQ(g.load(-1e-6), 0.0);
}

// Elliptic contacts: the Hertz solution (a, b, delta) must make the Boussinesq displacement
// of the Hertz pressure equal delta - A x^2 - B y^2 everywhere inside the ellipse (this is the
// definition of the Hertz solution). The check integrates the half-space solution numerically,
// independently of the eccentricity equation and elliptic integrals in the library.
// Tolerance 1e-10 relative to delta: the quadrature agrees to ~1e-14; 1e-10 leaves margin
// while still catching any error in e, K(e), E(e) (an error of 1e-6 in e moves delta ~1e-6).
TEST(Hertz, EllipticMatchesBoussinesqIntegral) {
  const double E_star = steelEStar();
  const double N = 100.0e3;
  struct Case {
    double A, B;
  };
  const Case cases[] = {
      {1.0 / (2 * 0.46), 1.0 / (2 * 0.30)},  // wheel on rail head: a > b
      {1.0 / (2 * 0.46), 1.0 / (2 * 0.60)},  // A > B: major axis lateral
      {0.5, 20.0},                           // curvature ratio 40
      {2.0, 2.0 * (1 + 1e-7)},               // near-circular branch
  };
  for (const Case& c : cases) {
    const rc::HertzGeometry g = rc::computeHertz(c.A, c.B, E_star);
    const double a = g.a(N), b = g.b(N), delta = g.approach(N);
    const double p0 = 3.0 * N / (2.0 * kPi * a * b);
    const double pts[][2] = {{0, 0}, {0.5, 0}, {0, 0.7}, {0.3, -0.4}, {-0.6, 0.5}};
    for (const auto& p : pts) {
      const double x = p[0] * a, y = p[1] * b;
      const double u = boussinesqDisplacement(a, b, p0, E_star, x, y);
      EXPECT_NEAR(u, delta - c.A * x * x - c.B * y * y, 1e-10 * delta)
          << "A=" << c.A << " B=" << c.B << " at (" << p[0] << "a, " << p[1] << "b)";
    }
    EXPECT_EQ(g.a_coeff > g.b_coeff, c.A < c.B);
  }
}

// The eccentricity solves Johnson's eq. B/A = (E(e)/(1-e^2) - K(e)) / (K(e) - E(e)) (A <= B),
// checked with the standard library's elliptic integrals (independent of the library's AGM).
// 1e-10 relative: the root is solved to ~1e-15 in the axis ratio.
TEST(Hertz, EccentricitySolvesJohnsonEquation) {
  std::vector<double> ratios = {1.0001, 1.009, 1.01, 1.011, 1.5, 3.0, 10.0, 100.0, 900.0};
  // 1 .. 1000 (the largest ratio computeHertz keeps), both solves.
  for (int i = 0; i <= 200; ++i) ratios.push_back(std::pow(10.0, 3.0 * i / 200.0));
  for (double ratio : ratios) {
    if (ratio - 1.0 < 1e-9) continue;  // the circle, flagged and not solved
    const rc::HertzGeometry g = rc::computeHertz(0.7, 0.7 * ratio, steelEStar());
    const double e = g.eccentricity;
    const double Kc = std::comp_ellint_1(e), Ec = std::comp_ellint_2(e);
    EXPECT_NEAR((Ec / (1 - e * e) - Kc) / (Kc - Ec), ratio, 1e-10 * ratio) << "ratio " << ratio;
    EXPECT_NEAR(g.b_coeff / g.a_coeff, std::sqrt(1 - e * e), 1e-14);
  }
}

// Johnson's relation between curvature ratio and eccentricity near the circle:
// B/A = 1 + 3/4 e^2 + O(e^4) (series of K and E). 1e-3 relative on e^2 covers the O(e^4) term.
TEST(Hertz, NearCircleSeries) {
  const double ratio = 1.0 + 1.0e-3;
  const rc::HertzGeometry g = rc::computeHertz(1.0, ratio, steelEStar());
  const double e2 = g.eccentricity * g.eccentricity;
  EXPECT_NEAR(e2, (ratio - 1.0) / 0.75, 2e-3 * (ratio - 1.0) / 0.75);
}

// Degenerate geometry never yields NaN, and is flagged.
TEST(Hertz, DegenerateCasesAreClampedAndFlagged) {
  const double E_star = steelEStar();
  // Convex-concave near the flange root: lateral relative curvature negative.
  rc::PrincipalCurvatures k;
  k.wheel_rolling = 1.0 / 0.45;
  k.wheel_lateral = -1.0 / 0.012;
  k.rail_lateral = 1.0 / 0.013;
  rc::HertzGeometry g = rc::computeHertz(k, E_star);
  EXPECT_TRUE(g.flags & rc::kHertzNonPositiveCurvature);
  EXPECT_TRUE(std::isfinite(g.a(1e4)) && std::isfinite(g.b(1e4)) && std::isfinite(g.K));
  EXPECT_GT(g.K, 0.0);
  // Both flat.
  g = rc::computeHertz(0.0, 0.0, E_star);
  EXPECT_TRUE(g.flags & rc::kHertzNonPositiveCurvature);
  EXPECT_TRUE(std::isfinite(g.K) && g.K > 0.0);
  // Very flat in one direction.
  g = rc::computeHertz(1e-9, 2.0, E_star);
  EXPECT_TRUE(g.flags & rc::kHertzRatioClamped);
  EXPECT_TRUE(std::isfinite(g.a(1e4)) && g.a(1e4) > g.b(1e4));
  // NaN input and bad modulus.
  g = rc::computeHertz(std::nan(""), 1.0, E_star);
  EXPECT_TRUE(g.flags & rc::kHertzBadInput);
  EXPECT_TRUE(std::isfinite(g.K));
  g = rc::computeHertz(1.0, 1.0, -5.0);
  EXPECT_TRUE(g.flags & rc::kHertzBadInput);
  EXPECT_TRUE(std::isfinite(g.K));
}

TEST(Hertz, MaterialValidationNamesField) {
  rc::ElasticMaterial bad;
  bad.poisson_ratio = 0.7;
  try {
    rc::contactModulus(bad, rc::ElasticMaterial{});
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("wheel material"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("0.7"), std::string::npos);
  }
  // Identical materials: G = E / (2 (1 + nu)), nu unchanged (exact up to rounding).
  const rc::ElasticMaterial s;
  EXPECT_NEAR(rc::combinedShearModulus(s, s), 2.10e11 / 2.6, 1e-3);
  EXPECT_NEAR(rc::combinedPoissonRatio(s, s), 0.3, 1e-15);
}

// Eq. 9 never produces a tensile force, whatever the (separating) velocity.
TEST(NormalForce, NeverNegative) {
  rc::NormalDampingParams p;
  p.restitution = 0.2;
  for (double delta : {-1e-4, 0.0, 1e-9, 1e-5, 1e-4})
    for (double vdot : {-10.0, -0.5, -1e-3, 0.0, 1e-3, 1.0})
      for (double v0 : {0.0, 1e-3, 0.5}) {
        const double N = rc::dampedNormalForce(1e10, delta, vdot, v0, p);
        EXPECT_GE(N, 0.0);
        EXPECT_TRUE(std::isfinite(N));
        if (delta <= 0.0) {
          EXPECT_EQ(N, 0.0);
        }
      }
}

// Formula check of eq. 9 against a hand evaluation; zero impact velocity uses the floor.
// 1e-12 relative: same arithmetic.
TEST(NormalForce, MatchesEquationNineWithFloor) {
  rc::NormalDampingParams p;
  p.restitution = 0.6;
  p.impact_velocity_floor = 0.02;
  const double K = 2e10, d = 5e-5, vd = 0.01;
  const double elastic = K * std::pow(d, 1.5);
  EXPECT_NEAR(rc::dampedNormalForce(K, d, 0.0, 0.3, p), elastic, 1e-12 * elastic);
  EXPECT_NEAR(rc::dampedNormalForce(K, d, vd, 0.3, p), elastic * (1 + 0.75 * (1 - 0.36) * vd / 0.3), 1e-12 * elastic);
  EXPECT_NEAR(rc::dampedNormalForce(K, d, vd, 0.0, p), elastic * (1 + 0.75 * (1 - 0.36) * vd / 0.02), 1e-12 * elastic);
}

// Physical check of the Lankarani-Nikravesh model: a mass dropped on a Hertz contact with
// restitution e rebounds with a velocity ratio close to e. The model's hysteresis term is
// derived for e near 1 (Lankarani & Nikravesh, J. Mech. Design 112 (1990) 369-376), so the
// check uses e = 0.95 and accepts 1% (the derivation neglects terms of order (1 - e)^2).
TEST(NormalForce, RestitutionOfSingleImpact) {
  rc::NormalDampingParams p;
  p.restitution = 0.95;
  const double m = 10.0, K = 1.0e10, v_in = 0.5;
  rc::ImpactMemory memory;
  double x = 0.0, v = v_in;  // x = penetration, v = penetration rate
  const double dt = 1e-8;
  auto acc = [&](double xx, double vv) { return -rc::dampedNormalForce(K, xx, vv, memory.impact_velocity, p) / m; };
  rc::updateImpactMemory(memory, 1e-300, v);
  EXPECT_DOUBLE_EQ(memory.impact_velocity, v_in);
  for (int i = 0; i < 20000000 && x >= 0.0; ++i) {
    const double k1x = v, k1v = acc(x, v);
    const double k2x = v + 0.5 * dt * k1v, k2v = acc(x + 0.5 * dt * k1x, v + 0.5 * dt * k1v);
    const double k3x = v + 0.5 * dt * k2v, k3v = acc(x + 0.5 * dt * k2x, v + 0.5 * dt * k2v);
    const double k4x = v + dt * k3v, k4v = acc(x + dt * k3x, v + dt * k3v);
    x += dt / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
    v += dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
    if (x >= 0.0) rc::updateImpactMemory(memory, x, v);  // as the contact evaluation does every call
  }
  // In a true impact the approach rate only falls after onset: the memory keeps the onset rate (eq. 9).
  EXPECT_DOUBLE_EQ(memory.impact_velocity, v_in);
  rc::updateImpactMemory(memory, x, v);
  EXPECT_FALSE(memory.in_contact);
  EXPECT_LT(x, 0.0);
  EXPECT_NEAR(-v / v_in, 0.95, 0.01);
}

TEST(Hertz, NearConformalPatchIsLimitedToTheLateralWidth) {
  // Flange root against the gauge corner: rolling curvature of a 0.45 m wheel (A = 1.1 /m), lateral
  // curvatures cancelling to B = 1e-3 /m. Unlimited, a 0.25 mm approach gives an ellipse metres wide and a
  // stiffness many times the tread's; limited to b = 10 mm, B is raised until b is 10 mm at that approach.
  const double E_star = 1.15e11, delta = 250e-6, max_b = 0.010;
  const rc::HertzGeometry conformal = rc::computeHertz(1.1, 1e-3, E_star);
  ASSERT_GT(conformal.b(conformal.load(delta)), 0.3);
  const rc::HertzGeometry limited = rc::limitLateralWidth(conformal, delta, max_b);
  EXPECT_LE(limited.b(limited.load(delta)), max_b);
  EXPECT_GT(limited.b(limited.load(delta)), (1.0 - 2e-4) * max_b);
  EXPECT_TRUE(limited.flags & rc::kHertzWidthClamped);
  EXPECT_DOUBLE_EQ(limited.A, conformal.A);
  EXPECT_GT(limited.B, conformal.B);
  EXPECT_LT(limited.K, 0.5 * conformal.K);
  // A tread contact (rail crown R 0.3 m against the tread: B ~ 0.6 /m) is far inside the limit: unchanged.
  const rc::HertzGeometry tread = rc::computeHertz(1.1, 0.6, E_star);
  const rc::HertzGeometry same = rc::limitLateralWidth(tread, 100e-6, max_b);
  EXPECT_EQ(same.K, tread.K);
  EXPECT_EQ(same.B, tread.B);
  EXPECT_FALSE(same.flags & rc::kHertzWidthClamped);
  EXPECT_EQ(rc::limitLateralWidth(conformal, delta, 0.0).K, conformal.K);  // 0: no limit
}

TEST(NormalForce, MemoryKeepsTheLargestApproachRateSoASoftStartIsNotOverdamped) {
  // A contact that starts at a tiny approach rate (the floor applies) and is then pushed in at 0.36 m/s (the
  // flange-climb hard case's reappearing tread contact): with the onset rate alone eq. 9's bracket would be
  // 1 + 0.5625 * 0.36 / 0.01 = 21; with the largest rate since onset it is 1 + 0.5625 = 1.5625 at most.
  const double K = 7e10, delta = 115e-6;
  const rc::NormalDampingParams p;  // e = 0.5, floor 0.01 m/s
  const double elastic = K * delta * std::sqrt(delta);
  rc::ImpactMemory memory;
  rc::updateImpactMemory(memory, 1e-9, 0.0);  // soft onset
  EXPECT_DOUBLE_EQ(memory.impact_velocity, 0.0);
  rc::updateImpactMemory(memory, delta, 0.36);
  EXPECT_DOUBLE_EQ(memory.impact_velocity, 0.36);
  const double N = rc::dampedNormalForce(K, delta, 0.36, memory.impact_velocity, p);
  EXPECT_NEAR(N, elastic * (1.0 + 0.75 * (1.0 - 0.25)), 1e-9 * elastic);
  // Separating at the same rate afterwards: 1 - 0.5625, positive (the onset rate alone gave a negative
  // bracket, N clamped to 0, for any separation faster than 0.018 m/s).
  rc::updateImpactMemory(memory, delta, -0.36);
  EXPECT_DOUBLE_EQ(memory.impact_velocity, 0.36);
  EXPECT_NEAR(rc::dampedNormalForce(K, delta, -0.36, memory.impact_velocity, p), elastic * (1.0 - 0.5625),
              1e-9 * elastic);
  rc::updateImpactMemory(memory, -1e-9, 0.0);  // contact lost: forgotten
  EXPECT_FALSE(memory.in_contact);
  EXPECT_EQ(memory.impact_velocity, 0.0);
}

TEST(NormalForce, ValidationRejectsBadParameters) {
  rc::NormalDampingParams p;
  p.restitution = 1.2;
  EXPECT_THROW(rc::validate(p), std::runtime_error);
  p = {};
  p.impact_velocity_floor = 0.0;
  EXPECT_THROW(rc::validate(p), std::runtime_error);
  EXPECT_NO_THROW(rc::validate(rc::NormalDampingParams{}));
}

// The Illinois bracket on x^3 = 2 from [0, 4]: a plain regula falsi keeps the end 4 for ever (g convex) and
// converges linearly; halving the kept end's value moves both ends, and the root is found to 1e-12 within
// 20 updates.
TEST(IllinoisBracket, BothEndsMoveAndTheRootIsFound) {
  const auto g = [](double x) { return x * x * x - 2.0; };
  rc::IllinoisBracket br{0.0, g(0.0), 4.0, g(4.0)};
  bool moved_a = false, moved_b = false;
  int updates = 0;
  double x = 0.0;
  while (updates < 20 && std::abs(g(x = br.next())) > 1e-12) {
    (br.update(x, g(x)) ? moved_a : moved_b) = true;
    ++updates;
  }
  EXPECT_NEAR(x, std::cbrt(2.0), 1e-12);
  EXPECT_LT(updates, 20);
  EXPECT_TRUE(moved_a);
  EXPECT_TRUE(moved_b);
  EXPECT_LT(br.a, std::cbrt(2.0));  // the ends still bracket the root
  EXPECT_GT(br.b, std::cbrt(2.0));
}
