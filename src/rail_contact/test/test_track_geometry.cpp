// Tests of the track geometry: centre-line integration against closed forms, canted-track rail curves
// and frames, derivative consistency for the contact Newton iteration, irregularities on the rails, error
// handling, and the EN 13803 cant helpers.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "rail_contact/irregularities.hpp"
#include "rail_contact/track_geometry.hpp"

namespace rc = rail::contact;
using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace {

rc::SegmentSpec straight(double L, double cant = 0.0, double gradient = 0.0) {
  rc::SegmentSpec s;
  s.type = rc::SegmentSpec::Type::Straight;
  s.length = L;
  s.cant_start = s.cant_end = cant;
  s.gradient = gradient;
  return s;
}
rc::SegmentSpec circular(double L, double kappa, double cant = 0.0, double gradient = 0.0) {
  rc::SegmentSpec s;
  s.type = rc::SegmentSpec::Type::Circular;
  s.length = L;
  s.curvature_start = s.curvature_end = kappa;
  s.cant_start = s.cant_end = cant;
  s.gradient = gradient;
  return s;
}
rc::SegmentSpec transition(double L, double k0, double k1, double c0 = 0.0, double c1 = 0.0, double gradient = 0.0) {
  rc::SegmentSpec s;
  s.type = rc::SegmentSpec::Type::Transition;
  s.length = L;
  s.curvature_start = k0;
  s.curvature_end = k1;
  s.cant_start = c0;
  s.cant_end = c1;
  s.gradient = gradient;
  return s;
}

// Fresnel-type integrals of the clothoid kappa(s) = c s from the origin, heading 0:
//   X(L) = int_0^L cos(c s^2 / 2) ds,  Y(L) = int_0^L sin(c s^2 / 2) ds,
// by their power series (term-wise integration of the cos/sin series), in long double, summed until
// the terms fall below 1e-30 m. Independent of the library's quadrature.
void clothoidSeries(double c, double L, double& X, double& Y) {
  const long double a = 0.5L * c;  // heading = a s^2
  long double x = 0, y = 0;
  long double pow_a = 1, fact = 1;  // a^m, m!
  for (int m = 0; m < 60; ++m) {
    if (m > 0) {
      pow_a *= a;
      fact *= m;
    }
    // cos(a s^2) = sum_n (-1)^n (a s^2)^(2n) / (2n)!, sin = sum_n (-1)^n (a s^2)^(2n+1) / (2n+1)!
    const long double term = pow_a * std::pow(static_cast<long double>(L), 2 * m + 1) / (fact * (2 * m + 1));
    const int n = m / 2;
    const long double sign = (n % 2 == 0) ? 1.0L : -1.0L;
    if (m % 2 == 0)
      x += sign * term;
    else
      y += sign * term;
    if (m > 4 && std::fabs(static_cast<double>(term)) < 1e-30) break;
  }
  X = static_cast<double>(x);
  Y = static_cast<double>(y);
}

Matrix3d rotZ(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitZ()).toRotationMatrix(); }

double orthonormalityError(const Matrix3d& R) {
  return std::max((R.transpose() * R - Matrix3d::Identity()).cwiseAbs().maxCoeff(), std::abs(R.determinant() - 1.0));
}

}  // namespace

// A straight with gradient g: the centre line is the segment s (cos theta, 0, sin theta), theta = atan(g)
// (s is the 3-D arc length). The integrand is constant, so only round-off remains: 1e-9 m over 1 km.
TEST(TrackGeometry, StraightWithGradientEndsWhereExpected) {
  rc::GeometrySpec spec;
  spec.s_start = 100.0;
  spec.segments = {straight(1000.0, 0.0, 0.02)};
  spec.table_step = 0.5;
  const rc::TrackGeometry geom(spec);
  EXPECT_DOUBLE_EQ(geom.sEnd(), 1100.0);
  const double theta = std::atan(0.02);
  rc::TrackPoint tp;
  for (double s : {100.0, 433.37, 1100.0}) {
    geom.centre(s, tp);
    const double x = s - 100.0;
    EXPECT_NEAR(tp.p_center_in_world.x(), x * std::cos(theta), 1e-9);
    EXPECT_NEAR(tp.p_center_in_world.y(), 0.0, 1e-9);
    EXPECT_NEAR(tp.p_center_in_world.z(), x * std::sin(theta), 1e-9);
    EXPECT_NEAR((tp.R_track_to_world.col(0) - Vector3d(std::cos(theta), 0, std::sin(theta))).norm(), 0.0, 1e-12);
  }
}

// Circular arc of radius R, length L, turning left: end point R (sin(L/R), 1 - cos(L/R)) and heading L/R.
// The heading is integrated exactly; the 10-point Gauss rule on <= 2 m pieces integrates cos/sin of it to
// round-off, so the error is accumulated round-off over ~600 stations: 1e-9 m. Interior points are
// cubic-Hermite interpolated: error <= h^4 kappa^3 / 384 ~ 1e-12 m for h = 0.5 m, so also 1e-9 m.
TEST(TrackGeometry, CircularArcEndsAtAnalyticPointAndHeading) {
  for (double sign : {1.0, -1.0}) {
    const double R = 500.0, L = 300.0;
    rc::GeometrySpec spec;
    spec.segments = {circular(L, sign / R)};
    spec.table_step = 0.5;
    const rc::TrackGeometry geom(spec);
    rc::TrackPoint tp;
    for (double s : {L, 123.456, 0.3}) {
      geom.centre(s, tp);
      const double a = s / R;
      EXPECT_NEAR(tp.p_center_in_world.x(), R * std::sin(a), 1e-9);
      EXPECT_NEAR(tp.p_center_in_world.y(), sign * R * (1.0 - std::cos(a)), 1e-9);
      EXPECT_NEAR(tp.p_center_in_world.z(), 0.0, 1e-12);
      const Vector3d t = tp.R_track_to_world.col(0);
      EXPECT_NEAR(std::atan2(t.y(), t.x()), sign * a, 1e-12);
      EXPECT_NEAR(tp.curvature, sign / R, 1e-15);
    }
  }
}

// On a gradient the plan view is scaled by cos(theta) (s is the 3-D arc length, kappa = d heading / ds):
// end = cos(theta) R (sin(L/R), 1 - cos(L/R)), z = L sin(theta). Same round-off tolerance as above.
TEST(TrackGeometry, CircularArcOnGradient) {
  const double R = 400.0, L = 250.0, g = 0.035, theta = std::atan(g);
  rc::GeometrySpec spec;
  spec.segments = {circular(L, 1.0 / R, 0.0, g)};
  spec.table_step = 0.5;
  const rc::TrackGeometry geom(spec);
  rc::TrackPoint tp;
  geom.centre(L, tp);
  EXPECT_NEAR(tp.p_center_in_world.x(), std::cos(theta) * R * std::sin(L / R), 1e-9);
  EXPECT_NEAR(tp.p_center_in_world.y(), std::cos(theta) * R * (1.0 - std::cos(L / R)), 1e-9);
  EXPECT_NEAR(tp.p_center_in_world.z(), L * std::sin(theta), 1e-9);
}

// Clothoid 0 -> 1/300 1/m over 100 m against the Fresnel power series. The requirement is 1e-6 m; the
// quadrature is exact to round-off, so 1e-9 m is asserted (accumulated round-off over 400 stations).
TEST(TrackGeometry, ClothoidMatchesFresnelSeries) {
  const double L = 100.0, k1 = 1.0 / 300.0, c = k1 / L;
  rc::GeometrySpec spec;
  spec.segments = {transition(L, 0.0, k1)};
  spec.table_step = 0.25;
  const rc::TrackGeometry geom(spec);
  rc::TrackPoint tp;
  for (double s : {L, 77.7, 31.31}) {
    double X, Y;
    clothoidSeries(c, s, X, Y);
    geom.centre(s, tp);
    EXPECT_NEAR(tp.p_center_in_world.x(), X, 1e-9) << "s = " << s;
    EXPECT_NEAR(tp.p_center_in_world.y(), Y, 1e-9) << "s = " << s;
    const Vector3d t = tp.R_track_to_world.col(0);
    EXPECT_NEAR(std::atan2(t.y(), t.x()), 0.5 * c * s * s, 1e-12);
  }
}

// A 1 km alignment (straight, clothoid, circular arc, reverse clothoid, straight) against a reference
// composed segment by segment from closed forms and the Fresnel series (the exit clothoid is the entry
// clothoid reversed: displacement Rot(dpsi) (X, -Y)). Requirement: < 1 mm over 1 km; asserted 1e-6 m.
TEST(TrackGeometry, OneKilometreAlignmentMatchesComposedReference) {
  const double R = 800.0, k = 1.0 / R, Lt = 120.0, Lc = 400.0;
  rc::GeometrySpec spec;
  spec.segments = {straight(200.0), transition(Lt, 0.0, k), circular(Lc, k), transition(Lt, k, 0.0), straight(160.0)};
  spec.table_step = 1.0;
  const rc::TrackGeometry geom(spec);

  double X, Y;
  clothoidSeries(k / Lt, Lt, X, Y);
  const double dpsi_t = 0.5 * k * Lt;
  Vector3d p(200.0, 0.0, 0.0);
  double psi = 0.0;
  p += rotZ(psi) * Vector3d(X, Y, 0.0);  // entry clothoid
  psi += dpsi_t;
  p += rotZ(psi) * Vector3d(R * std::sin(Lc / R), R * (1.0 - std::cos(Lc / R)), 0.0);  // arc
  psi += Lc / R;
  p += rotZ(psi) * rotZ(dpsi_t) * Vector3d(X, -Y, 0.0);  // exit clothoid
  psi += dpsi_t;
  p += rotZ(psi) * Vector3d(160.0, 0.0, 0.0);

  rc::TrackPoint tp;
  geom.centre(geom.sEnd(), tp);
  EXPECT_NEAR((tp.p_center_in_world - p).norm(), 0.0, 1e-6);
  const Vector3d t = tp.R_track_to_world.col(0);
  EXPECT_NEAR(std::atan2(t.y(), t.x()), psi, 1e-12);
}

// Canted circular curve: both rail origins at rail_half_spacing from the centre, their height difference
// (right - left) = cant * (2 rail_half_spacing / cant_reference_width), all frames orthonormal, rails
// tilted by the inclination toward the track centre. Exact relations evaluated through the interpolated
// table: the frames are rotations of each other, so 1e-12 (round-off) except positions (1e-9 m).
TEST(TrackGeometry, CantedCurveRailsAndFrames) {
  const double cant = 0.15, e = 1.5, h = 0.7525, beta = std::atan(0.05);
  rc::GeometrySpec spec;
  spec.segments = {circular(300.0, 1.0 / 800.0, cant)};
  spec.cant_reference_width = e;
  spec.rail_half_spacing = h;
  spec.rail_inclination = beta;
  spec.table_step = 0.5;
  const rc::TrackGeometry geom(spec);
  rc::TrackPoint tp;
  rc::RailPoint left, right;
  for (double s : {0.0, 10.11, 150.0, 299.9}) {
    geom.centre(s, tp);
    geom.rail(rc::RailSide::kLeft, s, left);
    geom.rail(rc::RailSide::kRight, s, right);
    EXPECT_NEAR((left.p_origin_in_world - tp.p_center_in_world).norm(), h, 1e-9);
    EXPECT_NEAR((right.p_origin_in_world - tp.p_center_in_world).norm(), h, 1e-9);
    EXPECT_NEAR(right.p_origin_in_world.z() - left.p_origin_in_world.z(), cant * 2.0 * h / e, 1e-9);
    EXPECT_NEAR(tp.cant_angle, std::asin(cant / e), 1e-12);
    EXPECT_LT(orthonormalityError(tp.R_track_to_world), 1e-12);
    EXPECT_LT(orthonormalityError(left.R_rail_to_world), 1e-12);
    EXPECT_LT(orthonormalityError(right.R_rail_to_world), 1e-12);
    // Cant leans the track's up axis to the left (toward the raised right rail's opposite side).
    const Vector3d b = tp.R_track_to_world.col(2), n = tp.R_track_to_world.col(1), t = tp.R_track_to_world.col(0);
    const Vector3d left_horizontal = Vector3d::UnitZ().cross(t).normalized();
    EXPECT_NEAR(b.dot(left_horizontal), cant / e, 1e-12);
    // Rails: up axes tilted by beta toward the centre (left rail toward -n, right rail toward +n).
    EXPECT_NEAR(left.R_rail_to_world.col(2).dot(b), std::cos(beta), 1e-12);
    EXPECT_NEAR(left.R_rail_to_world.col(2).dot(n), -std::sin(beta), 1e-12);
    EXPECT_NEAR(right.R_rail_to_world.col(2).dot(n), std::sin(beta), 1e-12);
    EXPECT_EQ(left.lateral_sign, -1.0);
    EXPECT_EQ(right.lateral_sign, 1.0);
  }
}

// On a transition with a cant ramp, the rails' height difference follows the ramp: 2 h sin(phi(s)) with
// sin(phi) = D(s) / e, D linear. Hermite interpolation of the rail curves between stations: error
// O(h^4 |p''''|) < 1e-12 m for these smooth curves; 1e-9 m asserted.
TEST(TrackGeometry, CantRampHeightDifference) {
  const double e = 1.5, h = 0.75;
  rc::GeometrySpec spec;
  spec.segments = {straight(20.0), transition(80.0, 0.0, 1.0 / 600.0, 0.0, 0.16), circular(50.0, 1.0 / 600.0, 0.16)};
  spec.cant_reference_width = e;
  spec.rail_half_spacing = h;
  spec.table_step = 0.3;
  const rc::TrackGeometry geom(spec);
  rc::RailPoint left, right;
  for (double s : {27.77, 60.0, 99.01}) {
    const double D = 0.16 * (s - 20.0) / 80.0;
    EXPECT_NEAR(geom.designCant(s), D, 1e-15);
    geom.rail(rc::RailSide::kLeft, s, left);
    geom.rail(rc::RailSide::kRight, s, right);
    EXPECT_NEAR(right.p_origin_in_world.z() - left.p_origin_in_world.z(), 2.0 * h * D / e, 1e-9) << "s = " << s;
    EXPECT_LT(orthonormalityError(left.R_rail_to_world), 1e-12);
    EXPECT_LT(orthonormalityError(right.R_rail_to_world), 1e-12);
  }
}

namespace {

rc::GeometrySpec rampSpec() {
  rc::GeometrySpec spec;
  spec.segments = {straight(15.0, 0.0, 0.01), transition(60.0, 0.0, -1.0 / 250.0, 0.0, -0.12, 0.01),
                   circular(40.0, -1.0 / 250.0, -0.12, 0.01)};
  spec.cant_reference_width = 1.5;
  spec.rail_half_spacing = 0.7525;
  spec.rail_vertical_offset = 0.01;
  spec.rail_inclination = std::atan(0.05);
  spec.table_step = 0.1;
  return spec;
}

rc::Irregularities psdIrregularities() {
  rc::PsdRealisationSpec p;
  p.spectrum = rc::PsdSpectrum::kFraClass4;
  p.wavelength_min = 2.0;
  p.wavelength_max = 50.0;
  p.seed = 7;
  p.harmonics = 256;
  return rc::Irregularities::fromPsd(p);
}

// Central differences of frames and positions at s with step ds; truncation error ds^2/6 |f'''|.
void checkDerivatives(const rc::TrackGeometry& geom, double s, double tol) {
  const double ds = 1e-4;
  rc::TrackPoint a, b, c;
  geom.centre(s - ds, a);
  geom.centre(s + ds, b);
  geom.centre(s, c);
  EXPECT_LT(((b.p_center_in_world - a.p_center_in_world) / (2 * ds) - c.dp_ds).cwiseAbs().maxCoeff(), tol);
  EXPECT_LT(((b.R_track_to_world - a.R_track_to_world) / (2 * ds) - c.dR_ds).cwiseAbs().maxCoeff(), tol);
  for (rc::RailSide side : {rc::RailSide::kLeft, rc::RailSide::kRight}) {
    rc::RailPoint ra, rb, rp;
    geom.rail(side, s - ds, ra);
    geom.rail(side, s + ds, rb);
    geom.rail(side, s, rp);
    EXPECT_LT(((rb.p_origin_in_world - ra.p_origin_in_world) / (2 * ds) - rp.dp_origin_ds).cwiseAbs().maxCoeff(), tol);
    EXPECT_LT(((rb.R_rail_to_world - ra.R_rail_to_world) / (2 * ds) - rp.dR_ds).cwiseAbs().maxCoeff(), tol);
  }
}

}  // namespace

// d/ds of the interpolated centre and rail frames equals their central difference (step 1e-4 m). The
// interpolant is a cubic per cell (then orthonormalised, derivative propagated exactly), so what remains
// is the truncation ds^2/6 |f'''| < 1e-10 and the round-off |p| eps / ds ~ 100 m * 2.2e-16 / 1e-4 = 2e-10
// (measured: 1.6e-10): tolerance 2e-9. Points are chosen inside cells. Without and with irregularities.
TEST(TrackGeometry, FrameDerivativesMatchFiniteDifferences) {
  const rc::TrackGeometry plain(rampSpec());
  const rc::TrackGeometry rough(rampSpec(), psdIrregularities());
  for (double s : {5.037, 33.333, 61.049, 98.76}) {
    checkDerivatives(plain, s, 2e-9);
    checkDerivatives(rough, s, 2e-9);
  }
}

// Rail surface partial derivatives (for the contact Newton iteration) against central differences, for a
// profile y(u) = u, z(u) = -u^2 / (2 * 0.3) (a 0.3 m crown). In u the point is quadratic, so the central
// difference is exact up to round-off; in s as above. Tolerance 2e-9 (measured 1.6e-10).
TEST(TrackGeometry, RailSurfaceDerivativesMatchFiniteDifferences) {
  const double rho = 0.3;
  auto y = [](double u) { return u; };
  auto z = [rho](double u) { return -u * u / (2 * rho); };
  const rc::TrackGeometry plain(rampSpec());
  const rc::TrackGeometry rough(rampSpec(), psdIrregularities());
  for (const rc::TrackGeometry* g : {&plain, &rough}) {
    for (rc::RailSide side : {rc::RailSide::kLeft, rc::RailSide::kRight}) {
      for (double s : {7.77, 40.404, 80.08}) {
        for (double u : {-0.03, 0.0, 0.021}) {
          const rc::RailSurfacePoint p = g->railSurface(side, s, y(u), z(u), 1.0, -u / rho);
          const double ds = 1e-4, du = 1e-5;
          const rc::RailSurfacePoint ps1 = g->railSurface(side, s + ds, y(u), z(u), 1.0, -u / rho);
          const rc::RailSurfacePoint ps0 = g->railSurface(side, s - ds, y(u), z(u), 1.0, -u / rho);
          const rc::RailSurfacePoint pu1 = g->railSurface(side, s, y(u + du), z(u + du), 1.0, -(u + du) / rho);
          const rc::RailSurfacePoint pu0 = g->railSurface(side, s, y(u - du), z(u - du), 1.0, -(u - du) / rho);
          EXPECT_LT(((ps1.r - ps0.r) / (2 * ds) - p.dr_ds).cwiseAbs().maxCoeff(), 2e-9);
          EXPECT_LT(((pu1.r - pu0.r) / (2 * du) - p.dr_du).cwiseAbs().maxCoeff(), 2e-9);
        }
      }
    }
  }
}

// The tabulated node slopes must be the true derivatives: then the Hermite tables converge at fourth
// order (error ratio 16 when the step halves); wrong node slopes would leave a first-order error (ratio 2).
// Rail origins and frames with irregularities (lambda_min 2 m), steps 0.25 and 0.125 m against 0.02 m,
// away from segment junctions (where the rail curve has a slope kink, see doc/geometry.md). Asserted:
// ratio > 10, and the 0.25 m error below 1e-5 (m, frame entries): Hermite bound h^4/384 |o^(4)| ~ 1e-6
// for |o^(4)| ~ 0.1 1/m^3 (measured 1.0e-6 m and 2.7e-6).
TEST(TrackGeometry, RailTablesConvergeAtFourthOrder) {
  rc::GeometrySpec spec = rampSpec();
  const rc::Irregularities irr = psdIrregularities();
  spec.table_step = 0.02;
  const rc::TrackGeometry fine(spec, irr);
  double err_p[2] = {0, 0}, err_R[2] = {0, 0};
  const double steps[2] = {0.25, 0.125};
  for (int k = 0; k < 2; ++k) {
    spec.table_step = steps[k];
    const rc::TrackGeometry coarse(spec, irr);
    for (int i = 0; i < 2000; ++i) {
      const double s = 20.0 + 50.0 * i / 2000.0;
      for (rc::RailSide side : {rc::RailSide::kLeft, rc::RailSide::kRight}) {
        rc::RailPoint x, y;
        coarse.rail(side, s, x);
        fine.rail(side, s, y);
        err_p[k] = std::max(err_p[k], (x.p_origin_in_world - y.p_origin_in_world).norm());
        err_R[k] = std::max(err_R[k], (x.R_rail_to_world - y.R_rail_to_world).cwiseAbs().maxCoeff());
      }
    }
  }
  EXPECT_LT(err_p[0], 1e-5);
  EXPECT_LT(err_R[0], 1e-5);
  EXPECT_GT(err_p[0] / err_p[1], 10.0);
  EXPECT_GT(err_R[0] / err_R[1], 10.0);
}

// The profile's lateral coordinate points toward the track centre on both rails.
TEST(TrackGeometry, ProfileLateralAxisPointsToTrackCentre) {
  rc::GeometrySpec spec;
  spec.segments = {straight(10.0)};
  spec.rail_half_spacing = 0.75;
  spec.table_step = 0.5;
  const rc::TrackGeometry geom(spec);
  for (rc::RailSide side : {rc::RailSide::kLeft, rc::RailSide::kRight}) {
    rc::RailPoint rp;
    geom.rail(side, 5.0, rp);
    const rc::RailSurfacePoint p = rc::TrackGeometry::railSurface(rp, 0.01, 0.0, 1.0, 0.0);
    EXPECT_NEAR(std::abs(p.r.y()), 0.74, 1e-12);  // 1 cm closer to the centre line (y = 0)
  }
}

// Irregularities move the rails as documented: left rail lateral a + g/2, vertical v - c/2; right rail
// lateral a - g/2, vertical v + c/2; the rail frames roll by -c/e (right rail up). A constant table gives
// exact displacements: tolerance 1e-12 m (round-off).
TEST(TrackGeometry, IrregularitiesDisplaceRailsPerEn13848Conventions) {
  const double a = 0.003, v = 0.002, c = 0.004, g = 0.006, e = 1.5, h = 0.75;
  std::istringstream csv(
      "s, alignment, level, cross level, gauge\n-10, 0.003, 0.002, 0.004, 0.006\n"
      "500, 0.003, 0.002, 0.004, 0.006\n");
  const rc::Irregularities irr = rc::Irregularities::fromCsvStream(csv, "constant.csv");
  rc::GeometrySpec spec;
  spec.segments = {straight(100.0)};
  spec.cant_reference_width = e;
  spec.rail_half_spacing = h;
  spec.table_step = 0.5;
  const rc::TrackGeometry geom(spec, irr);
  EXPECT_TRUE(geom.hasIrregularities());
  rc::RailPoint left, right;
  geom.rail(rc::RailSide::kLeft, 42.42, left);
  geom.rail(rc::RailSide::kRight, 42.42, right);
  EXPECT_NEAR(left.p_origin_in_world.y(), h + a + g / 2, 1e-12);
  EXPECT_NEAR(left.p_origin_in_world.z(), v - c / 2, 1e-12);
  EXPECT_NEAR(right.p_origin_in_world.y(), -h + a - g / 2, 1e-12);
  EXPECT_NEAR(right.p_origin_in_world.z(), v + c / 2, 1e-12);
  EXPECT_NEAR(left.R_rail_to_world.col(2).y(), std::sin(c / e), 1e-12);
  EXPECT_NEAR(right.R_rail_to_world.col(2).y(), std::sin(c / e), 1e-12);
}

// "No irregularities" builds exactly the plain geometry (the per-step path is identical).
TEST(TrackGeometry, NoIrregularitiesIsThePlainGeometry) {
  const rc::TrackGeometry plain(rampSpec());
  const rc::TrackGeometry none(rampSpec(), rc::Irregularities());
  EXPECT_FALSE(none.hasIrregularities());
  rc::RailPoint a, b;
  plain.rail(rc::RailSide::kRight, 50.5, a);
  none.rail(rc::RailSide::kRight, 50.5, b);
  EXPECT_EQ(a.p_origin_in_world, b.p_origin_in_world);
  EXPECT_EQ(a.R_rail_to_world, b.R_rail_to_world);
}

// Local defects against their analytic shapes (track_defects.hpp): a dipped joint of total angle 0.01 rad
// over 2 m on the left rail (depth alpha L / 2 = 5 mm at the joint, slopes -/+ alpha on its two ramps) and a
// weld dip of 0.3 mm over 0.2 m on both rails move the rail origin along the rail frame's b axis by z(s) and
// its slope by z'(s) b; the slope agrees with central differences of the position; a rail without the defect,
// and any point beyond a defect, is the plain geometry to the last bit.
TEST(TrackGeometry, LocalDefectsAddTheirAnalyticShapeAlongTheRailNormal) {
  rc::GeometrySpec spec;
  spec.segments = {straight(100.0)};
  spec.table_step = 0.5;
  rc::RailDefect joint;
  joint.shape = rc::DefectShape::kDippedJoint;
  joint.s_centre = 40.0;
  joint.length = 2.0;
  joint.dip_angle = 0.01;
  joint.right = false;
  rc::RailDefect weld;
  weld.shape = rc::DefectShape::kWeld;
  weld.s_centre = 60.0;
  weld.length = 0.2;
  weld.height = -3e-4;
  const rc::TrackGeometry plain(spec);
  const rc::TrackGeometry with(spec, rc::Irregularities(), rc::TrackDefects({weld, joint}));
  auto height = [&](rc::RailSide side, double s, double& z, double& slope) {
    rc::RailPoint a, b;
    plain.rail(side, s, a);
    with.rail(side, s, b);
    z = (b.p_origin_in_world - a.p_origin_in_world).dot(a.R_rail_to_world.col(2));
    slope = (b.dp_origin_ds - a.dp_origin_ds).dot(a.R_rail_to_world.col(2));
    EXPECT_LT((b.p_origin_in_world - a.p_origin_in_world - z * a.R_rail_to_world.col(2)).norm(), 1e-13);
  };
  const double alpha = 0.005, k = 2.0 * M_PI / 0.2;
  const struct {
    rc::RailSide side;
    double s, z, slope;
  } expected[] = {
      {rc::RailSide::kLeft, 40.0 - 1e-6, -alpha * (1.0 - 1e-6), -alpha},  // either side of the joint
      {rc::RailSide::kLeft, 40.0 + 1e-6, -alpha * (1.0 - 1e-6), alpha},
      {rc::RailSide::kLeft, 39.5, -alpha * 0.5, -alpha},
      {rc::RailSide::kLeft, 40.75, -alpha * 0.25, alpha},
      {rc::RailSide::kRight, 60.0, -3e-4, 0.0},
      {rc::RailSide::kLeft, 60.05, -1.5e-4, 1.5e-4 * k},
      {rc::RailSide::kRight, 59.97, -1.5e-4 * (1.0 + std::cos(k * 0.03)), -1.5e-4 * k * std::sin(k * 0.03)},
  };
  for (const auto& e : expected) {
    SCOPED_TRACE(e.s);
    double z = 0.0, slope = 0.0;
    height(e.side, e.s, z, slope);
    EXPECT_NEAR(z, e.z, 1e-13);  // the plain geometry's round-off at s ~ 50 m
    EXPECT_NEAR(slope, e.slope, 1e-12);
    if (std::abs(e.s - 40.0) > 1e-3) {  // away from the kink: the slope is the position's derivative
      double zp = 0.0, zm = 0.0, unused = 0.0;
      const double ds = 1e-5;
      height(e.side, e.s + ds, zp, unused);
      height(e.side, e.s - ds, zm, unused);
      EXPECT_NEAR((zp - zm) / (2.0 * ds), slope, 1e-7 * (1.0 + std::abs(slope)));
    }
  }
  for (const auto& [side, s] : {std::pair{rc::RailSide::kRight, 40.0}, std::pair{rc::RailSide::kLeft, 41.01},
                                std::pair{rc::RailSide::kLeft, 59.89}, std::pair{rc::RailSide::kRight, 70.0}}) {
    rc::RailPoint a, b;
    plain.rail(side, s, a);
    with.rail(side, s, b);
    EXPECT_EQ(a.p_origin_in_world, b.p_origin_in_world) << s;
    EXPECT_EQ(a.dp_origin_ds, b.dp_origin_ds) << s;
  }
}

// A joint with a 20 mm gap bridged by wheels of radius 0.46 m: beside the V of the dip, within 10 mm of
// the joint the rail is lowered by the drop of the wheel centre pivoting on the rail end behind it (then on
// the one ahead), r - sqrt(r^2 - u^2) with u = g/2 - |x| (109 um at the joint, 0 at the rail ends), its
// slope -/+ u / sqrt(r^2 - u^2) (21.7 mrad at the joint: the kink the wheel meets); the slope agrees with
// central differences; beyond the gap the plain V.
TEST(TrackGeometry, JointGapLowersTheRailByTheBridgingWheelsDrop) {
  rc::GeometrySpec spec;
  spec.segments = {straight(100.0)};
  spec.table_step = 0.5;
  rc::RailDefect joint;
  joint.shape = rc::DefectShape::kDippedJoint;
  joint.s_centre = 40.0;
  joint.length = 2.0;
  joint.dip_angle = 0.01;
  joint.gap = 0.02;
  joint.wheel_radius = 0.46;
  rc::RailDefect closed = joint;
  closed.gap = 0.0;
  const rc::TrackGeometry plain(spec);
  const rc::TrackGeometry with_gap(spec, rc::Irregularities(), rc::TrackDefects({joint}));
  const rc::TrackGeometry without(spec, rc::Irregularities(), rc::TrackDefects({closed}));
  auto height = [&](const rc::TrackGeometry& g, double s, double& z, double& slope) {
    rc::RailPoint a, b;
    plain.rail(rc::RailSide::kRight, s, a);
    g.rail(rc::RailSide::kRight, s, b);
    z = (b.p_origin_in_world - a.p_origin_in_world).dot(a.R_rail_to_world.col(2));
    slope = (b.dp_origin_ds - a.dp_origin_ds).dot(a.R_rail_to_world.col(2));
  };
  const double r = 0.46, alpha = 0.005;
  for (const double x : {-0.0099, -0.006, -1e-6, 1e-6, 0.003, 0.0095}) {
    SCOPED_TRACE(x);
    const double u = 0.01 - std::abs(x), root = std::sqrt(r * r - u * u);
    double z = 0.0, slope = 0.0;
    height(with_gap, 40.0 + x, z, slope);
    EXPECT_NEAR(z, -alpha * (1.0 - std::abs(x)) - (r - root), 1e-13);
    EXPECT_NEAR(slope, (x < 0.0 ? -1.0 : 1.0) * (alpha + u / root), 1e-12);
    if (std::abs(x) > 1e-4) {
      double zp = 0.0, zm = 0.0, unused = 0.0;
      const double ds = 1e-7;
      height(with_gap, 40.0 + x + ds, zp, unused);
      height(with_gap, 40.0 + x - ds, zm, unused);
      EXPECT_NEAR((zp - zm) / (2.0 * ds), slope, 1e-6 * (1.0 + std::abs(slope)));
    }
  }
  double z_centre = 0.0, unused = 0.0;
  height(with_gap, 40.0, z_centre, unused);
  EXPECT_NEAR(z_centre, -alpha - (r - std::sqrt(r * r - 1e-4)), 1e-13);
  EXPECT_NEAR(r - std::sqrt(r * r - 1e-4), 1.087e-4, 1e-7);  // the figure the comment gives
  for (const double s : {39.98, 40.011, 40.5}) {             // beyond the gap: the closed joint to the last bit
    double z1 = 0.0, s1 = 0.0, z0 = 0.0, s0 = 0.0;
    height(with_gap, s, z1, s1);
    height(without, s, z0, s0);
    EXPECT_EQ(z1, z0) << s;
    EXPECT_EQ(s1, s0) << s;
  }
}

TEST(TrackGeometry, OutOfRangeThrowsWithValue) {
  rc::GeometrySpec spec;
  spec.s_start = 10.0;
  spec.segments = {straight(100.0)};
  const rc::TrackGeometry geom(spec);
  rc::TrackPoint tp;
  try {
    geom.centre(111.5, tp);
    FAIL() << "no exception";
  } catch (const std::runtime_error& ex) {
    EXPECT_NE(std::string(ex.what()).find("s = 111.5 m outside the track [10, 110] m"), std::string::npos) << ex.what();
  }
  EXPECT_THROW(geom.centre(9.0, tp), std::runtime_error);
  EXPECT_THROW(geom.centre(std::nan(""), tp), std::runtime_error);
  EXPECT_NO_THROW(geom.centre(110.0, tp));
}

namespace {
std::string buildError(const rc::GeometrySpec& spec, const rc::Irregularities& irr = rc::Irregularities()) {
  try {
    const rc::TrackGeometry g(spec, irr);
  } catch (const std::runtime_error& ex) {
    return ex.what();
  }
  return "no exception";
}
}  // namespace

TEST(TrackGeometry, BadSpecThrowsNamingFieldAndValue) {
  rc::GeometrySpec spec;
  spec.segments = {straight(10.0), straight(-5.0)};
  EXPECT_NE(buildError(spec).find("segments[1].length = -5 m must be positive"), std::string::npos) << buildError(spec);
  spec.segments = {circular(10.0, 0.01, 1.6)};
  EXPECT_NE(buildError(spec).find("segments[0].cant = 1.6 m"), std::string::npos) << buildError(spec);
  spec.segments = {straight(10.0)};
  spec.segments[0].curvature_start = 0.001;
  EXPECT_NE(buildError(spec).find("straight"), std::string::npos) << buildError(spec);
  spec.segments = {};
  EXPECT_NE(buildError(spec).find("no segments"), std::string::npos);
  spec.segments = {straight(10.0)};
  spec.cant_reference_width = 0.0;
  EXPECT_NE(buildError(spec).find("cant_reference_width = 0 m must be positive"), std::string::npos);
  spec.cant_reference_width = 1.5;
  spec.table_step = 0.5;
  EXPECT_NE(buildError(spec, psdIrregularities()).find("too coarse"), std::string::npos);  // lambda_min 2 m
}

// EN 13803: equilibrium cant D_eq = e V^2 / (g R). Checked against a hand value and against the standard's
// practical form D_eq[mm] = 11.8 V[km/h]^2 / R[m] for e = 1500 mm (11.8 is 1500 / (9.81 * 3.6^2) = 11.797
// rounded, hence the 0.1 % tolerance).
TEST(CantHelpers, CantAngleEquilibriumCantAndDeficiency) {
  EXPECT_NEAR(rc::cantAngle(0.15, 1.5), std::asin(0.1), 1e-15);
  EXPECT_NEAR(rc::cantAngle(-0.15, 1.5), -std::asin(0.1), 1e-15);
  EXPECT_THROW(rc::cantAngle(1.6, 1.5), std::runtime_error);
  EXPECT_THROW(rc::cantAngle(0.1, 0.0), std::runtime_error);
  // Hand value: 1.5 * 50^2 / (9.81 * 1000) = 3750 / 9810 = 0.38226299694...
  EXPECT_NEAR(rc::equilibriumCant(1.5, 50.0, 1000.0), 0.382262996942, 1e-12);
  const double V_kmh = 200.0, R = 2000.0;
  const double D_eq = rc::equilibriumCant(1.5, V_kmh / 3.6, R);
  const double practical = 11.8 * V_kmh * V_kmh / R * 1e-3;  // m
  EXPECT_NEAR(D_eq, practical, 1e-3 * practical);
  // Deficiency I = D_eq - D: 0.236 m equilibrium with 0.150 m applied is 0.086 m deficient.
  EXPECT_NEAR(rc::cantDeficiency(0.236, 0.150), 0.086, 1e-15);
  EXPECT_NEAR(rc::cantDeficiency(0.100, 0.150), -0.050, 1e-15);  // excess cant is negative deficiency
  EXPECT_THROW(rc::equilibriumCant(1.5, 50.0, 0.0), std::runtime_error);
}
