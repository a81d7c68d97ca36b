// Tests of the profile interpolant, the UIC60 rail and S1002 wheel profiles and the profile readers.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <new>
#include <string>

#include "rail_contact/profile.hpp"

// Global allocation counter, to check that curve evaluation does not allocate.
namespace {
std::atomic<long> g_allocations{0};
}
void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace rc = rail::contact;
using Eigen::Vector2d;

namespace {

const std::string kData = RAILSIM_TEST_DATA_DIR;

// Points on a circle of radius R about c, from angle a0 to a1 (counter-clockwise), n points.
rc::ProfilePoints circlePoints(const Vector2d& c, double R, double a0, double a1, int n) {
  rc::ProfilePoints pts;
  for (int i = 0; i < n; ++i) {
    const double a = a0 + (a1 - a0) * i / (n - 1);
    pts.push_back(c + R * Vector2d(std::cos(a), std::sin(a)));
  }
  return pts;
}

// Checks unit tangent/normal, their consistency with finite differences of position and of the
// tangent (dt/du = -kappa n), at many parameters of a curve. FD step 1e-6 m: truncation error of the
// central differences ~ (1e-6)^2 * |p'''| (< 1e-8 for radii >= 10 mm) and round-off ~ 1e-16 / 1e-6.
void checkFrameConsistency(const rc::ProfileCurve& c, double tol_t, double tol_dt) {
  const double d = 1e-6;
  for (int i = 1; i < 200; ++i) {
    const double u = c.uMax() * i / 200.0;
    rc::ProfileEval e;
    c.evaluate(u, e);
    ASSERT_NEAR(e.t.norm(), 1.0, 1e-12);
    ASSERT_NEAR(e.n.norm(), 1.0, 1e-12);
    ASSERT_NEAR(e.t.dot(e.n), 0.0, 1e-12);
    // u is arc length, so dp/du is the unit tangent.
    const Vector2d fd_t = (c.position(u + d) - c.position(u - d)) / (2 * d);
    ASSERT_LT((fd_t - e.t).norm(), tol_t) << "u = " << u;
    const Vector2d fd_dt = (c.tangent(u + d) - c.tangent(u - d)) / (2 * d);
    ASSERT_LT((fd_dt + e.kappa * e.n).norm(), tol_dt * (1.0 + std::abs(e.kappa))) << "u = " << u;
  }
}

// UIC60 arc chain rebuilt from the published breakpoint half widths (same data as the library, own
// code path): returns the centre of the gauge-side arc `which` (1: R300, 2: R80, 3: R13), mm, z up.
Vector2d uic60Centre(int which) {
  const double R1 = 300, R2 = 80, X1 = 20.456 / 2, X2 = 52.053 / 2;
  const double f1 = std::asin(X1 / R1);
  const Vector2d c1(0, -R1);
  const Vector2d c2 = c1 + (R1 - R2) * Vector2d(std::sin(f1), std::cos(f1));
  const double f2 = std::asin((X2 - c2.x()) / R2);
  const Vector2d c3 = c2 + (R2 - 13.0) * Vector2d(std::sin(f2), std::cos(f2));
  return which == 1 ? c1 : (which == 2 ? c2 : c3);
}

Vector2d tiltPoint(const Vector2d& p, double inclination) { return rc::tiltProfile({p}, inclination).front(); }

std::string writeTemp(const std::string& name, const std::string& content) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "railsim_test_profile";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path) << content;
  return path;
}

// Expects `fn` to throw ProfileFileError whose message is exactly "<path>:<line>: <what>".
template <class Fn>
void expectFileError(Fn fn, const std::string& path, int line, const std::string& what) {
  try {
    fn();
    FAIL() << "no exception for " << path;
  } catch (const rc::ProfileFileError& e) {
    EXPECT_EQ(std::string(e.what()), path + ":" + std::to_string(line) + ": " + what);
    EXPECT_EQ(e.line(), line);
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
// Interpolant

TEST(ProfileCurve, CircleArcLengthCurvatureAndFrame) {
  // 120 deg arc of radius 50 mm through 121 points (h = 0.87 mm): the curve must reproduce the circle.
  // Cubic-spline interpolation errors scale with (h kappa) = 0.017: relative curvature error
  // ~ (h kappa)^2 = 3e-4, normal direction ~ (h kappa)^3 = 5e-6, position ~ h (h kappa)^3 = 5e-9 m;
  // tolerances at these scales (the not-a-knot ends are the worst place).
  const double R = 0.05;
  const Vector2d c(0.01, -0.02);
  const rc::ProfileCurve curve(circlePoints(c, R, 0.2, 0.2 + 2 * M_PI / 3, 121), rc::SolidSide::Left);
  EXPECT_NEAR(curve.uMax(), R * 2 * M_PI / 3, 5e-9);
  for (int i = 0; i <= 100; ++i) {
    const double u = curve.uMax() * i / 100.0;
    rc::ProfileEval e;
    curve.evaluate(u, e);
    EXPECT_NEAR((e.p - c).norm(), R, 5e-9);
    // Counter-clockwise arc with the solid (disc) on the left: convex, outward normal radial.
    EXPECT_NEAR(e.kappa, 1.0 / R, 3e-4 / R);
    EXPECT_LT((e.n - (e.p - c) / R).norm(), 1e-5);
  }
  checkFrameConsistency(curve, 1e-6, 1e-3);
}

TEST(ProfileCurve, ConcaveSideGivesNegativeCurvature) {
  // Same arc with the solid outside the circle (a groove): curvature -1/R, normal toward the centre.
  const double R = 0.013;
  const rc::ProfileCurve curve(circlePoints(Vector2d::Zero(), R, -2.5, -0.6, 100), rc::SolidSide::Right);
  const double u = 0.5 * curve.uMax();
  EXPECT_NEAR(curve.curvature(u), -1.0 / R, 1e-3 / R);  // error ~ (h/R)^2 = 6e-5, h = 0.25 mm
  EXPECT_LT((curve.normal(u) + curve.position(u) / R).norm(), 1e-6);
}

TEST(ProfileCurve, StraightLineIsExact) {
  rc::ProfilePoints pts;
  for (int i = 0; i < 7; ++i) pts.emplace_back(0.003 * i, 0.05 * 0.003 * i);
  const rc::ProfileCurve line(pts, rc::SolidSide::Right);
  EXPECT_NEAR(line.uMax(), 0.018 * std::sqrt(1 + 0.05 * 0.05), 1e-15);  // round-off only
  for (double u : {0.0, 0.004, 0.011, line.uMax()}) {
    EXPECT_NEAR(line.curvature(u), 0.0, 1e-9);
    EXPECT_NEAR(line.normal(u).dot(Vector2d(-0.05, 1.0).normalized()), 1.0, 1e-12);  // solid below
  }
}

TEST(ProfileCurve, SegmentLookupAndExtrapolation) {
  const rc::ProfileCurve curve(circlePoints(Vector2d::Zero(), 0.02, 0.0, 1.5, 30), rc::SolidSide::Left);
  const double h = curve.uMax() / curve.numSegments();
  for (int k = 0; k < curve.numSegments(); ++k) {
    EXPECT_EQ(curve.segment((k + 0.5) * h), k);
  }
  EXPECT_EQ(curve.segment(-1.0), 0);
  EXPECT_EQ(curve.segment(2.0 * curve.uMax()), curve.numSegments() - 1);
  // Beyond the ends the curve continues along the end tangent (exact by construction, round-off).
  const double eps = 1e-3;
  const Vector2d beyond = curve.position(curve.uMax() + eps);
  const Vector2d expect = curve.position(curve.uMax()) + eps * curve.tangent(curve.uMax());
  EXPECT_LT((beyond - expect).norm(), 1e-15);
  EXPECT_EQ(curve.curvature(-eps), 0.0);
  EXPECT_FALSE(curve.inRange(-eps));
  EXPECT_TRUE(curve.inRange(0.5 * curve.uMax()));
}

TEST(ProfileCurve, BadInputThrows) {
  EXPECT_THROW(rc::ProfileCurve({Vector2d(0, 0), Vector2d(1, 0), Vector2d(2, 0)}, rc::SolidSide::Right),
               std::invalid_argument);
  EXPECT_THROW(rc::ProfileCurve({Vector2d(0, 0), Vector2d(1, 0), Vector2d(1, 0), Vector2d(2, 0)}, rc::SolidSide::Right),
               std::invalid_argument);
  EXPECT_THROW(
      rc::ProfileCurve({Vector2d(0, 0), Vector2d(1, NAN), Vector2d(2, 0), Vector2d(3, 0)}, rc::SolidSide::Right),
      std::invalid_argument);
}

TEST(ProfileCurve, EvaluationDoesNotAllocateAndIsFast) {
  const rc::ProfileCurve rail = rc::makeUic60Rail();
  rc::ProfileEval e;
  double sink = 0.0;
  const long before = g_allocations.load();
  const int n = 1000000;
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i) {
    rail.evaluate(rail.uMax() * static_cast<double>((i * 7919LL) % n) / n, e);
    sink += e.kappa;
  }
  const auto t1 = std::chrono::steady_clock::now();
  EXPECT_EQ(g_allocations.load() - before, 0);
  const double ns_per_eval = std::chrono::duration<double, std::nano>(t1 - t0).count() / n;
  // Generous bound (a few tens of flops per call; the machine is shared): 1 microsecond.
  EXPECT_LT(ns_per_eval, 1000.0) << "sink " << sink;
  std::printf("[ info ] ProfileCurve::evaluate: %.1f ns per call\n", ns_per_eval);
}

// ---------------------------------------------------------------------------------------------------
// UIC60 rail

TEST(Uic60, HeadWidthAndHeight) {
  // Head width between the two R13 / flank tangent points, located on the curve where its curvature
  // drops to half of 1/13 mm; height of the section outline. Tolerance +-0.5 mm (drawing tolerance).
  const rc::ProfileCurve head(rc::uic60HeadPoints(), rc::SolidSide::Right);
  const double half_k = 0.5 / 0.013;
  double u_field = -1, u_gauge = -1;
  for (int i = 0; i < 20000; ++i) {
    const double u = head.uMax() * i / 20000.0;
    if (u_field < 0 && head.curvature(u) > half_k) u_field = u;
    if (head.curvature(u) > half_k) u_gauge = u;
  }
  ASSERT_GT(u_field, 0.0);
  const double width = head.position(u_gauge).x() - head.position(u_field).x();
  EXPECT_NEAR(width, rc::uic60::kHeadWidth, 0.5e-3);
  EXPECT_NEAR(width, 0.072, 0.5e-3);

  const rc::ProfilePoints outline = rc::uic60SectionOutline();
  double z_min = 1, z_max = -1, y_min = 1, y_max = -1;
  for (const Vector2d& p : outline) {
    z_min = std::min(z_min, p.y());
    z_max = std::max(z_max, p.y());
    y_min = std::min(y_min, p.x());
    y_max = std::max(y_max, p.x());
  }
  EXPECT_NEAR(z_max - z_min, 0.172, 0.5e-3);
  EXPECT_NEAR(y_max - y_min, 0.150, 0.5e-3);  // foot width
}

TEST(Uic60, RoughOutlineMatchesPublishedSectionData) {
  // The outline has no fillets and an assumed foot edge, so it only roughly matches the published
  // area (76.70 cm^2) and centroid depth (I / W_head = 91.1 mm): 10 % and 4 mm. This guards the
  // published constants against gross error (e.g. a unit slip or head/foot swap).
  const rc::ProfilePoints o = rc::uic60SectionOutline();
  double A = 0, Sz = 0;
  for (size_t i = 0; i < o.size(); ++i) {
    const Vector2d& a = o[i];
    const Vector2d& b = o[(i + 1) % o.size()];
    const double cr = a.x() * b.y() - b.x() * a.y();
    A += 0.5 * cr;
    Sz += (a.y() + b.y()) * cr / 6.0;
  }
  const double z_c = Sz / A;
  EXPECT_NEAR(std::abs(A), rc::uic60::kArea, 0.10 * rc::uic60::kArea);
  EXPECT_NEAR(-z_c, rc::uic60::kCentroidDepth, 4e-3);
  // The foot-side section modulus must give the same neutral axis from the other side.
  EXPECT_NEAR(rc::uic60::kIyy / rc::uic60::kSectionModulusFoot + rc::uic60::kCentroidDepth, rc::uic60::kHeight, 0.1e-3);
}

TEST(Uic60, ArcCurvatures) {
  // Curvature at the middle of each arc equals 1/R (interpolation error ~ (ds/R)^2 < 1e-4).
  const rc::ProfileCurve head(rc::uic60HeadPoints(), rc::SolidSide::Right);
  auto kappaAtY = [&](double y) {
    double u = 0;
    EXPECT_TRUE(head.findCoordinate(0, y, head.uMin(), head.uMax(), u));
    return head.curvature(u);
  };
  EXPECT_NEAR(kappaAtY(0.0), 1 / 0.300, 1e-3 / 0.300);
  EXPECT_NEAR(kappaAtY(0.018), 1 / 0.080, 1e-3 / 0.080);
  EXPECT_NEAR(kappaAtY(-0.018), 1 / 0.080, 1e-3 / 0.080);
  EXPECT_NEAR(kappaAtY(0.032), 1 / 0.013, 1e-3 / 0.013);
  checkFrameConsistency(head, 1e-6, 2e-3);
}

TEST(Uic60, TiltTurnsRunningSurfaceTowardTrackCentre) {
  // Tilting by 1/20 rotates the rail axis to (sin a, cos a); the 1:20 gauge flank becomes vertical
  // (its published slope is 1:20 to 0.6 %, so the residual slope is below 1e-3).
  const double a = std::atan(1.0 / 20);
  EXPECT_LT((tiltPoint(Vector2d(0, 1), 1.0 / 20) - Vector2d(std::sin(a), std::cos(a))).norm(), 1e-15);
  const rc::ProfileCurve rail = rc::makeUic60Rail();
  double u = 0;
  ASSERT_TRUE(rail.findCoordinate(1, -0.025, 0.5 * rail.uMax(), rail.uMax(), u));
  EXPECT_LT(std::abs(rail.tangent(u).x()), 1e-3);
  EXPECT_GT(rail.normal(u).x(), 0.999);  // gauge face looks toward the track centre
}

TEST(Uic60, GaugePointLiesOnGaugeFace) {
  // Independent reference: the running-surface top of the tilted rail is the top of the tilted
  // field-side R80 arc, and 14 mm below it the gauge side lies on the tilted R13 arc (the R13 / flank
  // tangent point is 16.1 mm below the origin). Tolerance 1 micrometre (spline vs exact circle).
  const double inc = 1.0 / 20;
  const rc::ProfileCurve rail = rc::makeUic60Rail(inc);
  const Vector2d top = rc::railTopPoint(rail);
  const Vector2d c80_field = tiltPoint(Vector2d(-uic60Centre(2).x(), uic60Centre(2).y()) * 1e-3, inc);
  EXPECT_NEAR(top.y(), c80_field.y() + 0.080, 1e-6);
  EXPECT_NEAR(top.x(), c80_field.x(), 1e-5);  // flat maximum: y is located less sharply than z

  const Vector2d gp = rc::gaugePoint(rail, 0.014);
  EXPECT_NEAR(gp.y(), top.y() - 0.014, 1e-9);
  const Vector2d c13 = tiltPoint(uic60Centre(3) * 1e-3, inc);
  EXPECT_NEAR((gp - c13).norm(), 0.013, 1e-6);
  EXPECT_GT(gp.x(), c13.x());  // on the outer (gauge) side of the corner arc
  double dist = 1;
  const double u = rail.closestParameter(gp, &dist);
  EXPECT_LT(dist, 1e-9);
  EXPECT_GT(rail.normal(u).x(), 0.9);  // the face at the gauge point looks toward the track centre
}

TEST(Uic60, MatchesManchesterBenchmarkProfile) {
  // Published reference: the Manchester contact benchmark UIC60 profile (canted 1/40, origin at the
  // top of the canted head), read from a MiniProf file subset. Distance of each published point to
  // our curve, tilted 1/40 and shifted so that its top is at the origin: two independent rebuilds of
  // the same drawing, printed to 1e-6 mm; 0.1 mm is a fifth of the drawing tolerance.
  const rc::ProfilePoints ref = rc::readMiniProfProfile(kData + "/mbench_uic60_v3_subset.ban");
  ASSERT_EQ(ref.size(), 48u);
  const rc::ProfileCurve rail(rc::tiltProfile(rc::uic60HeadPoints(), 1.0 / 40), rc::SolidSide::Right);
  const Vector2d top = rc::railTopPoint(rail);
  double max_d = 0;
  for (const Vector2d& q : ref) {
    double d = 0;
    rail.closestParameter(q + top, &d);
    max_d = std::max(max_d, d);
  }
  EXPECT_LT(max_d, 0.1e-3);
  std::printf("[ info ] UIC60 vs Manchester benchmark: max distance %.4f mm\n", max_d * 1e3);
}

// ---------------------------------------------------------------------------------------------------
// S1002 wheel

TEST(S1002, PiecewiseDefinitionIsContinuous) {
  // The published coefficients are rounded; adjacent sections meet to ~1e-4 mm in value and ~1e-4 in
  // slope. A mistyped coefficient would open a gap of millimetres: tolerance 2e-4 mm and 1e-3.
  const double bounds_S[] = {32.15796, -26.0, -35.0, -38.426669071, -39.764473993, -49.662510381, -62.764705882};
  for (double S : bounds_S) {
    const double y = -S * 1e-3, e = 1e-9, d = 1e-7;
    EXPECT_NEAR(rc::s1002Z(y - e), rc::s1002Z(y + e), 2e-7) << "S = " << S;
    const double slope_lo = (rc::s1002Z(y - e) - rc::s1002Z(y - e - d)) / d;
    const double slope_hi = (rc::s1002Z(y + e + d) - rc::s1002Z(y + e)) / d;
    EXPECT_NEAR(slope_lo, slope_hi, 1e-3) << "S = " << S;
  }
}

TEST(S1002, MatchesManchesterBenchmarkPoints) {
  // Published points of the Manchester contact benchmark S1002 wheel (CONTACT software,
  // testbank/profiles/MBench_S1002_v3.prw, data columns converted: y = column 1, z = -column 2; mm).
  // Printed to 8 digits: tolerance 1e-3 mm.
  const double ref[][2] = {{69.612628, -13.485642},  {54.892493, -27.999518},  {45.208193, -23.727001},
                           {40.893537, -18.213368},  {38.335925, -11.757921},  {33.273160, -5.5298268},
                           {25.580201, -2.6414043},  {12.003476, -0.68277101}, {0.34825167, -0.011887234},
                           {-14.239919, 0.24892741}, {-30.714676, 0.68793755}, {-45.008704, 1.6362567},
                           {-60.0, 2.6356764}};
  for (const auto& r : ref) EXPECT_NEAR(rc::s1002Z(r[0] * 1e-3) * 1e3, r[1], 1e-3) << "y = " << r[0];
}

TEST(S1002, FlangeHeightThicknessAndBackFace) {
  // EN 13715 nominal S1002: flange height 28 mm, flange thickness 32.5 mm at 10 mm above the taping
  // line, back face 70 mm from the taping line. Tolerance 0.1 mm.
  const rc::WheelProfile w = rc::makeS1002();
  EXPECT_NEAR(rc::tapingLineZ(w), 0.0, 1e-9);
  EXPECT_NEAR(rc::flangeHeight(w), 0.028, 0.1e-3);
  EXPECT_NEAR(rc::flangeThickness(w, 0.010), 0.0325, 0.1e-3);
  EXPECT_NEAR(rc::flangeBackY(w), 0.070, 0.1e-3);
  std::printf("[ info ] S1002: Sh = %.4f mm, Sd = %.4f mm, back face at %.4f mm\n", rc::flangeHeight(w) * 1e3,
              rc::flangeThickness(w) * 1e3, rc::flangeBackY(w) * 1e3);
}

TEST(S1002, TreadFlangeSplitAt45Degrees) {
  // The 45 deg slope is reached inside section D (R13 about S = -26.210665, F = 16.446 mm) where
  // |S + 26.210665| = 13 / sqrt(2): exact split point. Tolerance 1 micrometre (spline vs circle).
  const rc::WheelProfile w = rc::makeS1002();
  const double r = 13.0 / std::sqrt(2.0);
  EXPECT_NEAR(w.split_yz.x() * 1e3, 26.210665 + r, 1e-3);
  EXPECT_NEAR(w.split_yz.y() * 1e3, -(16.446 - r), 1e-3);
  // Tread and flange share the split point; the tread covers the taping line, the flange the tip.
  EXPECT_LT((w.tread.position(w.tread.uMax()) - w.split_yz).norm(), 1e-12);
  EXPECT_LT((w.flange.position(0.0) - w.split_yz).norm(), 1e-12);
  EXPECT_NEAR(w.tread.position(0.0).x(), -0.060, 1e-9);
  EXPECT_NEAR(w.flange.position(w.flange.uMax()).x(), 0.070, 1e-9);
  // Outward normals point away from the wheel: down on the tread, toward -y on the flange face.
  double u = 0;
  ASSERT_TRUE(w.tread.findCoordinate(0, 0.0, 0.0, w.tread.uMax(), u));
  EXPECT_LT(w.tread.normal(u).y(), -0.99);
  ASSERT_TRUE(w.flange.findCoordinate(0, 0.039, 0.0, 0.5 * w.flange.uMax(), u));
  EXPECT_LT(w.flange.normal(u).x(), -0.9);
}

TEST(S1002, SplineFollowsDefinitionAndArcCurvatures) {
  const rc::WheelProfile w = rc::makeS1002();
  // Position: the tread curve vs the definition over the tread, 1 micrometre (junctions of sections
  // with different curvature are smoothed over a few 0.1 mm nodes).
  double max_dz = 0;
  for (double y = -0.0595; y < w.split_yz.x(); y += 0.0005) {
    double u = 0;
    ASSERT_TRUE(w.tread.findCoordinate(0, y, 0.0, w.tread.uMax(), u));
    max_dz = std::max(max_dz, std::abs(w.tread.position(u).y() - rc::s1002Z(y)));
  }
  EXPECT_LT(max_dz, 1e-6);
  // Curvature at the middle of the circular sections: tip R12 and R20 convex, back R20.5 convex,
  // flange-root fillet R13 concave; straight sections A and E zero. Tolerance 0.3 % (interpolation
  // error ~ (ds/R)^2 plus the smoothing of the neighbouring junctions).
  auto kappaAt = [&](const rc::ProfileCurve& c, int axis, double v, double u_from, double u_to) {
    double u = 0;
    EXPECT_TRUE(c.findCoordinate(axis, v, u_from, u_to, u));
    return c.curvature(u);
  };
  const rc::ProfileCurve& f = w.flange;
  double u_tip = 0;
  ASSERT_TRUE(f.findCoordinate(0, 0.055, 0.0, f.uMax(), u_tip));
  EXPECT_NEAR(f.curvature(u_tip), 1 / 0.012, 3e-3 / 0.012);                        // G, tip
  EXPECT_NEAR(kappaAt(f, 0, 0.0447, 0.0, u_tip), 1 / 0.020, 3e-3 / 0.020);         // F
  EXPECT_NEAR(kappaAt(f, 0, 0.0669, u_tip, f.uMax()), 1 / 0.0205, 3e-3 / 0.0205);  // H, back
  EXPECT_NEAR(kappaAt(f, 0, 0.0370, 0.0, u_tip), -1 / 0.013, 3e-3 / 0.013);        // D, root fillet
  EXPECT_NEAR(kappaAt(f, 0, 0.0391, 0.0, u_tip), 0.0, 0.5);                        // E, straight
  EXPECT_NEAR(kappaAt(w.tread, 0, -0.046, 0.0, w.tread.uMax()), 0.0, 0.05);        // A, straight
  checkFrameConsistency(w.tread, 1e-6, 2e-3);
  checkFrameConsistency(w.flange, 1e-6, 2e-3);
}

TEST(S1002, BadSplitAngleThrows) {
  EXPECT_THROW(rc::makeS1002(0.0), std::invalid_argument);
  EXPECT_THROW(rc::makeS1002(80.0 * M_PI / 180.0), std::runtime_error);  // flange flank is 70 deg
}

// ---------------------------------------------------------------------------------------------------
// Files

TEST(ProfileFiles, RoundTripAllFormats) {
  // Writers print 16 significant digits (mm): read-back error ~1e-17 m; tolerance 1e-12 m.
  const rc::ProfilePoints wheel = rc::s1002Points(0.5e-3);
  const rc::ProfilePoints rail = rc::tiltProfile(rc::uic60HeadPoints(0.5e-3));
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "railsim_test_profile";
  std::filesystem::create_directories(dir);
  struct Case {
    std::string name;
    const rc::ProfilePoints* pts;
  };
  for (const Case& c : {Case{"w.txt", &wheel}, Case{"w.ban", &wheel}, Case{"w.prw", &wheel}, Case{"r.txt", &rail},
                        Case{"r.ban", &rail}, Case{"r.prr", &rail}}) {
    const std::string path = (dir / c.name).string();
    const std::string ext = c.name.substr(c.name.find('.'));
    if (ext == ".txt") rc::writePlainProfile(path, *c.pts, "round trip");
    if (ext == ".ban") rc::writeMiniProfProfile(path, *c.pts);
    if (ext == ".prw") rc::writeSimpackProfile(path, *c.pts, 1, "round trip");
    if (ext == ".prr") rc::writeSimpackProfile(path, *c.pts, 0, "round trip");
    const rc::ProfilePoints back = rc::readProfilePoints(path);
    ASSERT_EQ(back.size(), c.pts->size()) << path;
    double max_err = 0;
    for (size_t i = 0; i < back.size(); ++i) max_err = std::max(max_err, (back[i] - (*c.pts)[i]).norm());
    EXPECT_LT(max_err, 1e-12) << path;
  }
  // Loading builds the same surfaces as the built-in profiles (1e-9 m: same points up to print).
  const rc::WheelProfile w = rc::loadWheelProfile((dir / "w.prw").string());
  EXPECT_NEAR(rc::flangeHeight(w), 0.028, 0.1e-3);
  EXPECT_NEAR(rc::flangeThickness(w), 0.0325, 0.1e-3);
  const rc::ProfileCurve r = rc::loadRailProfile((dir / "r.ban").string());
  const rc::ProfileCurve r_ref(rail, rc::SolidSide::Right);
  EXPECT_NEAR(r.uMax(), r_ref.uMax(), 1e-9);
  EXPECT_LT((rc::gaugePoint(r) - rc::gaugePoint(r_ref)).norm(), 1e-9);
}

TEST(ProfileFiles, SimpackModificationsAndUnits) {
  // A wheel stored as in the benchmark files: data y toward the flange, z = radius increase, with
  // mirror.y = 1 and inversion = 1 in the spline block, mm. Points on S1002 (published benchmark
  // values, see MatchesManchesterBenchmarkPoints): the read-back must match the definition (1e-3 mm).
  int type = -1;
  const rc::ProfilePoints p = rc::readSimpackProfile(kData + "/s1002_mirrored.prw", {}, &type);
  EXPECT_EQ(type, 1);
  ASSERT_EQ(p.size(), 8u);
  EXPECT_GT(p.front().x(), p.back().x());  // inversion reversed the file order
  for (const Vector2d& q : p) EXPECT_NEAR(q.y() * 1e3, rc::s1002Z(q.x()) * 1e3, 1e-3) << "y = " << q.x();
  // Rotation, shift and metres: rotate = 90 deg (units.ang.f = 180/pi deg per rad) maps (y, z) ->
  // (-z, y) after the shift; units.len.f = 1 (metres). Exact up to round-off.
  const std::string path = writeTemp("rot.prr",
                                     "header.begin\n type = 0\nheader.end\nspline.begin\n"
                                     " shift.y = 0.001\n rotate = 90\n units.ang.f = 57.29577951308232\n"
                                     " units.len.f = 1\n point.begin\n"
                                     "0.000 0.010\n0.001 0.011\n0.002 0.013\n0.003 0.016\n point.end\nspline.end\n");
  const rc::ProfilePoints r = rc::readSimpackProfile(path);
  ASSERT_EQ(r.size(), 4u);
  // File point (0, 0.010) -> shift (0.001, 0.010) -> rotate (-0.010, 0.001) -> library (0.010, -0.001).
  EXPECT_LT((r[0] - Vector2d(0.010, -0.001)).norm(), 1e-15);
  EXPECT_LT((r[3] - Vector2d(0.016, -0.004)).norm(), 1e-15);
}

TEST(ProfileFiles, PlainUnitsRule) {
  // "# units:" decides; without it, |values| > 1 means millimetres.
  const std::string mm = writeTemp("mm.txt", "0 0\n1 0.1\n2 0.3\n3 0.6\n");
  const std::string m = writeTemp("m.txt", "0 0\n0.001 0.0001\n0.002 0.0003\n0.003 0.0006\n");
  const std::string forced = writeTemp("forced.txt", "# units: mm\n0 0\n0.5 0.1\n0.9 0.3\n1.0 0.6\n");
  EXPECT_NEAR(rc::readPlainProfile(mm)[3].x(), 0.003, 1e-15);
  EXPECT_NEAR(rc::readPlainProfile(m)[3].x(), 0.003, 1e-15);
  EXPECT_NEAR(rc::readPlainProfile(forced)[3].x(), 0.001, 1e-15);
  // Options: mirror and shift after the format convention.
  rc::ProfileFileOptions o;
  o.mirror_y = true;
  o.shift_z = 0.5;
  EXPECT_LT((rc::readPlainProfile(mm, o)[1] - Vector2d(-0.001, 0.5001)).norm(), 1e-15);
}

TEST(ProfileFiles, MalformedPlainFiles) {
  const std::string d = kData + "/";
  expectFileError([&] { rc::readPlainProfile(d + "bad_nonnumeric.txt"); }, d + "bad_nonnumeric.txt", 5,
                  "non-numeric value '1.2x'");
  expectFileError([&] { rc::readPlainProfile(d + "bad_columns.txt"); }, d + "bad_columns.txt", 4,
                  "wrong column count (3 values, expected 2: y z)");
  expectFileError([&] { rc::readPlainProfile(d + "bad_monotonic.txt"); }, d + "bad_monotonic.txt", 6,
                  "y not increasing (12.3 after 12.5)");
  expectFileError([&] { rc::readPlainProfile(d + "too_few.txt"); }, d + "too_few.txt", 4,
                  "too few points (3, need at least 4)");
  expectFileError([&] { rc::readPlainProfile(d + "does_not_exist.txt"); }, d + "does_not_exist.txt", 0,
                  "cannot open file");
  const std::string units = writeTemp("units.txt", "# units: inch\n0 0\n1 1\n2 2\n3 3\n");
  expectFileError([&] { rc::readPlainProfile(units); }, units, 1, "unknown units 'inch' (expected mm or m)");
  const std::string dup = writeTemp("dup.txt", "0 0\n1 1\n1 1\n2 2\n3 3\n");
  expectFileError([&] { rc::readPlainProfile(dup); }, dup, 3, "repeated point (1 1)");
}

TEST(ProfileFiles, MalformedMiniProfFiles) {
  const std::string d = kData + "/";
  expectFileError([&] { rc::readMiniProfProfile(d + "bad_columns.ban"); }, d + "bad_columns.ban", 7,
                  "wrong column count (3 values, ColumnDef has 2)");
  const std::string nonnum = writeTemp("nonnum.ban", "ColumnDef=X,Y\n\n1 2\n2 3\n3 abc\n4 5\n");
  expectFileError([&] { rc::readMiniProfProfile(nonnum); }, nonnum, 5, "non-numeric value 'abc'");
  const std::string mono = writeTemp("mono.ban", "ColumnDef=X,Y\n\n4 2\n3 3\n2 4\n2.5 5\n1 5\n");
  expectFileError([&] { rc::readMiniProfProfile(mono); }, mono, 6, "X not decreasing (2.5 after 2)");
  const std::string coldef = writeTemp("coldef.ban", "ColumnDef=A,Y\n\n1 2\n");
  expectFileError([&] { rc::readMiniProfProfile(coldef); }, coldef, 1, "ColumnDef must name columns X and Y ('A,Y')");
  const std::string few = writeTemp("few.ban", "ColumnDef=X,Y\n\n1 2\n2 3\n\"3 4\n");
  expectFileError([&] { rc::readMiniProfProfile(few); }, few, 5, "too few points (2, need at least 4)");
}

TEST(ProfileFiles, MalformedSimpackFiles) {
  const std::string d = kData + "/";
  expectFileError([&] { rc::readSimpackProfile(d + "bad_monotonic.prr"); }, d + "bad_monotonic.prr", 11,
                  "y not increasing (-20.5 after -20)");
  const std::string head = "header.begin\n type = 0\nheader.end\nspline.begin\n";
  const std::string key =
      writeTemp("key.prr", head + " units.len.f = mm\n point.begin\n0 0\n1 1\n2 2\n3 3\n point.end\nspline.end\n");
  expectFileError([&] { rc::readSimpackProfile(key); }, key, 5, "non-numeric value 'mm' for units.len.f");
  const std::string cols = writeTemp("cols.prr", head + " point.begin\n0 0\n1 1 1 1\n point.end\nspline.end\n");
  expectFileError([&] { rc::readSimpackProfile(cols); }, cols, 7,
                  "wrong column count (4 values, expected y z [weight])");
  const std::string outside = writeTemp("outside.prr", head + "spline.end\n0 0\n");
  expectFileError([&] { rc::readSimpackProfile(outside); }, outside, 6, "data outside point.begin/point.end ('0 0')");
  const std::string open = writeTemp("open.prr", head + " point.begin\n0 0\n1 1\n2 2\n3 3\n");
  expectFileError([&] { rc::readSimpackProfile(open); }, open, 9, "file ends inside a block");
  const std::string nonnum =
      writeTemp("nonnum.prr", head + " point.begin\n0 0\n1 1\n2 two\n3 3\n point.end\nspline.end\n");
  expectFileError([&] { rc::readSimpackProfile(nonnum); }, nonnum, 8, "non-numeric value 'two'");
  expectFileError([&] { rc::readSimpackProfile(d + "missing.prr"); }, d + "missing.prr", 0, "cannot open file");
}

// A profile spans about 0.15 m: a coordinate beyond 1 m (after unit conversion) is refused with the line
// of its point, in every format; 999 mm is still accepted.
TEST(ProfileFiles, CoordinatesBeyondOneMetreRefused) {
  const std::string plain_mm = writeTemp("far_mm.txt", "0 0\n1 0.1\n1e300 0.3\n3 0.6\n");
  expectFileError([&] { rc::readPlainProfile(plain_mm); }, plain_mm, 3,
                  "y = 1e+300 mm out of range (|y|, |z| must be at most 1 m)");
  const std::string plain_m = writeTemp("far_m.txt", "# units: m\n0 0\n0.001 0.0001\n0.002 -1.5\n0.003 0.0006\n");
  expectFileError([&] { rc::readPlainProfile(plain_m); }, plain_m, 4,
                  "z = -1.5 m out of range (|y|, |z| must be at most 1 m)");
  const std::string near = writeTemp("near_mm.txt", "0 0\n1 0.1\n2 0.3\n999 0.6\n");
  EXPECT_NEAR(rc::readPlainProfile(near)[3].x(), 0.999, 1e-15);
  const std::string ban = writeTemp("far.ban", "ColumnDef=X,Y\n\n4 2\n3 -1e300\n2 4\n1 5\n");
  expectFileError([&] { rc::readMiniProfProfile(ban); }, ban, 4,
                  "Y = -1e+300 mm out of range (|X|, |Y| must be at most 1 m)");
  const std::string head = "header.begin\n type = 0\nheader.end\nspline.begin\n";
  const std::string prr_mm = writeTemp(
      "far_mm.prr", head + " units.len.f = 1000\n point.begin\n0 0\n1 1\n2 1e300\n3 3\n point.end\nspline.end\n");
  expectFileError([&] { rc::readSimpackProfile(prr_mm); }, prr_mm, 9,
                  "z = 1e+300 mm out of range (|y|, |z| must be at most 1 m)");
  const std::string prr_m =
      writeTemp("far_m.prr", head + " point.begin\n0 0\n0.1 0.1\n1.5 0.2\n1.6 0.3\n point.end\nspline.end\n");
  expectFileError([&] { rc::readSimpackProfile(prr_m); }, prr_m, 8,
                  "y = 1.5 m out of range (|y|, |z| must be at most 1 m)");
}

TEST(ProfileFiles, ExampleConfigProfilesLoad) {
  // The example user files shipped in config/profiles build valid surfaces with the nominal
  // dimensions (0.1 mm, as for the built-in profiles).
  const std::string cfg = std::string(RAILSIM_CONFIG_DIR) + "/profiles/";
  const rc::WheelProfile w = rc::loadWheelProfile(cfg + "S1002.prw");
  EXPECT_NEAR(rc::flangeHeight(w), 0.028, 0.1e-3);
  EXPECT_NEAR(rc::flangeThickness(w), 0.0325, 0.1e-3);
  const rc::WheelProfile w2 = rc::loadWheelProfile(cfg + "S1002.txt");
  EXPECT_NEAR(rc::flangeBackY(w2), 0.070, 0.1e-3);
  for (const char* name : {"UIC60_1in20.prr", "UIC60_1in20.ban"}) {
    const rc::ProfileCurve r = rc::loadRailProfile(cfg + name);
    EXPECT_LT((rc::gaugePoint(r) - rc::gaugePoint(rc::makeUic60Rail())).norm(), 1e-5) << name;
  }
}

TEST(RailSectionCentre, FollowsTheProfileWhateverItsOrigin) {
  // Symmetric untilted UIC60 with its origin on the axis at the top: the centroid on the axis, 91.1 mm down.
  const rc::ProfileCurve rail = rc::makeUic60Rail(0.0);
  const Eigen::Vector2d c = rc::railSectionCentre(rail);
  EXPECT_NEAR(c.x(), 0.0, 1e-6);
  EXPECT_NEAR(c.y(), -rc::uic60::kCentroidDepth, 1e-9);
  // The same rail with its origin moved (7 mm toward the gauge side, 3 mm up): the centre moves with it.
  rc::ProfilePoints pts = rc::uic60HeadPoints();
  for (Eigen::Vector2d& p : pts) p += Eigen::Vector2d(-0.007, -0.003);
  const Eigen::Vector2d c2 = rc::railSectionCentre(rc::ProfileCurve(pts, rc::SolidSide::Right));
  EXPECT_NEAR(c2.x(), -0.007, 1e-6);
  EXPECT_NEAR(c2.y(), -0.003 - rc::uic60::kCentroidDepth, 1e-9);
  // The Manchester benchmark's rail (1:40 built in, origin at the highest point, which lies R300 / 40 =
  // 7.5 mm field side of the axis): the head centre 7.5 mm toward the gauge side, within the 1:40 lean of
  // the head over 14 mm (0.35 mm) and the file's own shape (0.04 mm from the standard, test above).
  const rc::ProfileCurve mb = rc::loadRailProfile(RAILSIM_CONFIG_DIR "/profiles/manchester_a22/MBench_UIC60_v3.prr");
  EXPECT_NEAR(rc::railSectionCentre(mb).x(), 0.0075, 0.5e-3);
}
