// Standard profiles: UIC60 (60E1) rail head from EN 13674-1's arcs, S1002 wheel from EN 13715's
// piecewise definition.
#include "rail_contact/format.hpp"
#include "rail_contact/profile.hpp"

#include <algorithm>
#include <cmath>

namespace rail {
namespace contact {

namespace {

// Appends points of p(s), s in [s0, s1], about every ds of arc length (length_estimate in the same
// unit as ds); the first point is skipped if skip_first (shared with the previous piece).
template <class F>
void appendPiece(ProfilePoints& out, F p, double s0, double s1, double length_estimate, double ds, bool skip_first) {
  const int n = std::max(2, static_cast<int>(std::ceil(length_estimate / ds)));
  for (int i = skip_first ? 1 : 0; i <= n; ++i) out.push_back(p(s0 + (s1 - s0) * i / n));
}

// ----------------------------------------------------------------------------------------------------
// UIC60 (60E1) head, EN 13674-1. Arc radii R300 (crown), R80, R13 (gauge corner) and the 1:20 head
// flank; the arcs meet tangentially at the half widths 20.456/2, 52.053/2 and 72.000/2 mm (breakpoint
// widths of the 60E1 drawing as tabulated in the GENSYS documentation, "Creation of a rail profile
// from a drawing", gensys.se/doc_html/kpf/create_UIC60.html). Millimetres, z up, gauge side y > 0.
struct Uic60Head {
  static constexpr double R1 = 300.0, R2 = 80.0, R3 = 13.0;
  static constexpr double X1 = 20.456 / 2.0, X2 = 52.053 / 2.0, X3 = 72.000 / 2.0;
  // Arc centres (gauge side) and end angles measured from the upward vertical.
  double c1y, c1z, phi1;
  double c2y, c2z, phi2;
  double c3y, c3z, phi3;
  Uic60Head() {
    c1y = 0.0;
    c1z = -R1;
    phi1 = std::asin(X1 / R1);
    c2y = c1y + (R1 - R2) * std::sin(phi1);
    c2z = c1z + (R1 - R2) * std::cos(phi1);
    phi2 = std::asin((X2 - c2y) / R2);
    c3y = c2y + (R2 - R3) * std::sin(phi2);
    c3z = c2z + (R2 - R3) * std::cos(phi2);
    phi3 = std::asin((X3 - c3y) / R3);
  }
};

}  // namespace

ProfilePoints uic60HeadPoints(double ds, double flank_depth) {
  if (!(ds > 0.0)) throw std::invalid_argument("uic60HeadPoints: ds must be positive");
  const Uic60Head g;
  const double ds_mm = ds * 1e3;
  const Eigen::Vector2d flank_start(g.c3y + Uic60Head::R3 * std::sin(g.phi3), g.c3z + Uic60Head::R3 * std::cos(g.phi3));
  const double depth_mm = flank_depth * 1e3;
  if (!(depth_mm > -flank_start.y()))
    throw std::invalid_argument("uic60HeadPoints: flank depth must exceed the R13 end depth (14.3 mm)");
  // Flank direction: tangent of R13 at its end, going down and outward.
  const Eigen::Vector2d flank_dir(std::cos(g.phi3), -std::sin(g.phi3));
  const double flank_len = (depth_mm + flank_start.y()) / std::sin(g.phi3);

  // Gauge half, from the crown centre outward, in mm.
  ProfilePoints half;
  auto arc = [](double cy, double cz, double R) {
    return [=](double phi) { return Eigen::Vector2d(cy + R * std::sin(phi), cz + R * std::cos(phi)); };
  };
  appendPiece(half, arc(g.c1y, g.c1z, Uic60Head::R1), 0.0, g.phi1, Uic60Head::R1 * g.phi1, ds_mm, false);
  appendPiece(half, arc(g.c2y, g.c2z, Uic60Head::R2), g.phi1, g.phi2, Uic60Head::R2 * (g.phi2 - g.phi1), ds_mm, true);
  appendPiece(half, arc(g.c3y, g.c3z, Uic60Head::R3), g.phi2, g.phi3, Uic60Head::R3 * (g.phi3 - g.phi2), ds_mm, true);
  appendPiece(
      half, [&](double s) { return Eigen::Vector2d(flank_start + s * flank_dir); }, 0.0, flank_len, flank_len, ds_mm,
      true);

  ProfilePoints out;
  out.reserve(2 * half.size());
  for (size_t i = half.size(); i-- > 1;) out.emplace_back(-half[i].x() * 1e-3, half[i].y() * 1e-3);
  for (const Eigen::Vector2d& p : half) out.push_back(p * 1e-3);
  return out;
}

ProfilePoints uic60SectionOutline() {
  // Head as the contact profile down to its intersection with the fishing surfaces; the rest are
  // straight lines between the main dimensions of EN 13674-1 (height 172, foot width 150, web 16.5,
  // head depth 51, foot depth 31.5 mm); fishing-surface slope 1:2.75 under the head; foot-edge
  // thickness 12 mm assumed. mm, then converted.
  const double web = 0.5 * uic60::kWebThickness * 1e3;  // half web thickness
  const double z_head = -uic60::kHeadDepth * 1e3;       // head fishing line meets the web
  const double z_foot = -(uic60::kHeight - uic60::kFootDepth) * 1e3;
  const double z_bottom = -uic60::kHeight * 1e3;
  const double foot_half = 0.5 * uic60::kFootWidth * 1e3;
  const double edge = 12.0;
  const double fishing_slope = 1.0 / 2.75;
  // Flank (y = y0 + (depth - d0) * k) meets the head underside z = z_head + (y - web) * slope.
  const Uic60Head g;
  const double y0 = g.c3y + Uic60Head::R3 * std::sin(g.phi3);
  const double d0 = -(g.c3z + Uic60Head::R3 * std::cos(g.phi3));
  const double k = 1.0 / std::tan(g.phi3);
  // depth d: y = y0 + (d - d0) k and -d = z_head + (y - web) slope  ->  solve for d.
  const double d = (-z_head - (y0 - d0 * k - web) * fishing_slope) / (1.0 + k * fishing_slope);
  const ProfilePoints head = uic60HeadPoints(0.5e-3, d * 1e-3);
  ProfilePoints out;
  // Gauge-side head corner, down and around clockwise, back up the field side.
  const std::vector<Eigen::Vector2d> lower = {
      {web, z_head},         {web, z_foot},          {foot_half, z_bottom + edge},
      {foot_half, z_bottom}, {-foot_half, z_bottom}, {-foot_half, z_bottom + edge},
      {-web, z_foot},        {-web, z_head}};
  out.push_back(head.back());
  for (const Eigen::Vector2d& p : lower) out.push_back(p * 1e-3);
  for (const Eigen::Vector2d& p : head) out.push_back(p);
  return out;
}

ProfileCurve makeUic60Rail(double inclination, const ProfileCurveOptions& options) {
  return ProfileCurve(tiltProfile(uic60HeadPoints(), inclination), SolidSide::Right, options);
}

// ----------------------------------------------------------------------------------------------------
// S1002, EN 13715. Coordinates of the standard's definition: S in mm along the axle from the taping
// line, positive toward the field side (the flange is at S < 0); F(S) in mm, the radius increase over
// the taping-line radius. Wheel profile frame: y = -S, z = -F.
// Section coefficients and bounds of EN 13715 (identical to UIC 510-2's S1002 table):
//   A: F = AA - BA S                                   S in [ 32.15796,      60]
//   B: F = AB - BB S + CB S^2 - DB S^3 + EB S^4 - FB S^5 + GB S^6 - HB S^7 + IB S^8
//                                                      S in [-26,            32.15796]
//   C: F = -AC - BC S - CC S^2 - DC S^3 - EC S^4 - FC S^5 - GC S^6 - HC S^7
//                                                      S in [-35,           -26]
//   D: F = AD - sqrt(BD^2 - (S + CD)^2)                S in [-38.426669071, -35]
//   E: F = -AE - BE S                                  S in [-39.764473993, -38.426669071]
//   F: F = AF + sqrt(BF^2 - (S + CF)^2)                S in [-49.662510381, -39.764473993]
//   G: F = AG + sqrt(BG^2 - (S + CG)^2)                S in [-62.764705882, -49.662510381]
//   H: F = AH + sqrt(BH^2 - (S + CH)^2)                S in [-70,           -62.764705882]
namespace s1002 {
constexpr double AA = 1.364323640, BA = 0.066666667;
constexpr double B[9] = {0.0,
                         3.358537058e-02,
                         1.565681624e-03,
                         2.810427944e-05,
                         5.844240864e-08,
                         1.562379023e-08,
                         5.309217349e-15,
                         5.957839843e-12,
                         2.646656573e-13};
constexpr double C[8] = {4.320221063e+03, 1.038384026e+03, 1.065501873e+02, 6.051367875,
                         2.054332446e-01, 4.169739389e-03, 4.687195829e-05, 2.252755540e-07};
constexpr double AD = 16.446, BD = 13.0, CD = 26.210665;
constexpr double AE = 93.576667419, BE = 2.747477419;
constexpr double AF = 8.834924130, BF = 20.0, CF = 58.558326413;
constexpr double AG = 16.0, BG = 12.0, CG = 55.0;
constexpr double AH = 9.519259302, BH = 20.5, CH = 49.5;
constexpr double S_AB = 32.15796, S_BC = -26.0, S_CD = -35.0, S_DE = -38.426669071, S_EF = -39.764473993,
                 S_FG = -49.662510381, S_GH = -62.764705882, S_MIN = -70.0, S_MAX = 60.0;

double sectionB(double S) {
  // Alternating signs: + - + - + - + - + for powers 0..8.
  double f = 0.0;
  for (int i = 8; i >= 0; --i) f = f * S + ((i % 2) ? -B[i] : B[i]);
  return f;
}
double sectionC(double S) {
  double f = 0.0;
  for (int i = 7; i >= 0; --i) f = f * S + C[i];
  return -f;
}
double circleRoot(double R, double x) { return std::sqrt(std::max(0.0, R * R - x * x)); }

double f(double S) {
  if (S >= S_AB) return AA - BA * S;
  if (S >= S_BC) return sectionB(S);
  if (S >= S_CD) return sectionC(S);
  if (S >= S_DE) return AD - circleRoot(BD, S + CD);
  if (S >= S_EF) return -AE - BE * S;
  if (S >= S_FG) return AF + circleRoot(BF, S + CF);
  if (S >= S_GH) return AG + circleRoot(BG, S + CG);
  return AH + circleRoot(BH, S + CH);
}
}  // namespace s1002

double s1002Z(double y) {
  const double S = -y * 1e3;
  if (!(S >= s1002::S_MIN - 1e-9 && S <= s1002::S_MAX + 1e-9))
    throw std::out_of_range("s1002Z: y = " + formatNumber(y) + " m outside [-0.060, 0.070]");
  return -s1002::f(S) * 1e-3;
}

ProfilePoints s1002Points(double ds) {
  using namespace s1002;
  if (!(ds > 0.0)) throw std::invalid_argument("s1002Points: ds must be positive");
  const double ds_mm = ds * 1e3;
  ProfilePoints mm;  // (S, F) in mm, ordered from S = 60 toward S = -70
  auto graph = [](double (*f)(double)) { return [f](double S) { return Eigen::Vector2d(S, f(S)); }; };
  auto length_of_graph = [](double (*f)(double), double a, double b) {
    double len = 0.0;
    const int n = 200;
    for (int i = 0; i < n; ++i) {
      const double s0 = a + (b - a) * i / n, s1 = a + (b - a) * (i + 1) / n;
      len += std::hypot(s1 - s0, f(s1) - f(s0));
    }
    return len;
  };
  // Arcs parametrised by their angle phi: S = -c + R sin(phi), F = a -/+ R cos(phi).
  auto arc = [](double a, double R, double c, double sgn) {
    return [=](double phi) { return Eigen::Vector2d(-c + R * std::sin(phi), a + sgn * R * std::cos(phi)); };
  };
  auto phi_of = [](double R, double c, double S) { return std::asin(std::clamp((S + c) / R, -1.0, 1.0)); };
  static double (*const fA)(double) = [](double S) { return AA - BA * S; };
  static double (*const fB)(double) = sectionB;
  static double (*const fC)(double) = sectionC;
  static double (*const fE)(double) = [](double S) { return -AE - BE * S; };

  appendPiece(mm, graph(fA), S_MAX, S_AB, length_of_graph(fA, S_MAX, S_AB), ds_mm, false);
  appendPiece(mm, graph(fB), S_AB, S_BC, length_of_graph(fB, S_AB, S_BC), ds_mm, true);
  appendPiece(mm, graph(fC), S_BC, S_CD, length_of_graph(fC, S_BC, S_CD), ds_mm, true);
  {
    const double p0 = phi_of(BD, CD, S_CD), p1 = phi_of(BD, CD, S_DE);
    appendPiece(mm, arc(AD, BD, CD, -1.0), p0, p1, BD * std::abs(p1 - p0), ds_mm, true);
  }
  appendPiece(mm, graph(fE), S_DE, S_EF, length_of_graph(fE, S_DE, S_EF), ds_mm, true);
  {
    const double p0 = phi_of(BF, CF, S_EF), p1 = phi_of(BF, CF, S_FG);
    appendPiece(mm, arc(AF, BF, CF, +1.0), p0, p1, BF * std::abs(p1 - p0), ds_mm, true);
  }
  {
    const double p0 = phi_of(BG, CG, S_FG), p1 = phi_of(BG, CG, S_GH);
    appendPiece(mm, arc(AG, BG, CG, +1.0), p0, p1, BG * std::abs(p1 - p0), ds_mm, true);
  }
  {
    const double p0 = phi_of(BH, CH, S_GH), p1 = phi_of(BH, CH, S_MIN);
    appendPiece(mm, arc(AH, BH, CH, +1.0), p0, p1, BH * std::abs(p1 - p0), ds_mm, true);
  }
  ProfilePoints out(mm.size());
  for (size_t i = 0; i < mm.size(); ++i) out[i] = Eigen::Vector2d(-mm[i].x() * 1e-3, -mm[i].y() * 1e-3);
  return out;
}

WheelProfile makeS1002(double split_angle, const ProfileCurveOptions& options) {
  return makeWheelProfile(s1002Points(), split_angle, options);
}

}  // namespace contact
}  // namespace rail
