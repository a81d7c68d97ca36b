// Track geometry: centre-line integration, tabulation and interpolation of the track and rail frames.
#include "rail_contact/track_geometry.hpp"
#include "rail_contact/format.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rail {
namespace contact {

namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr double kPi = 3.14159265358979323846;

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error("track geometry: " + what); }

std::string segField(std::size_t j, const char* field) { return "segments[" + std::to_string(j) + "]." + field; }

void requireFinite(double v, const std::string& name) {
  if (!std::isfinite(v)) fail(name + " = " + formatNumber(v) + " is not a finite number");
}

// Skew-symmetric matrix [w]x: [w]x v = w x v.
Matrix3d skew(const Vector3d& w) {
  Matrix3d S;
  S << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return S;
}

// Orthonormal right-handed frame [t n b] from a tangent direction a (not normalised) and an approximate
// lateral direction m, by Gram-Schmidt: t = a/|a|, n = (m - t (t.m)) normalised, b = t x n; with the
// exact derivatives t', n', b' given a' and m'.
void orthonormalFrame(const Vector3d& a, const Vector3d& da, const Vector3d& m, const Vector3d& dm, Matrix3d& R,
                      Matrix3d& dR) {
  const double a_norm = a.norm();
  const Vector3d t = a / a_norm;
  const Vector3d dt = (da - t * t.dot(da)) / a_norm;
  const double tm = t.dot(m);
  const Vector3d w = m - t * tm;
  const Vector3d dw = dm - dt * tm - t * (dt.dot(m) + t.dot(dm));
  const double w_norm = w.norm();
  const Vector3d n = w / w_norm;
  const Vector3d dn = (dw - n * n.dot(dw)) / w_norm;
  R.col(0) = t;
  R.col(1) = n;
  R.col(2) = t.cross(n);
  dR.col(0) = dt;
  dR.col(1) = dn;
  dR.col(2) = dt.cross(n) + t.cross(dn);
}

// 10-point Gauss-Legendre nodes and weights on [-1, 1] (Abramowitz & Stegun, Table 25.4).
constexpr int kGaussPoints = 10;
constexpr double kGaussX[kGaussPoints] = {
    -0.9739065285171717, -0.8650633666889845, -0.6794095682990244, -0.4333953941292472, -0.1488743389816312,
    0.1488743389816312,  0.4333953941292472,  0.6794095682990244,  0.8650633666889845,  0.9739065285171717};
constexpr double kGaussW[kGaussPoints] = {
    0.0666713443086881, 0.1494513491505806, 0.2190863625159820, 0.2692667193099963, 0.2955242247147529,
    0.2955242247147529, 0.2692667193099963, 0.2190863625159820, 0.1494513491505806, 0.0666713443086881};

// Longest sub-interval of one Gauss-Legendre rule (m). The integrand cos/sin of a heading that is at most
// quadratic in s is entire; with |d heading/ds| <= 1/rail_half_spacing the 10-point rule on 2 m is exact to
// round-off for any railway curvature (error term ~ (h kappa)^20 / 20!).
constexpr double kMaxQuadratureStep = 2.0;

// Curvature, cant and their derivatives on one segment at local arc length x in [0, L].
struct SegmentState {
  double kappa, dkappa;  // 1/m, 1/m^2
  double cant, dcant;    // m, 1
};

SegmentState segmentState(const SegmentSpec& seg, double x) {
  SegmentState st;
  if (seg.type == SegmentSpec::Type::Transition) {
    st.dkappa = (seg.curvature_end - seg.curvature_start) / seg.length;
    st.dcant = (seg.cant_end - seg.cant_start) / seg.length;
    st.kappa = seg.curvature_start + st.dkappa * x;
    st.cant = seg.cant_start + st.dcant * x;
  } else {
    st.dkappa = 0.0;
    st.dcant = 0.0;
    st.kappa = seg.type == SegmentSpec::Type::Straight ? 0.0 : seg.curvature_start;
    st.cant = seg.cant_start;
  }
  return st;
}

// Heading at local x of a segment whose heading at x = 0 is psi0: psi0 + integral of kappa.
double segmentHeading(const SegmentSpec& seg, double psi0, double x) {
  const SegmentState st0 = segmentState(seg, 0.0);
  return psi0 + st0.kappa * x + 0.5 * st0.dkappa * x * x;
}

// Integral of the unit tangent over local arc length [xa, xb] of a segment (composite Gauss-Legendre).
Vector3d integrateTangent(const SegmentSpec& seg, double psi0, double xa, double xb) {
  const double theta = std::atan(seg.gradient);
  const double c_theta = std::cos(theta), s_theta = std::sin(theta);
  const int pieces = std::max(1, static_cast<int>(std::ceil((xb - xa) / kMaxQuadratureStep)));
  const double dx = (xb - xa) / pieces;
  double ix = 0.0, iy = 0.0;
  for (int p = 0; p < pieces; ++p) {
    const double mid = xa + (p + 0.5) * dx;
    double sx = 0.0, sy = 0.0;
    for (int g = 0; g < kGaussPoints; ++g) {
      const double psi = segmentHeading(seg, psi0, mid + 0.5 * dx * kGaussX[g]);
      sx += kGaussW[g] * std::cos(psi);
      sy += kGaussW[g] * std::sin(psi);
    }
    ix += 0.5 * dx * sx;
    iy += 0.5 * dx * sy;
  }
  return Vector3d(c_theta * ix, c_theta * iy, s_theta * (xb - xa));
}

// Design state of the centre line at one station: position, frame and its first two derivatives.
struct CentreState {
  Vector3d p, t, dt;    // position, tangent, d t / ds
  Matrix3d R, dR, ddR;  // [t n b] and derivatives
  double kappa, phi;    // curvature, cant angle
};

CentreState centreState(const SegmentSpec& seg, const Vector3d& p, double psi, double x, double e) {
  const SegmentState st = segmentState(seg, x);
  const double theta = std::atan(seg.gradient);
  const double ct = std::cos(theta), sth = std::sin(theta);
  const double cp = std::cos(psi), sp = std::sin(psi);
  const Vector3d t(ct * cp, ct * sp, sth);
  const Vector3d n0(-sp, cp, 0.0);
  const Vector3d b0(-sth * cp, -sth * sp, ct);
  // Cant: roll about t by alpha = -phi (positive cant raises the right rail).
  const double phi = std::asin(st.cant / e);
  const double dphi = st.dcant / (e * std::cos(phi));
  const double ddphi = (st.dcant / e) * (st.dcant / e) * std::sin(phi) / std::pow(std::cos(phi), 3);
  const double alpha = -phi, dalpha = -dphi, ddalpha = -ddphi;
  const double ca = std::cos(alpha), sa = std::sin(alpha);
  CentreState cs;
  cs.p = p;
  cs.R.col(0) = t;
  cs.R.col(1) = ca * n0 + sa * b0;
  cs.R.col(2) = -sa * n0 + ca * b0;
  // Angular rate per unit s (world frame): heading rate about z, cant rate about t (gradient constant).
  const Vector3d ez = Vector3d::UnitZ();
  const Vector3d omega = st.kappa * ez + dalpha * t;
  cs.dR = skew(omega) * cs.R;
  const Vector3d dt = cs.dR.col(0);
  const Vector3d domega = st.dkappa * ez + ddalpha * t + dalpha * dt;
  cs.ddR = skew(domega) * cs.R + skew(omega) * cs.dR;
  cs.t = t;
  cs.dt = dt;
  cs.kappa = st.kappa;
  cs.phi = phi;
  return cs;
}

// Cubic Hermite basis on tau in [0, 1] and its tau-derivative.
struct Hermite {
  double h00, h10, h01, h11;
  double d00, d10, d01, d11;
  explicit Hermite(double tau) {
    const double t2 = tau * tau, t3 = t2 * tau;
    h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
    h10 = t3 - 2.0 * t2 + tau;
    h01 = -2.0 * t3 + 3.0 * t2;
    h11 = t3 - t2;
    d00 = 6.0 * t2 - 6.0 * tau;
    d10 = 3.0 * t2 - 4.0 * tau + 1.0;
    d01 = -d00;
    d11 = 3.0 * t2 - 2.0 * tau;
  }
};

}  // namespace

TrackGeometry::TrackGeometry(const GeometrySpec& spec, const Irregularities& irregularities, TrackDefects defects)
    : spec_(spec), defects_(std::move(defects)) {
  // ---- validation ----
  requireFinite(spec.s_start, "s_start");
  requireFinite(spec.cant_reference_width, "cant_reference_width");
  requireFinite(spec.rail_half_spacing, "rail_half_spacing");
  requireFinite(spec.rail_vertical_offset, "rail_vertical_offset");
  requireFinite(spec.rail_inclination, "rail_inclination");
  requireFinite(spec.table_step, "table_step");
  if (spec.segments.empty()) fail("no segments");
  if (spec.cant_reference_width <= 0.0)
    fail("cant_reference_width = " + formatNumber(spec.cant_reference_width) + " m must be positive");
  if (spec.rail_half_spacing <= 0.0)
    fail("rail_half_spacing = " + formatNumber(spec.rail_half_spacing) + " m must be positive");
  if (std::abs(spec.rail_inclination) >= 0.25 * kPi)
    fail("rail_inclination = " + formatNumber(spec.rail_inclination) +
         " rad is not a rail inclination (|value| < pi/4)");
  if (spec.table_step <= 0.0) fail("table_step = " + formatNumber(spec.table_step) + " m must be positive");
  const double e = spec.cant_reference_width;
  double total = 0.0;
  for (std::size_t j = 0; j < spec.segments.size(); ++j) {
    const SegmentSpec& seg = spec.segments[j];
    requireFinite(seg.length, segField(j, "length"));
    requireFinite(seg.curvature_start, segField(j, "curvature_start"));
    requireFinite(seg.curvature_end, segField(j, "curvature_end"));
    requireFinite(seg.cant_start, segField(j, "cant_start"));
    requireFinite(seg.cant_end, segField(j, "cant_end"));
    requireFinite(seg.gradient, segField(j, "gradient"));
    if (seg.length <= 0.0) fail(segField(j, "length") + " = " + formatNumber(seg.length) + " m must be positive");
    if (seg.type == SegmentSpec::Type::Straight && seg.curvature_start != 0.0)
      fail(segField(j, "curvature_start") + " = " + formatNumber(seg.curvature_start) + " 1/m on a straight segment");
    const bool ramp = seg.type == SegmentSpec::Type::Transition;
    for (double kappa : {seg.curvature_start, ramp ? seg.curvature_end : seg.curvature_start}) {
      if (std::abs(kappa) * spec.rail_half_spacing >= 1.0)
        fail(segField(j, "curvature") + " = " + formatNumber(kappa) + " 1/m: radius below rail_half_spacing " +
             formatNumber(spec.rail_half_spacing) + " m");
    }
    for (double cant : {seg.cant_start, ramp ? seg.cant_end : seg.cant_start}) {
      if (std::abs(cant) >= e)
        fail(segField(j, "cant") + " = " + formatNumber(cant) + " m is not smaller than cant_reference_width " +
             formatNumber(e) + " m");
    }
    if (std::abs(seg.gradient) >= 1.0)
      fail(segField(j, "gradient") + " = " + formatNumber(seg.gradient) + " is not a railway gradient (|g| < 1)");
    total += seg.length;
  }
  has_irregularities_ = !irregularities.empty();
  if (has_irregularities_) {
    const double lambda_min = irregularities.shortestWavelength();
    if (spec.table_step > lambda_min / 8.0)
      fail("table_step = " + formatNumber(spec.table_step) + " m too coarse for irregularity wavelengths down to " +
           formatNumber(lambda_min) + " m (need <= " + formatNumber(lambda_min / 8.0) + " m)");
  }
  const double n_real = std::ceil(total / spec.table_step - 1e-9);
  if (n_real > 2.0e7)
    fail("table of " + formatNumber(n_real) + " intervals (track " + formatNumber(total) + " m, table_step " +
         formatNumber(spec.table_step) + " m) is too large");

  s_start_ = spec.s_start;
  s_end_ = spec.s_start + total;
  n_intervals_ = std::max(1, static_cast<int>(n_real));
  h_ = total / n_intervals_;

  // ---- segment start states: arc length, heading, position ----
  const std::size_t n_seg = spec.segments.size();
  segment_s0_.resize(n_seg + 1);
  std::vector<double> psi0(n_seg + 1);
  std::vector<Vector3d> p0(n_seg + 1);
  segment_s0_[0] = s_start_;
  psi0[0] = 0.0;
  p0[0].setZero();
  for (std::size_t j = 0; j < n_seg; ++j) {
    const SegmentSpec& seg = spec.segments[j];
    segment_s0_[j + 1] = segment_s0_[j] + seg.length;
    psi0[j + 1] = segmentHeading(seg, psi0[j], seg.length);
    p0[j + 1] = p0[j] + integrateTangent(seg, psi0[j], 0.0, seg.length);
  }
  segment_s0_[n_seg] = s_end_;

  // ---- irregularities sampled at the stations ----
  const int n_nodes = n_intervals_ + 1;
  std::vector<IrregularityState> irr;
  if (has_irregularities_) {
    irr.resize(n_nodes);
    irregularities.sampleUniform(s_start_, h_, irr);
  }

  // ---- stations ----
  centre_nodes_.resize(n_nodes);
  rail_nodes_[0].resize(n_nodes);
  rail_nodes_[1].resize(n_nodes);
  curvature_nodes_.resize(n_nodes);
  cant_angle_nodes_.resize(n_nodes);
  const double h_rail = spec.rail_half_spacing, v_rail = spec.rail_vertical_offset, beta = spec.rail_inclination;
  int prev_seg = -1;
  double prev_x = 0.0;
  Vector3d prev_p = Vector3d::Zero();
  for (int i = 0; i < n_nodes; ++i) {
    const double s = (i == n_intervals_) ? s_end_ : s_start_ + i * h_;
    const int j = segmentIndex(s);
    const SegmentSpec& seg = spec.segments[j];
    const double x = std::min(std::max(s - segment_s0_[j], 0.0), seg.length);
    Vector3d p;
    if (j == prev_seg)
      p = prev_p + integrateTangent(seg, psi0[j], prev_x, x);
    else
      p = p0[j] + integrateTangent(seg, psi0[j], 0.0, x);
    prev_seg = j;
    prev_x = x;
    prev_p = p;
    const CentreState cs = centreState(seg, p, segmentHeading(seg, psi0[j], x), x, e);
    Node& cn = centre_nodes_[i];
    cn.p = cs.p;
    cn.dp = cs.t;
    cn.R = cs.R;
    cn.dR = cs.dR;
    curvature_nodes_[i] = cs.kappa;
    cant_angle_nodes_[i] = cs.phi;

    // Rails. side_sign: +1 left rail (at +n), -1 right rail.
    const Vector3d n = cs.R.col(1), b = cs.R.col(2);
    const Vector3d dn = cs.dR.col(1), db = cs.dR.col(2);
    const Vector3d ddn = cs.ddR.col(1), ddb = cs.ddR.col(2);
    for (int side = 0; side < 2; ++side) {
      const double side_sign = side == 0 ? 1.0 : -1.0;
      // Irregularity displacements of this rail along n and b and the extra roll, with derivatives.
      double dl = 0, dl1 = 0, dl2 = 0, dv = 0, dv1 = 0, dv2 = 0, roll = 0, roll1 = 0;
      if (has_irregularities_) {
        const IrregularityState& q = irr[i];
        dl = q.value.alignment + 0.5 * side_sign * q.value.gauge;
        dl1 = q.d_ds.alignment + 0.5 * side_sign * q.d_ds.gauge;
        dl2 = q.d2_ds2.alignment + 0.5 * side_sign * q.d2_ds2.gauge;
        dv = q.value.vertical_level - 0.5 * side_sign * q.value.cross_level;
        dv1 = q.d_ds.vertical_level - 0.5 * side_sign * q.d_ds.cross_level;
        dv2 = q.d2_ds2.vertical_level - 0.5 * side_sign * q.d2_ds2.cross_level;
        roll = -q.value.cross_level / e;  // small-angle roll of the rail seat (right rail up for c > 0)
        roll1 = -q.d_ds.cross_level / e;
      }
      const double lat = side_sign * h_rail + dl;
      const double ver = v_rail + dv;
      Node& rn = rail_nodes_[side][i];
      rn.p = cs.p + lat * n + ver * b;
      const Vector3d d_origin = cs.t + lat * dn + dl1 * n + ver * db + dv1 * b;
      const Vector3d dd_origin = cs.dt + lat * ddn + 2.0 * dl1 * dn + dl2 * n + ver * ddb + 2.0 * dv1 * db + dv2 * b;
      rn.dp = d_origin;
      // Lateral axis: the track lateral axis rolled about t by the inclination (toward the centre) and
      // the cross-level roll, then made orthogonal to the rail's own tangent.
      const double a = side_sign * beta + roll;
      const double ca = std::cos(a), sa = std::sin(a);
      const Vector3d m = ca * n + sa * b;
      const Vector3d dm = ca * dn + sa * db + roll1 * (-sa * n + ca * b);
      orthonormalFrame(d_origin, dd_origin, m, dm, rn.R, rn.dR);
    }
  }
}

int TrackGeometry::segmentIndex(double s) const {
  // Last segment start <= s (a station on a boundary belongs to the following segment).
  const auto it = std::upper_bound(segment_s0_.begin(), segment_s0_.end() - 1, s);
  const int j = static_cast<int>(it - segment_s0_.begin()) - 1;
  return std::min(std::max(j, 0), static_cast<int>(spec_.segments.size()) - 1);
}

int TrackGeometry::cellIndex(double s, double& tau) const {
  const double tol = 1e-9 * (1.0 + std::abs(s_end_));
  if (!(s >= s_start_ - tol && s <= s_end_ + tol))
    throw std::runtime_error("track geometry: s = " + formatNumber(s) + " m outside the track [" +
                             formatNumber(s_start_) + ", " + formatNumber(s_end_) + "] m");
  const double u = (s - s_start_) / h_;
  int i = static_cast<int>(std::floor(u));
  i = std::min(std::max(i, 0), n_intervals_ - 1);
  tau = u - i;
  return i;
}

namespace {

// Hermite interpolation of one station pair: position, its s-derivative, frame columns and their
// s-derivatives, then re-orthonormalised frame with its exact derivative.
void interpolateNodes(const Eigen::Vector3d& p0, const Eigen::Vector3d& dp0, const Eigen::Matrix3d& R0,
                      const Eigen::Matrix3d& dR0, const Eigen::Vector3d& p1, const Eigen::Vector3d& dp1,
                      const Eigen::Matrix3d& R1, const Eigen::Matrix3d& dR1, double tau, double h, Eigen::Vector3d& p,
                      Eigen::Vector3d& dp, Eigen::Matrix3d& R, Eigen::Matrix3d& dR) {
  const Hermite H(tau);
  p = H.h00 * p0 + (H.h10 * h) * dp0 + H.h01 * p1 + (H.h11 * h) * dp1;
  dp = (H.d00 * p0 + H.d01 * p1) / h + H.d10 * dp0 + H.d11 * dp1;
  const Eigen::Vector3d c0 =
      H.h00 * R0.col(0) + (H.h10 * h) * dR0.col(0) + H.h01 * R1.col(0) + (H.h11 * h) * dR1.col(0);
  const Eigen::Vector3d dc0 = (H.d00 * R0.col(0) + H.d01 * R1.col(0)) / h + H.d10 * dR0.col(0) + H.d11 * dR1.col(0);
  const Eigen::Vector3d c1 =
      H.h00 * R0.col(1) + (H.h10 * h) * dR0.col(1) + H.h01 * R1.col(1) + (H.h11 * h) * dR1.col(1);
  const Eigen::Vector3d dc1 = (H.d00 * R0.col(1) + H.d01 * R1.col(1)) / h + H.d10 * dR0.col(1) + H.d11 * dR1.col(1);
  orthonormalFrame(c0, dc0, c1, dc1, R, dR);
}

}  // namespace

void TrackGeometry::centre(double s, TrackPoint& out) const {
  double tau;
  const int i = cellIndex(s, tau);
  const Node& a = centre_nodes_[i];
  const Node& b = centre_nodes_[i + 1];
  interpolateNodes(a.p, a.dp, a.R, a.dR, b.p, b.dp, b.R, b.dR, tau, h_, out.p_center_in_world, out.dp_ds,
                   out.R_track_to_world, out.dR_ds);
  out.curvature = (1.0 - tau) * curvature_nodes_[i] + tau * curvature_nodes_[i + 1];
  out.cant_angle = (1.0 - tau) * cant_angle_nodes_[i] + tau * cant_angle_nodes_[i + 1];
}

void TrackGeometry::rail(RailSide side, double s, RailPoint& out) const {
  double tau;
  const int i = cellIndex(s, tau);
  const std::vector<Node>& nodes = rail_nodes_[static_cast<int>(side)];
  const Node& a = nodes[i];
  const Node& b = nodes[i + 1];
  interpolateNodes(a.p, a.dp, a.R, a.dR, b.p, b.dp, b.R, b.dR, tau, h_, out.p_origin_in_world, out.dp_origin_ds,
                   out.R_rail_to_world, out.dR_ds);
  out.lateral_sign = side == RailSide::kLeft ? -1.0 : 1.0;
  if (defects_.empty()) return;
  double z, dz_ds;
  defects_.evaluate(side, s, z, dz_ds);
  if (z == 0.0 && dz_ds == 0.0) return;
  // The defect's height along the rail frame's b axis: p += z b, dp/ds += z' b + z db/ds.
  out.p_origin_in_world += z * out.R_rail_to_world.col(2);
  out.dp_origin_ds += dz_ds * out.R_rail_to_world.col(2) + z * out.dR_ds.col(2);
}

RailSurfacePoint TrackGeometry::railSurface(const RailPoint& rail, double y, double z, double dy_du, double dz_du) {
  const double ly = rail.lateral_sign * y;
  RailSurfacePoint out;
  out.r = rail.p_origin_in_world + ly * rail.R_rail_to_world.col(1) + z * rail.R_rail_to_world.col(2);
  out.dr_ds = rail.dp_origin_ds + ly * rail.dR_ds.col(1) + z * rail.dR_ds.col(2);
  out.dr_du = (rail.lateral_sign * dy_du) * rail.R_rail_to_world.col(1) + dz_du * rail.R_rail_to_world.col(2);
  return out;
}

RailSurfacePoint TrackGeometry::railSurface(RailSide side, double s_r, double y, double z, double dy_du,
                                            double dz_du) const {
  RailPoint rp;
  rail(side, s_r, rp);
  return railSurface(rp, y, z, dy_du, dz_du);
}

double TrackGeometry::designCant(double s) const {
  double tau;
  cellIndex(s, tau);  // range check
  const int j = segmentIndex(s);
  const SegmentSpec& seg = spec_.segments[j];
  return segmentState(seg, std::min(std::max(s - segment_s0_[j], 0.0), seg.length)).cant;
}

double TrackGeometry::designCurvature(double s) const {
  double tau;
  cellIndex(s, tau);
  const int j = segmentIndex(s);
  const SegmentSpec& seg = spec_.segments[j];
  return segmentState(seg, std::min(std::max(s - segment_s0_[j], 0.0), seg.length)).kappa;
}

double cantAngle(double cant, double cant_reference_width) {
  if (!(cant_reference_width > 0.0) || !std::isfinite(cant_reference_width))
    throw std::runtime_error("cant_angle: cant_reference_width = " + formatNumber(cant_reference_width) +
                             " m must be positive");
  if (!(std::abs(cant) < cant_reference_width))
    throw std::runtime_error("cant_angle: cant = " + formatNumber(cant) +
                             " m is not smaller than the cant reference width " + formatNumber(cant_reference_width) +
                             " m");
  return std::asin(cant / cant_reference_width);
}

double equilibriumCant(double cant_reference_width, double speed, double radius, double g) {
  if (!(cant_reference_width > 0.0) || !std::isfinite(cant_reference_width))
    throw std::runtime_error("equilibrium_cant: cant_reference_width = " + formatNumber(cant_reference_width) +
                             " m must be positive");
  if (!(radius > 0.0) || !std::isfinite(radius))
    throw std::runtime_error("equilibrium_cant: radius = " + formatNumber(radius) + " m must be positive");
  if (!(g > 0.0) || !std::isfinite(g))
    throw std::runtime_error("equilibrium_cant: g = " + formatNumber(g) + " m/s^2 must be positive");
  if (!std::isfinite(speed)) throw std::runtime_error("equilibrium_cant: speed = " + formatNumber(speed) + " m/s");
  return cant_reference_width * speed * speed / (g * radius);
}

double cantDeficiency(double equilibrium_cant_value, double applied_cant) {
  return equilibrium_cant_value - applied_cant;
}

}  // namespace contact
}  // namespace rail
