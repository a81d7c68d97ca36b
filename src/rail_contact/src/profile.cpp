// Profile interpolant (arc-length cubic spline) and generic profile measurements: rail tilt, top and
// gauge points, wheel tread/flange split, flange height, thickness and back-face position.
#include "rail_contact/profile.hpp"
#include "rail_contact/format.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace rail {
namespace contact {

namespace {

// Knot values x (strictly increasing) and 2-D values Y; returns per-interval coefficients of the C2
// cubic spline with not-a-knot end conditions (at least 4 points).
struct RawSegment {
  Eigen::Vector2d a, b, c, d;  // p(t) = a + b t + c t^2 + d t^3, t in [0, h]
};

std::vector<RawSegment> splineNotAKnot(const std::vector<double>& x, const ProfilePoints& Y) {
  const int n = static_cast<int>(x.size());
  const int m = n - 1;  // intervals
  std::vector<double> h(m);
  std::vector<Eigen::Vector2d> slope(m);
  for (int i = 0; i < m; ++i) {
    h[i] = x[i + 1] - x[i];
    slope[i] = (Y[i + 1] - Y[i]) / h[i];
  }
  // Unknowns: second derivatives M_1 .. M_{n-2}; M_0 and M_{n-1} eliminated by the not-a-knot
  // conditions (third derivative continuous at x_1 and x_{n-2}).
  const int k = n - 2;
  std::vector<double> lo(k, 0.0), di(k, 0.0), up(k, 0.0);
  std::vector<Eigen::Vector2d> rhs(k);
  for (int r = 0; r < k; ++r) {
    const int i = r + 1;
    lo[r] = h[i - 1];
    di[r] = 2.0 * (h[i - 1] + h[i]);
    up[r] = h[i];
    rhs[r] = 6.0 * (slope[i] - slope[i - 1]);
  }
  // M_0 = (1 + h0/h1) M_1 - (h0/h1) M_2
  const double q0 = h[0] / h[1];
  di[0] += h[0] * (1.0 + q0);
  up[0] -= h[0] * q0;
  // M_{n-1} = (1 + h_{m-1}/h_{m-2}) M_{n-2} - (h_{m-1}/h_{m-2}) M_{n-3}
  const double q1 = h[m - 1] / h[m - 2];
  di[k - 1] += h[m - 1] * (1.0 + q1);
  lo[k - 1] -= h[m - 1] * q1;
  // Thomas algorithm (the system is diagonally dominant for reasonable knot spacings).
  for (int r = 1; r < k; ++r) {
    const double w = lo[r] / di[r - 1];
    di[r] -= w * up[r - 1];
    rhs[r] -= w * rhs[r - 1];
  }
  std::vector<Eigen::Vector2d> M(n);
  M[k] = rhs[k - 1] / di[k - 1];
  for (int r = k - 2; r >= 0; --r) M[r + 1] = (rhs[r] - up[r] * M[r + 2]) / di[r];
  M[0] = (1.0 + q0) * M[1] - q0 * M[2];
  M[n - 1] = (1.0 + q1) * M[n - 2] - q1 * M[n - 3];

  std::vector<RawSegment> seg(m);
  for (int i = 0; i < m; ++i) {
    seg[i].a = Y[i];
    seg[i].b = slope[i] - h[i] * (2.0 * M[i] + M[i + 1]) / 6.0;
    seg[i].c = 0.5 * M[i];
    seg[i].d = (M[i + 1] - M[i]) / (6.0 * h[i]);
  }
  return seg;
}

inline Eigen::Vector2d rawDeriv(const RawSegment& s, double t) { return s.b + t * (2.0 * s.c + 3.0 * t * s.d); }
inline Eigen::Vector2d rawPos(const RawSegment& s, double t) { return s.a + t * (s.b + t * (s.c + t * s.d)); }

// 5-point Gauss-Legendre nodes and weights on [-1, 1].
constexpr double kGlX[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640};
constexpr double kGlW[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                            0.2369268850561891};

// Arc length of a raw segment over [0, t].
double rawArcLength(const RawSegment& s, double t) {
  double sum = 0.0;
  for (int q = 0; q < 5; ++q) sum += kGlW[q] * rawDeriv(s, 0.5 * t * (kGlX[q] + 1.0)).norm();
  return 0.5 * t * sum;
}

}  // namespace

// ----------------------------------------------------------------------------------------------------

ProfileCurve::ProfileCurve(const ProfilePoints& points_yz, SolidSide side, const ProfileCurveOptions& options)
    : side_(side), normal_sign_(side == SolidSide::Right ? 1.0 : -1.0) {
  if (!(options.ds > 0.0) || !std::isfinite(options.ds))
    throw std::invalid_argument("ProfileCurve: node spacing ds must be positive, got " + formatNumber(options.ds));
  if (points_yz.size() < 4)
    throw std::invalid_argument("ProfileCurve: at least 4 points needed, got " + std::to_string(points_yz.size()));
  // Stage 1: spline with chord-length knots through the input points.
  std::vector<double> x(points_yz.size(), 0.0);
  for (size_t i = 0; i < points_yz.size(); ++i) {
    if (!points_yz[i].allFinite())
      throw std::invalid_argument("ProfileCurve: non-finite point at index " + std::to_string(i));
    if (i > 0) {
      const double chord = (points_yz[i] - points_yz[i - 1]).norm();
      if (!(chord > 0.0)) throw std::invalid_argument("ProfileCurve: repeated point at index " + std::to_string(i));
      x[i] = x[i - 1] + chord;
    }
  }
  const std::vector<RawSegment> raw = splineNotAKnot(x, points_yz);
  std::vector<double> s_node(raw.size() + 1, 0.0);  // arc length at the stage-1 knots
  for (size_t i = 0; i < raw.size(); ++i) s_node[i + 1] = s_node[i] + rawArcLength(raw[i], x[i + 1] - x[i]);
  length_ = s_node.back();

  // Stage 2: resample at uniform arc length.
  const int n_seg = std::max(3, static_cast<int>(std::ceil(length_ / options.ds)));
  h_ = length_ / n_seg;
  ProfilePoints resampled(n_seg + 1);
  std::vector<double> u_knots(n_seg + 1);
  size_t j = 0;
  for (int k = 0; k <= n_seg; ++k) {
    const double target = (k == n_seg) ? length_ : k * h_;
    u_knots[k] = target;
    while (j + 1 < raw.size() && s_node[j + 1] <= target) ++j;
    const RawSegment& s = raw[j];
    const double hj = x[j + 1] - x[j];
    const double local = target - s_node[j];
    const double seg_len = s_node[j + 1] - s_node[j];
    double t = std::clamp(hj * local / seg_len, 0.0, hj);
    for (int it = 0; it < 30; ++it) {  // Newton on arc length, bracketed by [0, hj]
      const double f = rawArcLength(s, t) - local;
      const double step = f / rawDeriv(s, t).norm();
      t = std::clamp(t - step, 0.0, hj);
      if (std::abs(step) < 1e-15 * (1.0 + hj)) break;
    }
    resampled[k] = rawPos(s, t);
  }

  // Stage 3: spline with u = arc length at uniform knots.
  const std::vector<RawSegment> fin = splineNotAKnot(u_knots, resampled);
  coef_.resize(fin.size());
  for (size_t i = 0; i < fin.size(); ++i) coef_[i] = Segment{fin[i].a, fin[i].b, fin[i].c, fin[i].d};
}

int ProfileCurve::segment(double u) const {
  const int last = static_cast<int>(coef_.size()) - 1;
  if (!(u > 0.0)) return 0;  // also catches NaN
  const int k = static_cast<int>(u / h_);
  return k > last ? last : k;
}

void ProfileCurve::derivatives(double u, Eigen::Vector2d& p, Eigen::Vector2d& dp, Eigen::Vector2d& d2p) const {
  if (u < 0.0 || u > length_) {
    // Continue along the end tangent.
    const bool before = u < 0.0;
    const Segment& s = before ? coef_.front() : coef_.back();
    const double t_end = before ? 0.0 : h_;
    const double u_end = before ? 0.0 : length_;
    const Eigen::Vector2d p_end = s.a + t_end * (s.b + t_end * (s.c + t_end * s.d));
    Eigen::Vector2d tan_end = s.b + t_end * (2.0 * s.c + 3.0 * t_end * s.d);
    tan_end.normalize();
    p = p_end + (u - u_end) * tan_end;
    dp = tan_end;
    d2p.setZero();
    return;
  }
  const int k = segment(u);
  const Segment& s = coef_[k];
  const double t = u - k * h_;
  p = s.a + t * (s.b + t * (s.c + t * s.d));
  dp = s.b + t * (2.0 * s.c + 3.0 * t * s.d);
  d2p = 2.0 * s.c + 6.0 * t * s.d;
}

void ProfileCurve::evaluate(double u, ProfileEval& out) const {
  Eigen::Vector2d dp, d2p;
  derivatives(u, out.p, dp, d2p);
  const double speed = dp.norm();
  out.t = dp / speed;
  out.n = normal_sign_ * Eigen::Vector2d(-out.t.y(), out.t.x());
  // Counter-clockwise curvature (y' z'' - z' y'') / |p'|^3; convex-positive sign for the solid side.
  const double k_ccw = (dp.x() * d2p.y() - dp.y() * d2p.x()) / (speed * speed * speed);
  out.kappa = -normal_sign_ * k_ccw;
}

Eigen::Vector2d ProfileCurve::position(double u) const {
  Eigen::Vector2d p, dp, d2p;
  derivatives(u, p, dp, d2p);
  return p;
}

Eigen::Vector2d ProfileCurve::tangent(double u) const {
  Eigen::Vector2d p, dp, d2p;
  derivatives(u, p, dp, d2p);
  return dp.normalized();
}

Eigen::Vector2d ProfileCurve::normal(double u) const {
  const Eigen::Vector2d t = tangent(u);
  return normal_sign_ * Eigen::Vector2d(-t.y(), t.x());
}

double ProfileCurve::curvature(double u) const {
  ProfileEval e;
  evaluate(u, e);
  return e.kappa;
}

ProfilePoints ProfileCurve::nodes() const {
  ProfilePoints out;
  out.reserve(coef_.size() + 1);
  for (const Segment& s : coef_) out.push_back(s.a);
  out.push_back(position(length_));
  return out;
}

double ProfileCurve::closestParameter(const Eigen::Vector2d& q, double* distance_out) const {
  // Closest node, then Newton on (p(u) - q) . p'(u) = 0 within the curve's range.
  int best = 0;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= numSegments(); ++k) {
    const double d2 = (position(std::min(k * h_, length_)) - q).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best = k;
    }
  }
  double u = std::min(best * h_, length_);
  for (int it = 0; it < 50; ++it) {
    Eigen::Vector2d p, dp, d2p;
    derivatives(u, p, dp, d2p);
    const double f = (p - q).dot(dp);
    double fp = dp.squaredNorm() + (p - q).dot(d2p);
    if (fp <= 0.0) fp = dp.squaredNorm();
    const double u_new = std::clamp(u - f / fp, 0.0, length_);
    const double step = u_new - u;
    u = u_new;
    if (std::abs(step) < 1e-14) break;
  }
  if (distance_out) *distance_out = (position(u) - q).norm();
  return u;
}

bool ProfileCurve::findCoordinate(int axis, double value, double u_from, double u_to, double& u_out) const {
  if (axis != 0 && axis != 1) throw std::invalid_argument("ProfileCurve::findCoordinate: axis must be 0 or 1");
  u_from = std::clamp(u_from, 0.0, length_);
  u_to = std::clamp(u_to, 0.0, length_);
  const double span = u_to - u_from;
  const int n_steps = std::max(1, static_cast<int>(std::ceil(std::abs(span) / (0.25 * h_))));
  auto g = [&](double u) { return position(u)[axis] - value; };
  double ua = u_from;
  double ga = g(ua);
  if (ga == 0.0) {
    u_out = ua;
    return true;
  }
  for (int i = 1; i <= n_steps; ++i) {
    const double ub = u_from + span * i / n_steps;
    const double gb = g(ub);
    if ((ga < 0.0) != (gb < 0.0) || gb == 0.0) {
      double lo = ua, hi = ub, glo = ga;
      for (int it = 0; it < 200 && std::abs(hi - lo) > 1e-15; ++it) {
        const double mid = 0.5 * (lo + hi);
        const double gm = g(mid);
        if ((gm < 0.0) == (glo < 0.0)) {
          lo = mid;
          glo = gm;
        } else {
          hi = mid;
        }
      }
      u_out = 0.5 * (lo + hi);
      return true;
    }
    ua = ub;
    ga = gb;
  }
  return false;
}

// ----------------------------------------------------------------------------------------------------
// Rail helpers

ProfilePoints tiltProfile(const ProfilePoints& points_yz, double inclination) {
  if (!std::isfinite(inclination) || std::abs(inclination) > 1.0)
    throw std::invalid_argument("tiltProfile: inclination must be a finite slope |i| <= 1, got " +
                                std::to_string(inclination));
  const double a = std::atan(inclination);
  const double c = std::cos(a), s = std::sin(a);
  ProfilePoints out(points_yz.size());
  // Rotation by -a in the (y, z) plane: the rail axis (0, 1) becomes (sin a, cos a).
  for (size_t i = 0; i < points_yz.size(); ++i) {
    const Eigen::Vector2d& p = points_yz[i];
    out[i] = Eigen::Vector2d(c * p.x() + s * p.y(), -s * p.x() + c * p.y());
  }
  return out;
}

namespace {

// Parameter of the extremum of coordinate `axis` (max if sign = +1, min if sign = -1) over a curve:
// best node, then Newton on the derivative of the coordinate.
double extremumParameter(const ProfileCurve& curve, int axis, double sign) {
  const ProfilePoints nodes = curve.nodes();
  const double h = curve.uMax() / curve.numSegments();
  int best = 0;
  for (int k = 1; k < static_cast<int>(nodes.size()); ++k)
    if (sign * nodes[k][axis] > sign * nodes[best][axis]) best = k;
  double u = std::min(best * h, curve.uMax());
  if (best == 0 || best == static_cast<int>(nodes.size()) - 1) return u;
  for (int it = 0; it < 50; ++it) {
    Eigen::Vector2d p, dp, d2p;
    curve.derivatives(u, p, dp, d2p);
    if (d2p[axis] == 0.0) break;
    const double u_new = std::clamp(u - dp[axis] / d2p[axis], std::max(0.0, u - h), std::min(curve.uMax(), u + h));
    const double step = u_new - u;
    u = u_new;
    if (std::abs(step) < 1e-14) break;
  }
  return u;
}

}  // namespace

Eigen::Vector2d railTopPoint(const ProfileCurve& rail) { return rail.position(extremumParameter(rail, 1, +1.0)); }

Eigen::Vector2d gaugePoint(const ProfileCurve& rail, double depth) {
  if (!(depth > 0.0)) throw std::invalid_argument("gaugePoint: depth must be positive, got " + formatNumber(depth));
  const double u_top = extremumParameter(rail, 1, +1.0);
  const double z_level = rail.position(u_top).y() - depth;
  // The gauge side is the end of the curve with the larger y.
  const bool gauge_at_end = rail.position(rail.uMax()).x() > rail.position(rail.uMin()).x();
  double u = 0.0;
  if (!rail.findCoordinate(1, z_level, u_top, gauge_at_end ? rail.uMax() : rail.uMin(), u)) {
    std::ostringstream msg;
    msg << "gaugePoint: rail profile does not reach " << depth * 1e3 << " mm below its top on the gauge side";
    throw std::runtime_error(msg.str());
  }
  return rail.position(u);
}

Eigen::Vector2d railSectionCentre(const ProfileCurve& rail, double depth_below_top, double head_depth) {
  if (!(head_depth > 0.0) || !(depth_below_top > 0.0))
    throw std::invalid_argument("railSectionCentre: depths must be positive");
  const double u_top = extremumParameter(rail, 1, +1.0);
  const Eigen::Vector2d top = rail.position(u_top);
  const bool gauge_at_end = rail.position(rail.uMax()).x() > rail.position(rail.uMin()).x();
  // A profile cut short on one side (a measurement of the running surface and the gauge face only) is
  // measured where both sides reach; below 3 mm the crown alone says nothing: the highest point is used.
  const double u_gauge_end = gauge_at_end ? rail.uMax() : rail.uMin();
  const double u_field_end = gauge_at_end ? rail.uMin() : rail.uMax();
  const double depth =
      std::min({head_depth, top.y() - rail.position(u_gauge_end).y(), top.y() - rail.position(u_field_end).y()});
  double y_centre = top.x();
  double u_gauge = 0.0, u_field = 0.0;
  if (depth >= 3e-3 && rail.findCoordinate(1, top.y() - depth, u_top, u_gauge_end, u_gauge) &&
      rail.findCoordinate(1, top.y() - depth, u_top, u_field_end, u_field))
    y_centre = 0.5 * (rail.position(u_gauge).x() + rail.position(u_field).x());
  return Eigen::Vector2d(y_centre, top.y() - depth_below_top);
}

// ----------------------------------------------------------------------------------------------------
// Wheel helpers

WheelProfile makeWheelProfile(const ProfilePoints& points_yz, double split_angle, const ProfileCurveOptions& options) {
  if (!(split_angle > 0.0 && split_angle < 0.5 * M_PI))
    throw std::invalid_argument("makeWheelProfile: split angle must be in (0, 90) deg, got " +
                                formatNumber(split_angle * 180.0 / M_PI) + " deg");
  const ProfileCurve whole(points_yz, SolidSide::Left, options);
  double u_tape = 0.0;
  if (!whole.findCoordinate(0, 0.0, whole.uMin(), whole.uMax(), u_tape))
    throw std::runtime_error("makeWheelProfile: profile does not contain the taping line y = 0");
  const double u_tip = extremumParameter(whole, 1, -1.0);
  // Slope angle of the descent toward the flange tip: atan2(-t_z, t_y), from ~0 on the tread to the
  // flange-face angle; the split is where it first reaches split_angle.
  auto g = [&](double u) {
    const Eigen::Vector2d t = whole.tangent(u);
    return std::atan2(-t.y(), t.x()) - split_angle;
  };
  const double h = whole.uMax() / whole.numSegments();
  double ua = u_tape, ga = g(ua), u_split = -1.0;
  for (double ub = u_tape + 0.25 * h; ub <= u_tip; ub += 0.25 * h) {
    const double gb = g(ub);
    if (ga < 0.0 && gb >= 0.0) {
      double lo = ua, hi = ub;
      for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
        const double mid = 0.5 * (lo + hi);
        (g(mid) < 0.0 ? lo : hi) = mid;
      }
      u_split = 0.5 * (lo + hi);
      break;
    }
    ua = ub;
    ga = gb;
  }
  if (u_split < 0.0) {
    std::ostringstream msg;
    msg << "makeWheelProfile: profile slope never reaches " << split_angle * 180.0 / M_PI
        << " deg between the taping line and the flange tip";
    throw std::runtime_error(msg.str());
  }
  // Both surfaces are re-splined through the nodes of the whole curve plus the exact split point.
  const Eigen::Vector2d p_split = whole.position(u_split);
  ProfilePoints tread_pts, flange_pts;
  const ProfilePoints nodes = whole.nodes();
  for (int k = 0; k < static_cast<int>(nodes.size()); ++k) {
    const double u = std::min(k * h, whole.uMax());
    if (u < u_split - 0.5 * h) tread_pts.push_back(nodes[k]);
    if (u > u_split + 0.5 * h) flange_pts.push_back(nodes[k]);
  }
  tread_pts.push_back(p_split);
  flange_pts.insert(flange_pts.begin(), p_split);
  WheelProfile w;
  w.tread = ProfileCurve(tread_pts, SolidSide::Left, options);
  w.flange = ProfileCurve(flange_pts, SolidSide::Left, options);
  w.split_yz = p_split;
  w.split_angle = split_angle;
  return w;
}

double tapingLineZ(const WheelProfile& wheel) {
  double u = 0.0;
  if (!wheel.tread.findCoordinate(0, 0.0, wheel.tread.uMin(), wheel.tread.uMax(), u))
    throw std::runtime_error("tapingLineZ: the tread does not contain the taping line y = 0");
  return wheel.tread.position(u).y();
}

double flangeHeight(const WheelProfile& wheel) {
  const double z_tip = wheel.flange.position(extremumParameter(wheel.flange, 1, -1.0)).y();
  return tapingLineZ(wheel) - z_tip;
}

double flangeBackY(const WheelProfile& wheel) {
  return wheel.flange.position(extremumParameter(wheel.flange, 0, +1.0)).x();
}

double flangeThickness(const WheelProfile& wheel, double height) {
  const double z_level = tapingLineZ(wheel) - height;
  // Gauge-side flange face: first crossing of z_level going from the tread toward the flange tip.
  double u = 0.0;
  double y_face = 0.0;
  const double u_tip = extremumParameter(wheel.flange, 1, -1.0);
  if (wheel.split_yz.y() > z_level && wheel.flange.findCoordinate(1, z_level, 0.0, u_tip, u)) {
    y_face = wheel.flange.position(u).x();
  } else if (wheel.tread.findCoordinate(1, z_level, wheel.tread.uMin(), wheel.tread.uMax(), u)) {
    y_face = wheel.tread.position(u).x();
  } else {
    std::ostringstream msg;
    msg << "flangeThickness: the flange face does not reach " << height * 1e3 << " mm above the taping line";
    throw std::runtime_error(msg.str());
  }
  return flangeBackY(wheel) - y_face;
}

}  // namespace contact
}  // namespace rail
