// Track geometry (paper section 3.2): the track centre line built from curvature, cant and gradient,
// its moving frame, and the left and right rail reference curves and cross-section frames, tabulated
// once at a uniform step (paper section 4.1: "pre-calculated and included in a table accessed online")
// and interpolated in O(1) without allocation.
//
// Frames and conventions (doc/geometry.md has the figures in words):
//  - world: x forward at the track start, y left, z up; the centre line starts at the world origin at
//    s = s_start, heading along +x.
//  - s is the arc length of the (3-D) centre line, m. Curvature kappa = d(heading)/ds, 1/m, positive
//    curving to the left. The gradient g (rise over run) pitches the tangent by atan(g).
//  - track frame at s, R_track_to_world = [t n b]: t tangent (forward), n lateral (left, in the canted
//    track plane), b normal to the canted track plane (up). Cant D (m, positive raises the RIGHT rail)
//    rolls the frame about t by -phi, phi = asin(D / cant_reference_width).
//  - rail frame, R_rail_to_world = [t_r n_r b_r]: t_r the rail origin curve's unit tangent, n_r lateral
//    (left), b_r the rail's "up" axis, tilted toward the track centre by the rail inclination. The same
//    right-handed orientation for both rails; a profile's lateral coordinate y is measured TOWARD THE
//    TRACK CENTRE (gauge side positive) on both rails, so the lateral axis used for the profile is
//    lateral_sign * n_r with lateral_sign = -1 on the left rail and +1 on the right rail.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "rail_contact/irregularities.hpp"
#include "rail_contact/track_defects.hpp"

namespace rail {
namespace contact {

/// One piece of the centre line. A transition is a clothoid (curvature linear in s) with a linear cant
/// ramp; straight and circular segments have constant curvature and cant (start values are used).
struct SegmentSpec {
  enum class Type { Straight, Transition, Circular };
  Type type = Type::Straight;
  double length = 0.0;           // m, > 0
  double curvature_start = 0.0;  // 1/m, positive = curving to the left (+y of the track frame)
  double curvature_end = 0.0;    // 1/m
  double cant_start = 0.0;       // m, signed superelevation: positive raises the RIGHT rail
  double cant_end = 0.0;         // m
  double gradient = 0.0;         // rise over run (vertical slope), constant on the segment
};

struct GeometrySpec {
  std::vector<SegmentSpec> segments;
  double s_start = 0.0;               // m, arc length of the first segment's start
  double cant_reference_width = 1.5;  // m, base of the cant (distance between the running circles)
  double rail_half_spacing = 0.75;    // m, centre line to each rail's profile origin, in the track plane
  double rail_vertical_offset = 0.0;  // m, profile origins above the centre line along b
  double rail_inclination = 0.0;      // rad, rails tilted toward the track centre (1/20 -> atan(0.05))
  double table_step = 0.1;            // m, largest spacing of the tabulated frames
};

enum class RailSide { kLeft = 0, kRight = 1 };

/// Centre line state at s (world frame).
struct TrackPoint {
  Eigen::Vector3d p_center_in_world;  // m
  Eigen::Vector3d dp_ds;              // d p / ds (the unit tangent up to interpolation error)
  Eigen::Matrix3d R_track_to_world;   // columns t, n, b
  Eigen::Matrix3d dR_ds;              // d R_track_to_world / ds, 1/m
  double curvature = 0.0;             // 1/m, d(heading)/ds, interpolated linearly between table nodes
  double cant_angle = 0.0;            // rad, phi = asin(cant / cant_reference_width)
};

/// One rail's reference curve and cross-section frame at the track arc length s (world frame),
/// irregularities included.
struct RailPoint {
  Eigen::Vector3d p_origin_in_world;  // m, the rail profile origin
  Eigen::Vector3d dp_origin_ds;       // d p_origin / ds
  Eigen::Matrix3d R_rail_to_world;    // columns t_r, n_r, b_r (see the file comment)
  Eigen::Matrix3d dR_ds;              // d R_rail_to_world / ds, 1/m
  double lateral_sign = 1.0;          // -1 left rail, +1 right rail: profile y axis = lateral_sign n_r
};

/// A point of a rail surface and its partial derivatives with respect to the surface parameters.
struct RailSurfacePoint {
  Eigen::Vector3d r;      // m, world frame
  Eigen::Vector3d dr_ds;  // d r / d s_r
  Eigen::Vector3d dr_du;  // d r / d u_r
};

/// The track geometry: built once from a GeometrySpec (and optional irregularities), constant after.
/// Every query is O(1) (uniform table), allocation-free, and throws std::runtime_error only for s
/// outside [sStart(), sEnd()].
class TrackGeometry {
 public:
  /// Builds the tables; throws std::runtime_error naming the segment/field and value on bad input, and
  /// when table_step is too coarse for the irregularities (> shortest wavelength / 8).
  explicit TrackGeometry(const GeometrySpec& spec, const Irregularities& irregularities = Irregularities(),
                         TrackDefects defects = TrackDefects());

  double sStart() const { return s_start_; }
  double sEnd() const { return s_end_; }
  /// Actual uniform table spacing (m): (sEnd - sStart) / numIntervals() <= spec.table_step.
  double tableStep() const { return h_; }
  int numIntervals() const { return n_intervals_; }
  bool hasIrregularities() const { return has_irregularities_; }
  const TrackDefects& defects() const { return defects_; }
  const GeometrySpec& spec() const { return spec_; }

  /// Centre line at s.
  void centre(double s, TrackPoint& out) const;
  /// Rail reference curve and cross-section frame at s.
  void rail(RailSide side, double s, RailPoint& out) const;

  /// Point of the rail surface at (s_r, u_r) for a profile point (y, z) given in the rail frame's
  /// cross-section (y toward the track centre, z along b_r; m) with dy_du, dz_du its derivatives with
  /// respect to the profile parameter u_r: r = p_origin + lateral_sign y n_r + z b_r.
  RailSurfacePoint railSurface(RailSide side, double s_r, double y, double z, double dy_du, double dz_du) const;
  /// Same for an already evaluated rail point (saves the table lookup when several profile points share
  /// one s_r).
  static RailSurfacePoint railSurface(const RailPoint& rail, double y, double z, double dy_du, double dz_du);

  /// Design (irregularity-free) values: cant (m) and curvature (1/m) at s, exact (not interpolated).
  double designCant(double s) const;
  double designCurvature(double s) const;

 private:
  struct Node {  // one tabulated station
    Eigen::Vector3d p, dp;
    Eigen::Matrix3d R, dR;
  };
  int cellIndex(double s, double& tau) const;
  int segmentIndex(double s) const;

  GeometrySpec spec_;
  double s_start_ = 0.0, s_end_ = 0.0, h_ = 0.0;
  int n_intervals_ = 0;
  bool has_irregularities_ = false;
  TrackDefects defects_;            // added to the rails by rail() (not tabulated: a joint's kink needs no table step)
  std::vector<double> segment_s0_;  // arc length at each segment start
  std::vector<Node> centre_nodes_, rail_nodes_[2];
  std::vector<double> curvature_nodes_, cant_angle_nodes_;
};

/// Cant angle phi = asin(cant / cant_reference_width), rad; throws std::runtime_error when the width is
/// not positive or |cant| >= width.
double cantAngle(double cant, double cant_reference_width);

/// EN 13803 equilibrium cant D_eq = e V^2 / (g R) (m): e cant base (m), V speed (m/s), R curve radius
/// (m, > 0), g gravitational acceleration (m/s^2; EN 13803 uses 9.81). Throws on non-positive e, R, g.
double equilibriumCant(double cant_reference_width, double speed, double radius, double g = 9.81);

/// EN 13803 cant deficiency I = D_eq - D (m): positive when the applied cant D is below equilibrium.
double cantDeficiency(double d_eq, double applied_cant);

}  // namespace contact
}  // namespace rail
