#include "rail_contact/contact_detection.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "rail_contact/enum_words.hpp"
#include "rail_contact/format.hpp"

namespace rail {
namespace contact {

namespace {
constexpr Word<DetectionStatus> kDetectionStatusWords[] = {
    {"converged", DetectionStatus::kConverged},
    {"converged_after_search", DetectionStatus::kConvergedAfterSearch},
    {"approximate", DetectionStatus::kApproximate},
    {"out_of_bounds", DetectionStatus::kOutOfBounds},
    {"invalid_input", DetectionStatus::kInvalidInput}};
static_assert(namesEvery(kDetectionStatusWords, DetectionStatus::kInvalidInput));
}  // namespace

const char* toString(DetectionStatus status) noexcept { return wordOf(kDetectionStatusWords, status); }

std::string describe(const DetectionCounts& c) {
  std::ostringstream m;
  m.setf(std::ios::fixed);
  m.precision(2);
  m << c.calls << " contact detections, " << (c.calls > 0 ? static_cast<double>(c.newton_iterations) / c.calls : 0.0)
    << " Newton iterations each, " << c.searches << " robust searches (" << c.fallbacks
    << " after a failed warm start), " << c.skipped << " skipped far from the rail, " << c.approximations
    << " approximate";
  if (c.approximations > 0)
    m << " (Newton did not converge after the search: the search grid's point pair, within half a grid cell "
         "of the contact, was used)";
  if (c.past_end_contacts > 0)
    m << "; " << c.past_end_contacts
      << " contacts evaluated past their surface's end (a second contact on the neighbouring surface's part of "
         "the profile, beside that surface's own contact)";
  return m.str();
}

namespace {

using Eigen::Matrix3d;
using Eigen::Matrix4d;
using Eigen::Vector2d;
using Eigen::Vector3d;
using Eigen::Vector4d;

inline Vector2d perp(const Vector2d& v) { return Vector2d(-v.y(), v.x()); }  // +90 deg rotation

// Wheel frame of one pose: centre c, axle a, revolution directions d0 (s_w = 0, down) and f0 (forward),
// lateral sign of the profile y axis along a.
struct WheelFrame {
  Vector3d c, a, d0, f0;
  double ls = 1.0;
};

bool makeWheelFrame(const WheelPose& pose, WheelFrame& wf) {
  const Matrix3d& R = pose.R_wheelset_to_world;
  if (!R.allFinite() || !pose.p_wheel_in_world.allFinite() || !std::isfinite(pose.arc_length)) return false;
  wf.c = pose.p_wheel_in_world;
  const double an = R.col(1).norm();
  if (!(an > 0.5)) return false;
  wf.a = R.col(1) / an;
  const Vector3d down(0.0, 0.0, -1.0);
  Vector3d d0 = down - down.dot(wf.a) * wf.a;
  if (d0.norm() < 1e-6) d0 = -R.col(2) + R.col(2).dot(wf.a) * wf.a;  // axle vertical: wheelset -z
  wf.d0 = d0.normalized();
  wf.f0 = wf.d0.cross(wf.a);
  wf.ls = pose.side == RailSide::kLeft ? -1.0 : 1.0;
  return true;
}

constexpr int kMaxFanPlanes = 64;  // planes on each side of the lowest (the options are checked against it)

// A fan of wheel planes: circle angles th + j step, j = -n..n, and their radial directions in the wheel.
struct PlaneFan {
  int n = 0;
  double th[2 * kMaxFanPlanes + 1];
  Vector3d dir[2 * kMaxFanPlanes + 1];
};

int fanPlanes(double fan, double plane_step_max) {
  return plane_step_max > 0.0 ? static_cast<int>(std::ceil(fan / plane_step_max - 0.5)) : 0;
}

// Planes evenly across [th - fan, th + fan], at most plane_step_max apart; a fan narrower than half a step
// is the lowest plane alone.
void makePlaneFan(const WheelFrame& wf, double th, double fan, double plane_step_max, PlaneFan& out) {
  out.n = std::min(fanPlanes(fan, plane_step_max), kMaxFanPlanes);
  const double step = out.n > 0 ? fan / out.n : 0.0;
  for (int j = -out.n; j <= out.n; ++j) {
    const double th_j = th + j * step;
    out.th[j + out.n] = th_j;
    out.dir[j + out.n] = std::cos(th_j) * wf.d0 + std::sin(th_j) * wf.f0;
  }
}

// Wheel profile point (y, z) in the fan's plane jj (r0: the profile's nominal radius).
Vector3d fanPoint(const WheelFrame& wf, double r0, const PlaneFan& fan, double y, double z, int jj) {
  return wf.c + (wf.ls * y) * wf.a + (r0 - z) * fan.dir[jj];
}

// The smallest rail distance of profile point (y, z) over the fan's planes (rail_distance of the point in
// world), and that plane in jj_min (the first of equal ones; unchanged if none is finite).
template <class RailDistance>
double fanDistance(const WheelFrame& wf, double r0, const PlaneFan& fan, double y, double z,
                   const RailDistance& rail_distance, int& jj_min) {
  double d_min = std::numeric_limits<double>::infinity();
  for (int jj = 0; jj <= 2 * fan.n; ++jj) {
    const double d = rail_distance(fanPoint(wf, r0, fan, y, z, jj));
    if (d < d_min) {
      d_min = d;
      jj_min = jj;
    }
  }
  return d_min;
}

// Wheel surface point and first derivatives.
struct WheelEval {
  Vector3d p, p_th, p_u, n, n_th, n_u, e_r, e_th;
  Vector2d q;  // profile point (y, z)
  double rho = 0.0;
};

void evalWheel(const ProfileCurve& curve, double normal_sign, const WheelFrame& wf, double r0, double th, double u,
               WheelEval& w) {
  Vector2d dq, d2q;
  curve.derivatives(u, w.q, dq, d2q);
  const double speed = dq.norm();
  const Vector2d t = dq / speed;
  const Vector2d dt = (d2q - t * t.dot(d2q)) / speed;
  const Vector2d n2 = normal_sign * perp(t);
  const Vector2d dn2 = normal_sign * perp(dt);
  const double c = std::cos(th), s = std::sin(th);
  w.e_r = c * wf.d0 + s * wf.f0;
  w.e_th = -s * wf.d0 + c * wf.f0;
  w.rho = r0 - w.q.y();
  w.p = wf.c + (wf.ls * w.q.x()) * wf.a + w.rho * w.e_r;
  w.p_th = w.rho * w.e_th;
  w.p_u = (wf.ls * dq.x()) * wf.a - dq.y() * w.e_r;
  w.n = (wf.ls * n2.x()) * wf.a - n2.y() * w.e_r;
  w.n_th = -n2.y() * w.e_th;
  w.n_u = (wf.ls * dn2.x()) * wf.a - dn2.y() * w.e_r;
}

// Rail surface point, tangents, their derivatives and the outward normal, deformed by the provider.
struct RailEval {
  Vector3d r, t_s, t_u, t_us, t_uu, n, c_section;
  Vector2d q;
  RailPoint rp;
  RailSectionMotion motion;
};

template <class Deformation>
void evalRail(const TrackGeometry& track, RailSide side, const ProfileCurve& rail, double rail_normal_sign,
              const Vector2d& centre_yz, const Deformation& deformation, double s, double u, RailEval& e) {
  track.rail(side, std::clamp(s, track.sStart(), track.sEnd()), e.rp);
  Vector2d dq, d2q;
  rail.derivatives(u, e.q, dq, d2q);
  const double ls = e.rp.lateral_sign;
  const Matrix3d& R = e.rp.R_rail_to_world;
  const Matrix3d& dR = e.rp.dR_ds;
  const Vector3d& o = e.rp.p_origin_in_world;
  const Vector3d& dO = e.rp.dp_origin_ds;
  e.r = o + (ls * e.q.x()) * R.col(1) + e.q.y() * R.col(2);
  e.t_s = dO + (ls * e.q.x()) * dR.col(1) + e.q.y() * dR.col(2);
  e.t_u = (ls * dq.x()) * R.col(1) + dq.y() * R.col(2);
  e.t_us = (ls * dq.x()) * dR.col(1) + dq.y() * dR.col(2);
  e.t_uu = (ls * d2q.x()) * R.col(1) + d2q.y() * R.col(2);
  const Vector2d n2 = rail_normal_sign * perp(dq.normalized());
  e.n = (ls * n2.x()) * R.col(1) + n2.y() * R.col(2);
  const Vector3d c0 = o + (ls * centre_yz.x()) * R.col(1) + centre_yz.y() * R.col(2);
  if constexpr (!Deformation::kRigid) {
    deformation.sectionMotion(side, s, e.motion);
    const Vector3d dc0 = dO + (ls * centre_yz.x()) * dR.col(1) + centre_yz.y() * dR.col(2);
    const Matrix3d A = smallRotationMatrix(e.motion.theta);
    const Vector3d Arel = A * (e.r - c0);
    const Vector3d At_u = A * e.t_u;
    e.r = c0 + e.motion.u + Arel;
    e.t_s = dc0 + e.motion.du_ds + e.motion.dtheta_ds.cross(Arel) + A * (e.t_s - dc0);
    e.t_us = A * e.t_us + e.motion.dtheta_ds.cross(At_u);
    e.t_u = At_u;
    e.t_uu = A * e.t_uu;
    e.n = A * e.n;
    e.c_section = c0 + e.motion.u;
  } else {
    e.c_section = c0;
  }
  // Surface normal: the cross-section normal made orthogonal to t_s (differs only on twisting track).
  e.n -= (e.n.dot(e.t_s) / e.t_s.squaredNorm()) * e.t_s;
  e.n.normalize();
}

}  // namespace

const ProfileCurve& ContactDetector::profileCurveAt(int surface, double u, double& u_local) const noexcept {
  if (surface == 0 && u > tread_.uMax()) {
    u_local = u - tread_.uMax();  // tread continued onto the flange
    return flange_;
  }
  if (surface == 1 && u < 0.0) {
    u_local = tread_.uMax() + u;  // flange continued onto the tread
    return tread_;
  }
  u_local = u;
  return surface == 0 ? tread_ : flange_;
}

double ContactDetector::surfaceUMin(int surface) const noexcept {
  return surface == 0 ? tread_.uMin() : -options_.split_overlap;
}

double ContactDetector::surfaceUMax(int surface) const noexcept {
  return surface == 0 ? tread_.uMax() + options_.split_overlap : flange_.uMax();
}

ContactDetector::ContactDetector(const WheelProfile& wheel, double nominal_radius, const ProfileCurve& rail,
                                 const Vector2d& section_centre_yz, const DetectionOptions& options)
    : tread_(wheel.tread),
      flange_(wheel.flange),
      rail_(rail),
      r0_(nominal_radius),
      section_centre_(section_centre_yz),
      options_(options) {
  if (!(nominal_radius > 0.1) || !(nominal_radius < 2.0)) {
    std::ostringstream m;
    m << "ContactDetector: nominal_radius = " << nominal_radius << " m is not a wheel radius (0.1 .. 2 m)";
    throw std::runtime_error(m.str());
  }
  if (!section_centre_yz.allFinite()) throw std::runtime_error("ContactDetector: section centre is not finite");
  const DetectionOptions& o = options_;
  if (!(o.split_overlap >= 0.0) || !(o.split_overlap < 0.5 * std::min(wheel.tread.uMax(), wheel.flange.uMax()))) {
    std::ostringstream m;
    m << "ContactDetector: DetectionOptions.split_overlap = " << o.split_overlap
      << " m must be >= 0 and below half the shorter wheel surface";
    throw std::runtime_error(m.str());
  }
  if (o.max_iterations < 1 || !(o.tolerance > 0.0) || !(o.max_step_length > 0.0) || !(o.max_step_angle > 0.0) ||
      !(o.max_penetration > 0.0) || !(o.min_normal_opposition > 0.0 && o.min_normal_opposition <= 1.0) ||
      !(o.search_cell > 0.0) || !(o.search_margin > 0.0) || !(o.search_spacing > 0.0) || !(o.end_seed_reach >= 0.0))
    throw std::runtime_error("ContactDetector: DetectionOptions has a non-positive or out-of-range value");
  if (!(o.search_plane_step >= 0.0) || !(o.search_fan_max >= 0.0) || !(o.search_fan_max < 1.0) ||
      fanPlanes(o.search_fan_max, o.search_plane_step) > kMaxFanPlanes) {
    std::ostringstream m;
    m << "ContactDetector: DetectionOptions.search_plane_step = " << o.search_plane_step
      << " rad and search_fan_max = " << o.search_fan_max << " rad must be >= 0, the fan below 1 rad and at most "
      << kMaxFanPlanes << " planes on each side (search_fan_max / search_plane_step)";
    throw std::runtime_error(m.str());
  }
  if (!(o.scan_skip_clearance >= 0.0)) {
    std::ostringstream m;
    m << "ContactDetector: DetectionOptions.scan_skip_clearance = " << o.scan_skip_clearance << " m must be >= 0";
    throw std::runtime_error(m.str());
  }
  if (tread_.numSegments() < 1 || flange_.numSegments() < 1 || rail_.numSegments() < 1)
    throw std::runtime_error("ContactDetector: empty wheel or rail profile curve");

  // A curve whose points run the other way has its solid on the wrong side: every contact would look
  // for the rail from inside. Refuse it here, where the cause can still be named.
  {
    const Vector2d top = railTopPoint(rail_);
    const double u_top = rail_.closestParameter(top);
    if (!(rail_.normal(u_top).y() > 0.5))
      throw std::runtime_error(
          "ContactDetector: the rail profile's outward normal at its highest point points down: its points "
          "run gauge side -> field side (order them by increasing y toward the gauge side, orderByIncreasingY)");
    double u_tap = 0.0;
    if (tread_.findCoordinate(0, 0.0, tread_.uMin(), tread_.uMax(), u_tap) && !(tread_.normal(u_tap).y() < -0.5))
      throw std::runtime_error(
          "ContactDetector: the wheel tread's outward normal at the taping line points toward the axle: its "
          "points run flange -> field side (order them by increasing y toward the flange, orderByIncreasingY)");
  }
  auto normalSign = [](const ProfileCurve& c) {
    const double u = 0.5 * c.uMax();
    return c.normal(u).dot(perp(c.tangent(u))) >= 0.0 ? 1.0 : -1.0;
  };
  wheel_normal_sign_[0] = normalSign(tread_);
  wheel_normal_sign_[1] = normalSign(flange_);
  rail_normal_sign_ = normalSign(rail_);

  // Wheel profile samples for the search, over each surface continued across the split by split_overlap.
  for (int k = 0; k < 2; ++k) {
    const double u0 = surfaceUMin(k), u1 = surfaceUMax(k);
    const int n = std::max(3, static_cast<int>(std::ceil((u1 - u0) / o.search_spacing)) + 1);
    samples_[k].resize(n);
    for (int i = 0; i < n; ++i) {
      const double u = u0 + (u1 - u0) * i / (n - 1);
      double u_local = 0.0;
      const Vector2d p = profileCurveAt(k, u, u_local).position(u_local);
      samples_[k][i] = {
          u, p.x(), p.y(),
          i > 0 ? samples_[k][i - 1].arc + (p - Vector2d(samples_[k][i - 1].y, samples_[k][i - 1].z)).norm() : 0.0};
      search_lever_[k] = std::max(search_lever_[k], std::abs(p.x()) + 2.2 * std::abs(r0_ - p.y()));
      if (i > 0) {
        const double dy = std::abs(p.x() - samples_[k][i - 1].y), dz = std::abs(p.y() - samples_[k][i - 1].z);
        search_slope_[k] = std::max(search_slope_[k], std::min(dz, kMaxSearchSlope * dy) / std::max(dy, 1e-12));
      }
    }
  }

  const std::size_t n_samples = samples_[0].size() + samples_[1].size();
  if (n_samples > static_cast<std::size_t>(ProfileScan::kMaxSamples)) {
    throw std::runtime_error("ContactDetector: DetectionOptions.search_spacing = " + formatNumber(o.search_spacing) +
                             " m gives " + std::to_string(n_samples) + " wheel profile samples, more than " +
                             std::to_string(ProfileScan::kMaxSamples) + " (use a coarser spacing)");
  }

  // Signed-distance grid of the rail profile: exact distance to a 1 mm polyline of the curve, sign from
  // the curve's outward normal at the foot point.
  const int n_poly = std::max(8, static_cast<int>(std::ceil(rail_.uMax() / 1e-3)));
  std::vector<Vector2d> poly(n_poly + 1);
  std::vector<double> poly_u(n_poly + 1);
  double ymin = 1e9, ymax = -1e9, zmin = 1e9, zmax = -1e9;
  for (int i = 0; i <= n_poly; ++i) {
    poly_u[i] = rail_.uMax() * i / n_poly;
    poly[i] = rail_.position(poly_u[i]);
    ymin = std::min(ymin, poly[i].x());
    ymax = std::max(ymax, poly[i].x());
    zmin = std::min(zmin, poly[i].y());
    zmax = std::max(zmax, poly[i].y());
  }
  grid_h_ = o.search_cell;
  grid_y0_ = ymin - o.search_margin;
  grid_z0_ = zmin - o.search_margin;
  grid_ny_ = static_cast<int>(std::ceil((ymax - ymin + 2 * o.search_margin) / grid_h_)) + 1;
  grid_nz_ = static_cast<int>(std::ceil((zmax - zmin + 2 * o.search_margin) / grid_h_)) + 1;
  grid_dist_.resize(static_cast<std::size_t>(grid_ny_) * grid_nz_);
  grid_u_.resize(grid_dist_.size());
  for (int j = 0; j < grid_nz_; ++j) {
    for (int i = 0; i < grid_ny_; ++i) {
      const Vector2d q(grid_y0_ + i * grid_h_, grid_z0_ + j * grid_h_);
      double best = std::numeric_limits<double>::infinity(), best_u = 0.0;
      for (int k = 0; k < n_poly; ++k) {
        const Vector2d seg = poly[k + 1] - poly[k];
        const double t = std::clamp((q - poly[k]).dot(seg) / seg.squaredNorm(), 0.0, 1.0);
        const double d2 = (poly[k] + t * seg - q).squaredNorm();
        if (d2 < best) {
          best = d2;
          best_u = poly_u[k] + t * (poly_u[k + 1] - poly_u[k]);
        }
      }
      const Vector2d foot = rail_.position(best_u);
      const double sign = (q - foot).dot(rail_.normal(best_u)) >= 0.0 ? 1.0 : -1.0;
      grid_dist_[static_cast<std::size_t>(j) * grid_ny_ + i] = static_cast<float>(sign * std::sqrt(best));
      grid_u_[static_cast<std::size_t>(j) * grid_ny_ + i] = static_cast<float>(best_u);
    }
  }
}

double ContactDetector::railSignedDistance(const Vector2d& p, double* u_closest) const noexcept {
  const double fy = (p.x() - grid_y0_) / grid_h_, fz = (p.y() - grid_z0_) / grid_h_;
  if (!(fy >= 0.0) || !(fz >= 0.0) || !(fy <= grid_ny_ - 1) || !(fz <= grid_nz_ - 1)) {
    // Outside the grid: at least the margin away from the profile; grows with the distance to the grid.
    const double dy = std::max({0.0, -fy, fy - (grid_ny_ - 1)}) * grid_h_;
    const double dz = std::max({0.0, -fz, fz - (grid_nz_ - 1)}) * grid_h_;
    if (u_closest) *u_closest = 0.5 * rail_.uMax();
    return options_.search_margin + std::hypot(dy, dz);
  }
  const int i = std::min(static_cast<int>(fy), grid_ny_ - 2), j = std::min(static_cast<int>(fz), grid_nz_ - 2);
  const double ty = fy - i, tz = fz - j;
  const std::size_t k = static_cast<std::size_t>(j) * grid_ny_ + i;
  const double d = (1 - ty) * (1 - tz) * grid_dist_[k] + ty * (1 - tz) * grid_dist_[k + 1] +
                   (1 - ty) * tz * grid_dist_[k + grid_ny_] + ty * tz * grid_dist_[k + grid_ny_ + 1];
  if (u_closest) {
    const std::size_t kn = static_cast<std::size_t>(j + (tz > 0.5 ? 1 : 0)) * grid_ny_ + i + (ty > 0.5 ? 1 : 0);
    *u_closest = grid_u_[kn];
  }
  return d;
}

template <class Deformation>
void ContactDetector::sectionPose(const WheelPose& pose, const TrackGeometry& track, const Deformation& deformation,
                                  const Vector3d& c, const Vector3d& a, SectionPose& out) const noexcept {
  // Rail cross-section nearest to the wheel centre (two projection steps from the hint).
  RailPoint rp;
  double s = std::clamp(pose.arc_length, track.sStart(), track.sEnd());
  for (int k = 0; k < 2; ++k) {
    track.rail(pose.side, s, rp);
    const Vector3d t = rp.dp_origin_ds;
    s = std::clamp(s + (c - rp.p_origin_in_world).dot(t) / t.squaredNorm(), track.sStart(), track.sEnd());
  }
  track.rail(pose.side, s, rp);
  const Matrix3d& R = rp.R_rail_to_world;
  out.s = s;
  out.o = rp.p_origin_in_world;
  out.T = R.col(0);
  out.Ny = rp.lateral_sign * R.col(1);
  out.B = R.col(2);
  if constexpr (!Deformation::kRigid) {
    // Move the section frame with the rail section (eq. 8).
    RailSectionMotion m;
    deformation.sectionMotion(pose.side, s, m);
    const Matrix3d A = smallRotationMatrix(m.theta);
    const Vector3d c0 = out.o + (rp.lateral_sign * section_centre_.x()) * R.col(1) + section_centre_.y() * R.col(2);
    out.o = c0 + m.u + A * (out.o - c0);
    out.T = A * out.T;
    out.Ny = A * out.Ny;
    out.B = A * out.B;
  }
  const Vector3d rel = c - out.o;
  out.centre = Vector2d(out.Ny.dot(rel), out.B.dot(rel));
  out.axle = Vector3d(out.T.dot(a), out.Ny.dot(a), out.B.dot(a));
}

double ContactDetector::fanWidth(int surface, const SectionPose& section) const noexcept {
  // A wheel yawed by psi against the rail touches a profile slope tan(delta) about psi tan(delta) rad
  // ahead of or behind its lowest plane (the flange lead).
  return std::min(1.5 * std::abs(section.axle[0]) * search_slope_[surface], options_.search_fan_max);
}

template <class Deformation>
bool ContactDetector::search(WheelSurface surface, const WheelPose& pose, const TrackGeometry& track,
                             const Deformation& deformation, Vector4d& x_seed, double& distance, Vector3d& p_wheel_seed,
                             double& min_distance, SectionPose& section, bool& end_seed) const noexcept {
  WheelFrame wf;
  makeWheelFrame(pose, wf);
  sectionPose(pose, track, deformation, wf.c, wf.a, section);
  const double s = section.s;
  const Vector3d o = section.o, T = section.T, Ny = section.Ny, B = section.B;
  // Lowest circle direction of the wheel with respect to the rail's up axis.
  const double th = std::atan2(-B.dot(wf.f0), -B.dot(wf.d0));
  // Each sample is taken over a fan of planes around that one (fanWidth).
  const int k = static_cast<int>(surface);
  PlaneFan fan;
  makePlaneFan(wf, th, fanWidth(k, section), options_.search_plane_step, fan);
  const std::vector<Sample>& smp = samples_[k];
  const int n = static_cast<int>(smp.size());
  // Rail distance of world point p in the section (local copies of its axes: they stay in registers).
  auto railDistance = [&](const Vector3d& p, double* u_closest = nullptr) {
    const Vector3d rel = p - o;
    return railSignedDistance(Vector2d(Ny.dot(rel), B.dot(rel)), u_closest);
  };
  // Distance of profile point (y, z): its smallest over the fan of planes, and that plane's index.
  auto pointDistance = [&](double y, double z, int& jj_i) {
    return fanDistance(wf, r0_, fan, y, z, railDistance, jj_i);
  };
  const int lowest = fan.n;
  double d_prev2 = 0.0, d_prev = 0.0;
  int jj_prev = lowest;
  double d_first = 0.0;
  int jj_first = lowest;
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  int jj_best = lowest;
  double min_any = std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) {
    int jj_i = lowest;
    const double d = pointDistance(smp[i].y, smp[i].z, jj_i);
    min_any = std::min(min_any, d);
    if (i == 0) d_first = d, jj_first = jj_i;
    // Interior local minimum at i - 1.
    if (i >= 2 && d_prev <= d_prev2 && d_prev <= d && d_prev < best_d) {
      best_d = d_prev;
      best = i - 1;
      jj_best = jj_prev;
    }
    d_prev2 = d_prev;
    d_prev = d;
    jj_prev = jj_i;
  }
  end_seed = false;
  if (best < 0 && n >= 2) {
    // No interior minimum: the surface's nearest point may lie in its last sample interval (the first end
    // sample first, then the last: d_prev and jj_prev hold the last).
    const double d_end[2] = {d_first, d_prev};
    const int jj_end[2] = {jj_first, jj_prev};
    for (int e = 0; e < 2; ++e) {
      if (d_end[e] <= min_any && d_end[e] < options_.end_seed_reach) {
        best = e == 0 ? 0 : n - 1;
        best_d = d_end[e];
        jj_best = jj_end[e];
        end_seed = true;
        break;
      }
    }
  }
  distance = best >= 0 ? best_d : min_any;
  min_distance = min_any;
  if (best < 0 || !(best_d < 0.9 * options_.search_margin)) return false;
  double u_best = smp[best].u;
  Vector3d q = fanPoint(wf, r0_, fan, smp[best].y, smp[best].z, jj_best);
  if (end_seed) {
    // The gap may keep falling past the end sample, onto the neighbouring surface's part of the profile (a
    // second contact there, ContactGeometry::past_end), and Newton from the end sample can miss that
    // minimum: the samples are continued outward while the distance falls, and the seed is the last.
    const double du = (best == 0 ? -1.0 : 1.0) * options_.search_spacing;
    for (int j = 1; j * options_.search_spacing <= kPastEndScan; ++j) {
      const double u_j = smp[best].u + j * du;
      double u_local = 0.0;
      const ProfileCurve& curve = profileCurveAt(k, u_j, u_local);
      if (u_local < curve.uMin() || u_local > curve.uMax()) break;
      const Vector2d p = curve.position(u_local);
      int jj_j = lowest;
      const double d_j = pointDistance(p.x(), p.y(), jj_j);
      if (!(d_j < best_d)) break;
      best_d = d_j;
      u_best = u_j;
      jj_best = jj_j;
      q = fanPoint(wf, r0_, fan, p.x(), p.y(), jj_j);
    }
  }
  double u_r = 0.0;
  railDistance(q, &u_r);
  x_seed = Vector4d(fan.th[jj_best], u_best, s + T.dot(q - o), u_r);
  p_wheel_seed = q;
  return true;
}

int ProfileScan::nearest(double U) const noexcept {
  const double* end = profile_u + n;
  const double* it = std::lower_bound(profile_u, end, U);
  if (it == end) return n - 1;
  const int i = static_cast<int>(it - profile_u);
  return i > 0 && U - profile_u[i - 1] < profile_u[i] - U ? i - 1 : i;
}

bool ProfileScan::samePatch(double U_a, double U_b, double dip, double min_dip) const noexcept {
  if (n <= 0) return false;
  const int a = nearest(U_a), b = nearest(U_b);
  const int lo = std::min(a, b), hi = std::max(a, b);
  if (hi - lo <= 1) return true;
  const double shallower = std::max(distance[a], distance[b]);  // < 0 interpenetrating
  const double threshold = std::min(shallower + std::max(dip * std::abs(shallower), min_dip), 0.0);
  double saddle = -std::numeric_limits<double>::infinity();
  for (int i = lo + 1; i < hi; ++i) saddle = std::max(saddle, distance[i]);
  return saddle < threshold;
}

template <class Deformation>
void ContactDetector::scanProfile(const WheelPose& pose, const TrackGeometry& track, const Deformation& deformation,
                                  bool include_flange, ProfileScan& out) const noexcept {
  out.n = 0;
  out.n_minima = 0;
  WheelFrame wf;
  if (!makeWheelFrame(pose, wf)) return;
  SectionPose section;
  sectionPose(pose, track, deformation, wf.c, wf.a, section);
  const Vector3d o = section.o, T = section.T, Ny = section.Ny, B = section.B;
  const double th = std::atan2(-B.dot(wf.f0), -B.dot(wf.d0));
  // Each part's fan of planes (as in search).
  PlaneFan fans[2];
  const int n_parts = include_flange ? 2 : 1;
  for (int k = 0; k < n_parts; ++k) makePlaneFan(wf, th, fanWidth(k, section), options_.search_plane_step, fans[k]);
  // Rail distance of world point p in the section (local copies of its axes: they stay in registers).
  auto railDistance = [&](const Vector3d& p, double* u_closest = nullptr) {
    const Vector3d rel = p - o;
    return railSignedDistance(Vector2d(Ny.dot(rel), B.dot(rel)), u_closest);
  };
  // A sample is taken unless the last one taken bounds its distance above scan_skip_clearance: along the
  // profile the rail distance changes by at most kScanLipschitz times the arc between the two samples.
  const double skip = options_.scan_skip_clearance;
  int first[2] = {0, 0};
  for (int k = 0; k < n_parts; ++k) {
    // Each part's own samples: the tread up to the split, the flange from it.
    const PlaneFan& fan = fans[k];
    first[k] = out.n;
    double d_taken = 0.0, arc_taken = 0.0;
    bool taken = false;
    for (const Sample& smp : samples_[k]) {
      if (k == 0 ? smp.u > tread_.uMax() : smp.u < 0.0) continue;
      double d_i = 0.0;
      const double bound = std::min(d_taken, options_.search_margin) - kScanLipschitz * (smp.arc - arc_taken);
      if (taken && skip > 0.0 && bound > skip) {
        d_i = bound;
      } else {
        int jj_unused = 0;
        d_i = fanDistance(wf, r0_, fan, smp.y, smp.z, railDistance, jj_unused);
        d_taken = d_i;
        arc_taken = smp.arc;
        taken = true;
      }
      out.profile_u[out.n] = profileU(k, smp.u);
      out.distance[out.n] = d_i;
      ++out.n;
    }
  }
  // Interpenetrating interior minima, deepest first, each with a Newton seed on its part's surface.
  for (int i = 1; i + 1 < out.n; ++i) {
    const double d = out.distance[i];
    if (!(d < 0.0) || d > out.distance[i - 1] || d > out.distance[i + 1]) continue;
    if (out.n_minima == ProfileScan::kMaxMinima && !(d < out.distance[out.minima[out.n_minima - 1].sample])) continue;
    const int k = include_flange && i >= first[1] ? 1 : 0;
    const double u = k == 0 ? out.profile_u[i] : out.profile_u[i] - tread_.uMax();
    double u_local = 0.0;
    const Vector2d p = profileCurveAt(k, u, u_local).position(u_local);
    // The plane of the sample's minimum, searched again (cheap: one sample).
    const PlaneFan& fan = fans[k];
    int jj_best = fan.n;
    fanDistance(wf, r0_, fan, p.x(), p.y(), railDistance, jj_best);
    const Vector3d q = fanPoint(wf, r0_, fan, p.x(), p.y(), jj_best);
    double u_r = 0.0;
    railDistance(q, &u_r);
    ProfileScan::Minimum m;
    m.sample = i;
    m.surface = k;
    m.seed = Vector4d(fan.th[jj_best], u, section.s + T.dot(q - o), u_r);
    // Insert by depth.
    int pos = std::min(out.n_minima, ProfileScan::kMaxMinima - 1);
    while (pos > 0 && out.distance[out.minima[pos - 1].sample] > d) {
      if (pos < ProfileScan::kMaxMinima) out.minima[pos] = out.minima[pos - 1];
      --pos;
    }
    out.minima[pos] = m;
    out.n_minima = std::min(out.n_minima + 1, ProfileScan::kMaxMinima);
  }
}

template <class Deformation>
void ContactDetector::detect(WheelSurface surface, const WheelPose& pose, const TrackGeometry& track,
                             const Deformation& deformation, DetectionWork& work, ContactGeometry& out) const noexcept {
  ++work.calls;
  out.iterations = 0;
  out.past_end = false;
  bool past_end = false;  // the last Newton converged to a penetrating pair past the surface's end
  if (work.hold_warm_start) {
    work.x = work.x_committed;
    work.x_surface = work.x_surface_committed;
    work.has_warm_start = work.has_committed_warm_start;
  }
  WheelFrame wf;
  if (!makeWheelFrame(pose, wf)) {
    out.status = DetectionStatus::kInvalidInput;
    out.valid = out.in_contact = false;
    out.penetration = -1.0;
    work.has_warm_start = false;
    return;
  }
  const int k = static_cast<int>(surface);
  const double u_lo = surfaceUMin(k), u_hi = surfaceUMax(k);
  const DetectionOptions& opt = options_;
  WheelEval w;
  RailEval e;
  // Wheel surface k at (th, u), continued across the split (profileCurveAt).
  auto wheelAt = [&](double th, double u) {
    double u_local = 0.0;
    const ProfileCurve& c = profileCurveAt(k, u, u_local);
    evalWheel(c, wheel_normal_sign_[&c == &tread_ ? 0 : 1], wf, r0_, th, u_local, w);
  };

  // Newton on eq. 4 from x; true when converged to a valid point pair (w, e evaluated at the solution).
  auto newton = [&](Vector4d& x) -> bool {
    for (int it = 0; it <= opt.max_iterations; ++it) {
      wheelAt(x[0], x[1]);
      evalRail(track, pose.side, rail_, rail_normal_sign_, section_centre_, deformation, x[2], x[3], e);
      const Vector3d d = w.p - e.r;
      const Vector4d F(d.dot(e.t_s), d.dot(e.t_u), w.n.dot(e.t_s), w.n.dot(e.t_u));
      if (!F.allFinite()) return false;
      if (std::abs(F[0]) < opt.tolerance && std::abs(F[1]) < opt.tolerance && std::abs(F[2]) * r0_ < opt.tolerance &&
          std::abs(F[3]) * r0_ < opt.tolerance) {
        // Converged: check the bounds and that this is a contact-type pair.
        const double eps = 1e-7;
        if (x[3] < rail_.uMin() - eps || x[3] > rail_.uMax() + eps) return false;
        if (x[2] < track.sStart() || x[2] > track.sEnd()) return false;
        if (std::cos(x[0]) < 0.5) return false;
        if (-w.n.dot(e.n) < opt.min_normal_opposition) return false;
        if (-d.dot(e.n) > opt.max_penetration) return false;
        if (x[1] < u_lo - eps || x[1] > u_hi + eps) {
          // A contact-type pair on the neighbouring surface: not this surface's, but said when it penetrates.
          past_end = -d.dot(e.n) > 0.0;
          return false;
        }
        return true;
      }
      if (it == opt.max_iterations) break;
      Matrix4d J;
      J(0, 0) = w.p_th.dot(e.t_s);
      J(0, 1) = w.p_u.dot(e.t_s);
      J(0, 2) = -e.t_s.squaredNorm();
      J(0, 3) = -e.t_u.dot(e.t_s) + d.dot(e.t_us);
      J(1, 0) = w.p_th.dot(e.t_u);
      J(1, 1) = w.p_u.dot(e.t_u);
      J(1, 2) = -e.t_s.dot(e.t_u) + d.dot(e.t_us);
      J(1, 3) = -e.t_u.squaredNorm() + d.dot(e.t_uu);
      J(2, 0) = w.n_th.dot(e.t_s);
      J(2, 1) = w.n_u.dot(e.t_s);
      J(2, 2) = 0.0;  // n_w . d t_s/ds: of the order of the track curvature, left out
      J(2, 3) = w.n.dot(e.t_us);
      J(3, 0) = w.n_th.dot(e.t_u);
      J(3, 1) = w.n_u.dot(e.t_u);
      J(3, 2) = w.n.dot(e.t_us);
      J(3, 3) = w.n.dot(e.t_uu);
      const Eigen::PartialPivLU<Matrix4d> lu(J);
      const double det = lu.determinant();
      if (!(std::abs(det) > 1e-14)) return false;
      Vector4d dx = lu.solve(-F);
      if (!dx.allFinite()) return false;
      // Step limits (keep the direction).
      double scale = 1.0;
      scale = std::min(scale, opt.max_step_angle / std::max(std::abs(dx[0]), 1e-300));
      scale = std::min(scale, opt.max_step_length / std::max(std::abs(dx[1]), 1e-300));
      scale = std::min(scale, 5.0 * opt.max_step_length / std::max(std::abs(dx[2]), 1e-300));
      scale = std::min(scale, opt.max_step_length / std::max(std::abs(dx[3]), 1e-300));
      x += scale * dx;
      ++out.iterations;
      ++work.newton_iterations;
      // Far outside the surfaces: give up early.
      const double far = 0.02;
      if (x[1] < u_lo - far || x[1] > u_hi + far || x[3] < rail_.uMin() - far || x[3] > rail_.uMax() + far ||
          x[2] < track.sStart() - far || x[2] > track.sEnd() + far || std::abs(x[0]) > 1.2)
        return false;
    }
    return false;
  };

  SectionPose section;
  Vector4d x = work.x;
  bool ok = false;
  DetectionStatus status = DetectionStatus::kConverged;
  double search_distance = 0.0;
  bool take_past_end = false;  // the result is a penetrating pair past the surface's end, at x
  if (work.seeded) {
    // A further contact of the wheel: Newton from the caller's seed (its patch's deepest sample); only a
    // converged, penetrating pair of the surface's own part.
    status = DetectionStatus::kConvergedAfterSearch;
    x = work.seed;
    const bool converged = newton(x) && -(w.p - e.r).dot(e.n) > 0.0;
    if (!converged) {
      out.status = DetectionStatus::kOutOfBounds;
      out.valid = out.in_contact = false;
      out.penetration = -1.0;
      work.has_warm_start = false;
      return;
    }
    ok = true;
  } else {
    // The last search failed with every sample at least reference_distance from the rail; each sample has
    // moved since by at most |d centre| + lever |d axle| relative to the rail section (the deformed one on
    // flexible rails: the search measures in that section alone), and the grid's distance changes by at
    // most sqrt(2) per unit of that (bilinear on a distance field).
    if (work.skip_far_searches && work.has_search_reference && !work.has_warm_start) {
      sectionPose(pose, track, deformation, wf.c, wf.a, section);
      const double moved = std::sqrt(2.0) * ((section.centre - work.reference_centre).norm() +
                                             search_lever_[k] * (section.axle - work.reference_axle).norm());
      const double clearance = work.reference_distance - moved;
      if (clearance > opt.skip_clearance && std::abs(section.axle[2]) < 0.3) {
        ++work.skipped;
        out.status = DetectionStatus::kOutOfBounds;
        out.valid = out.in_contact = false;
        out.penetration = -std::min(clearance, 1.0);
        return;
      }
    }
    // A warm start that converges to a penetrating pair past the surface's end keeps it as a candidate: the
    // search looks for the surface's own contact first, and the candidate is taken when there is none.
    bool warm_past_end = false;
    Vector4d x_warm_past_end = Vector4d::Zero();
    if (work.has_warm_start) {
      ok = newton(x);
      if (!ok && past_end) {
        warm_past_end = true;
        x_warm_past_end = x;
      }
    }
    Vector3d p_seed;
    if (!ok) {
      if (work.has_warm_start && !warm_past_end) ++work.fallbacks;
      ++work.searches;
      Vector4d seed;
      double min_distance = 0.0;
      bool end_seed = false;
      const bool found =
          search(surface, pose, track, deformation, seed, search_distance, p_seed, min_distance, section, end_seed);
      work.has_search_reference = false;
      if (found) {
        x = seed;
        past_end = false;
        ok = newton(x);
        status = DetectionStatus::kConvergedAfterSearch;
        take_past_end = !ok && past_end;
      }
      if (!take_past_end && warm_past_end && (!ok || -(w.p - e.r).dot(e.n) <= 0.0)) {
        // The surface's own point is not in contact: the penetrating candidate is the contact.
        x = x_warm_past_end;
        take_past_end = true;
        status = DetectionStatus::kConverged;
      }
      if (take_past_end) {
        ok = true;
        wheelAt(x[0], x[1]);
        evalRail(track, pose.side, rail_, rail_normal_sign_, section_centre_, deformation, x[2], x[3], e);
      } else if (!found || (!ok && end_seed)) {
        // No seed, or an end sample that Newton could not move inside the surface nor into the rail past it:
        // no contact of this surface.
        if (!found) {
          work.has_search_reference = true;
          work.reference_distance = min_distance;
          work.reference_centre = section.centre;
          work.reference_axle = section.axle;
        }
        out.status = DetectionStatus::kOutOfBounds;
        out.valid = out.in_contact = false;
        out.penetration = -std::min(search_distance, 1.0);
        work.has_warm_start = false;
        return;
      } else if (!ok) {
        // Approximate: the search's best pair.
        x = seed;
        wheelAt(x[0], x[1]);
        evalRail(track, pose.side, rail_, rail_normal_sign_, section_centre_, deformation, x[2], x[3], e);
        w.p = p_seed;
        status = DetectionStatus::kApproximate;
        ++work.approximations;
      }
    }
  }
  out.past_end = take_past_end;
  work.x = x;
  work.x_surface = k;
  work.has_warm_start = status != DetectionStatus::kApproximate;

  out.status = status;
  out.valid = true;
  out.s_w = x[0];
  out.u_w = x[1];
  out.s_r = x[2];
  out.u_r = x[3];
  out.profile_u = profileU(k, x[1]);
  out.p_wheel_in_world = w.p;
  out.p_rail_in_world = e.r;
  out.n_in_world = e.n;
  out.penetration = status == DetectionStatus::kApproximate ? -search_distance : -(w.p - e.r).dot(e.n);
  out.in_contact = out.penetration > 0.0;
  Vector3d t = w.e_th - w.e_th.dot(e.n) * e.n;
  t.normalize();
  if (t.dot(e.t_s) < 0.0) t = -t;
  out.t_rolling_in_world = t;
  out.p_section_centre_in_world = e.c_section;
  if constexpr (Deformation::kRigid) {
    out.rail_motion.setZero();
  } else {
    out.rail_motion = e.motion;
  }
  out.wheel_radius = w.rho;
  out.cos_normal_radial = std::abs(e.n.dot(w.e_r));
  double u_local = 0.0;
  out.wheel_curvature = profileCurveAt(k, x[1], u_local).curvature(u_local);
  out.on_own_surface = k == 0 ? x[1] <= tread_.uMax() : x[1] >= 0.0;
  out.rail_curvature = rail_.curvature(x[3]);
  out.wheel_y = w.q.x();
  out.wheel_z = w.q.y();
  out.rail_y = e.q.x();
  out.rail_z = e.q.y();
}

// Explicit instantiations for the providers of rail_deformation.hpp.
template void ContactDetector::detect<RigidRailDeformation>(WheelSurface, const WheelPose&, const TrackGeometry&,
                                                            const RigidRailDeformation&, DetectionWork&,
                                                            ContactGeometry&) const noexcept;
template void ContactDetector::detect<BeamRailDeformation>(WheelSurface, const WheelPose&, const TrackGeometry&,
                                                           const BeamRailDeformation&, DetectionWork&,
                                                           ContactGeometry&) const noexcept;
template void ContactDetector::detect<RailDeformation>(WheelSurface, const WheelPose&, const TrackGeometry&,
                                                       const RailDeformation&, DetectionWork&,
                                                       ContactGeometry&) const noexcept;
template void ContactDetector::scanProfile<RigidRailDeformation>(const WheelPose&, const TrackGeometry&,
                                                                 const RigidRailDeformation&, bool,
                                                                 ProfileScan&) const noexcept;
template void ContactDetector::scanProfile<BeamRailDeformation>(const WheelPose&, const TrackGeometry&,
                                                                const BeamRailDeformation&, bool,
                                                                ProfileScan&) const noexcept;
template void ContactDetector::scanProfile<RailDeformation>(const WheelPose&, const TrackGeometry&,
                                                            const RailDeformation&, bool, ProfileScan&) const noexcept;

}  // namespace contact
}  // namespace rail
