// Wheel and rail cross-section profiles (paper section 4.1, Figure 8).
//
// A profile is a plane curve in its cross-section frame, coordinates (y, z) in metres:
//   rail profile frame:  origin at the top of the (untilted) rail head on its symmetry axis, y lateral,
//                        positive toward the track centre (gauge side), z up.
//   wheel profile frame: origin on the taping line (nominal rolling circle, 70 mm from the flange back
//                        face), y lateral, positive toward the flange side (= toward the track centre),
//                        z up at the wheel's lowest point (toward the axle). The surface radius of the
//                        wheel is r = r0 - z, r0 the nominal rolling radius; the flange tip has z < 0.
// Both frames are "local" frames of one rail / one wheel seen with the track centre on +y; the caller
// mirrors y for the other side. With the wheelset centred on a rail, the two frames are parallel.
//
// ProfileCurve parametrises the curve by its arc length u in [u_min, u_max] (m), u increasing with the
// order of the input points. The outward normal points out of the solid; the solid lies to the right of
// the direction of increasing u (rail, points ordered field side -> gauge side) or to the left (wheel,
// points ordered field side -> flange). Signed curvature is positive where the solid is convex (rail
// crown, flange tip), negative where it is concave (flange root), in 1/m.
#pragma once

#include <Eigen/Core>

#include <stdexcept>
#include <string>
#include <vector>

namespace rail {
namespace contact {

using ProfilePoints = std::vector<Eigen::Vector2d>;  ///< (y, z) points in a profile frame, metres

/// Side of the curve (looking along increasing u) on which the solid body lies.
enum class SolidSide { Right, Left };

/// Position, unit tangent, outward unit normal and signed curvature at one parameter value.
struct ProfileEval {
  Eigen::Vector2d p = Eigen::Vector2d::Zero();  ///< position (y, z), m
  Eigen::Vector2d t = Eigen::Vector2d::Zero();  ///< unit tangent, direction of increasing u
  Eigen::Vector2d n = Eigen::Vector2d::Zero();  ///< outward unit normal (out of the solid)
  double kappa = 0.0;                           ///< signed curvature, 1/m (> 0 convex solid)
};

/// Construction options of a ProfileCurve.
struct ProfileCurveOptions {
  double ds = 0.1e-3;  ///< arc-length spacing of the resampled spline nodes, m
};

/// Smooth C2 interpolant of a profile: a cubic spline through the input points (chord-length knots,
/// not-a-knot ends), resampled at uniform arc-length spacing and re-splined, so that u is the arc
/// length at every node and the segment of any u is found in O(1). Constant after construction;
/// evaluation is allocation-free. Outside [u_min, u_max] the curve continues along the end tangents
/// (zero curvature), so that a Newton step may leave the range without a jump.
class ProfileCurve {
 public:
  ProfileCurve() = default;  ///< empty curve: assign a built one before evaluating
  /// Builds the curve through points_yz (at least 4 distinct consecutive points, m). Throws
  /// std::invalid_argument on fewer points, repeated points or non-finite values.
  ProfileCurve(const ProfilePoints& points_yz, SolidSide side, const ProfileCurveOptions& options = {});

  double uMin() const { return 0.0; }
  double uMax() const { return length_; }
  bool inRange(double u) const { return u >= 0.0 && u <= length_; }
  int numSegments() const { return static_cast<int>(coef_.size()); }
  SolidSide solidSide() const { return side_; }

  /// Index of the spline segment containing u (clamped to the first/last segment), O(1).
  int segment(double u) const;

  Eigen::Vector2d position(double u) const;  ///< (y, z) at u, m
  Eigen::Vector2d tangent(double u) const;   ///< unit tangent at u
  Eigen::Vector2d normal(double u) const;    ///< outward unit normal at u
  double curvature(double u) const;          ///< signed curvature at u, 1/m
  /// Derivatives of position with respect to u (first: ~unit; second: ~kappa times inward normal).
  void derivatives(double u, Eigen::Vector2d& p, Eigen::Vector2d& dp_du, Eigen::Vector2d& d2p_du2) const;
  /// All of position, tangent, normal and curvature at once.
  void evaluate(double u, ProfileEval& out) const;

  /// Parameter of the point of the curve closest to point_yz (local search seeded on the nodes, then
  /// Newton); distance_out (m) receives the distance if not null. For analysis and set-up, not per step.
  double closestParameter(const Eigen::Vector2d& point_yz, double* distance_out = nullptr) const;

  /// First u in [u_from, u_to] (either order, scanned from u_from toward u_to) where coordinate
  /// `axis` (0: y, 1: z) of the curve equals value; false if there is none.
  bool findCoordinate(int axis, double value, double u_from, double u_to, double& u_out) const;

  /// Node points of the resampled spline (uniform arc-length spacing), e.g. for plotting or export.
  ProfilePoints nodes() const;

 private:
  // Segment k covers u in [k h, (k+1) h]; with t = u - k h: p(t) = a + b t + c t^2 + d t^3.
  struct Segment {
    Eigen::Vector2d a, b, c, d;
  };
  std::vector<Segment> coef_;
  double h_ = 0.0;       // node spacing in u, m
  double length_ = 0.0;  // total arc length, m
  SolidSide side_ = SolidSide::Right;
  double normal_sign_ = 1.0;  // +1: outward normal is the left normal of the tangent
};

// ----------------------------------------------------------------------------------------------------
// Rail: UIC60 (60E1, EN 13674-1)

/// Section data of the 60E1 rail (EN 13674-1), SI units.
namespace uic60 {
constexpr double kHeight = 0.172;                 ///< rail height, m
constexpr double kHeadWidth = 0.072;              ///< head width (at the R13 / flank tangent points), m
constexpr double kFootWidth = 0.150;              ///< foot width, m
constexpr double kWebThickness = 0.0165;          ///< web thickness, m
constexpr double kHeadDepth = 0.051;              ///< head depth (top to the head fishing-surface line), m
constexpr double kFootDepth = 0.0315;             ///< foot depth (bottom to the foot fishing-surface line), m
constexpr double kArea = 76.70e-4;                ///< cross-section area, m^2
constexpr double kIyy = 3038.3e-8;                ///< second moment of area about the horizontal axis, m^4
constexpr double kIzz = 512.3e-8;                 ///< second moment of area about the vertical axis, m^4
constexpr double kSectionModulusHead = 333.6e-6;  ///< elastic section modulus, head side, m^3
constexpr double kSectionModulusFoot = 375.5e-6;  ///< elastic section modulus, foot side, m^3
/// Depth of the centroid (neutral axis) below the head top = kIyy / kSectionModulusHead, m (~91.1 mm).
constexpr double kCentroidDepth = kIyy / kSectionModulusHead;
constexpr double kInclination = 1.0 / 20.0;  ///< default rail inclination (tan of the cant angle)
constexpr double kGaugeDepth = 0.014;        ///< gauge measuring depth below the running surface (EN 13848-1), m
}  // namespace uic60

/// UIC60 head contact profile in the (untilted) rail profile frame: field-side flank, R13, R80, R300
/// crown, R80, R13, gauge-side flank, down to flank_depth below the head top; ordered field -> gauge
/// (y increasing). Points every ds along each piece (m).
ProfilePoints uic60HeadPoints(double ds = 0.1e-3, double flank_depth = 0.038);

/// Rough closed outline of the whole 60E1 section (head as uic60HeadPoints, straight fishing surfaces,
/// web and foot without fillets, an assumed 12 mm foot-edge thickness), untilted rail frame, clockwise
/// from the gauge-side head corner. For section checks (height, widths), not for contact.
ProfilePoints uic60SectionOutline();

/// Rotates points about the profile origin by the rail inclination (tan of the cant angle, default
/// 1/20) so that the running surface faces the track centre (+y): the rail axis becomes
/// (sin a, cos a), a = atan(inclination).
ProfilePoints tiltProfile(const ProfilePoints& points_yz, double inclination = uic60::kInclination);

/// UIC60 head contact curve tilted by inclination (rail profile frame, solid on the right).
ProfileCurve makeUic60Rail(double inclination = uic60::kInclination, const ProfileCurveOptions& options = {});

/// Highest point of a rail curve (the running surface's top), in its profile frame.
Eigen::Vector2d railTopPoint(const ProfileCurve& rail);

/// Gauge point: the point of the gauge face (the side y > y_top) lying depth below the highest point
/// of the rail curve, EN 13848-1 (depth 14 mm). Profile frame, m. Throws std::runtime_error if the
/// curve does not reach that depth on the gauge side.
Eigen::Vector2d gaugePoint(const ProfileCurve& rail, double depth = uic60::kGaugeDepth);

/// Rail section centre (beam axis) in the profile frame the curve is given in, whatever its origin:
/// laterally midway between the head's two faces at head_depth below the highest point, vertically
/// depth_below_top below that point. For a profile whose origin is not on the rail's axis (e.g. the
/// highest point of an inclined rail, as the Manchester benchmark's file has it). An inclination built
/// into the file is not undone: at 1:40 the centre is then about 2 mm off at 91 mm depth. A head whose
/// faces do not both reach head_depth is measured at the depth both reach (the highest point's y below
/// 3 mm).
Eigen::Vector2d railSectionCentre(const ProfileCurve& rail, double depth_below_top = uic60::kCentroidDepth,
                                  double head_depth = uic60::kGaugeDepth);

// ----------------------------------------------------------------------------------------------------
// Wheel: S1002 (EN 13715)

/// S1002 height z(y) in the wheel profile frame (m in, m out), from EN 13715's piecewise definition;
/// valid for y in [-0.060, 0.070] (field-side end of the tread to the flange back face).
double s1002Z(double y);

/// S1002 profile points in the wheel profile frame, from y = -60 mm to the flange back face at
/// y = +70 mm, ordered field -> flange, one every ds along the curve (m).
ProfilePoints s1002Points(double ds = 0.1e-3);

/// Wheel profile split into its tread and flange surfaces (paper section 4.1, Figure 8). The split is
/// where the profile slope first reaches split_angle on the way from the taping line toward the flange.
struct WheelProfile {
  ProfileCurve tread;        ///< field-side end -> split point, solid on the left
  ProfileCurve flange;       ///< split point -> flange back, solid on the left
  Eigen::Vector2d split_yz;  ///< split point (shared end of tread and flange), m
  double split_angle = 0.0;  ///< slope angle at the split, rad
};

/// Default tread / flange split angle: 45 deg of profile slope, inside the S1002 flange-root fillet
/// (section D, whose slope runs from 42.5 deg to the 70 deg of the flange flank).
constexpr double kDefaultSplitAngle = 0.78539816339744830962;

/// Splits a whole wheel profile (ordered field -> flange, wheel frame, m) into tread and flange.
/// Throws std::runtime_error if the slope never reaches split_angle between y = 0 and the flange tip.
WheelProfile makeWheelProfile(const ProfilePoints& points_yz, double split_angle = kDefaultSplitAngle,
                              const ProfileCurveOptions& options = {});

/// S1002 split into tread and flange.
WheelProfile makeS1002(double split_angle = kDefaultSplitAngle, const ProfileCurveOptions& options = {});

/// z of the tread at the taping line (y = 0), m (0 for a profile in the standard frame).
double tapingLineZ(const WheelProfile& wheel);
/// Flange height: radial distance from the taping-line circle to the flange tip, m (S1002: 28 mm).
double flangeHeight(const WheelProfile& wheel);
/// Flange back face position: largest y of the flange surface, m (S1002: 70 mm). A measured profile
/// may stop short of the back face: place the wheel with kTapingLineFromFlangeBack, not with this.
double flangeBackY(const WheelProfile& wheel);
/// Distance of the taping line (the wheel profile frame's origin) from the flange back face, m: 70 mm
/// by definition of the frame (EN 13715), whatever lateral extent the profile's points have.
constexpr double kTapingLineFromFlangeBack = 0.070;
/// Flange thickness: lateral distance from the flange back face to the flange's gauge-side face,
/// measured height above the taping-line circle (EN 15313: 10 mm), m (S1002: 32.5 mm).
double flangeThickness(const WheelProfile& wheel, double height = 0.010);

// ----------------------------------------------------------------------------------------------------
// Profile files

/// Malformed profile file; what() reads "<file>:<line>: <what> (<offending value>)".
class ProfileFileError : public std::runtime_error {
 public:
  ProfileFileError(const std::string& file, int line, const std::string& what);
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  std::string file_;
  int line_;
};

/// Conversion of file coordinates to the library's profile frame, applied after each format's own
/// convention (see doc/profiles.md): optional mirroring, then a shift (m, in the library frame).
struct ProfileFileOptions {
  bool mirror_y = false;
  bool mirror_z = false;
  double shift_y = 0.0;
  double shift_z = 0.0;
};

/// Plain text: one "y z" pair per line (blank or comma separated), '#' starts a comment. Units: a
/// comment line "# units: mm" or "# units: m" decides; without it, millimetres if any |value| > 1,
/// metres otherwise. Coordinates are in the library frame already.
ProfilePoints readPlainProfile(const std::string& path, const ProfileFileOptions& options = {});

/// MiniProf text export (.ban rail, .whl wheel): "Key=Value" header lines, an empty line, then one
/// point per line with the columns named by ColumnDef (X, Y, ... ; default X,Y), in mm; a leading
/// '"' (point flag) is ignored. MiniProf's X is taken as y, its Y (positive down) as -z.
ProfilePoints readMiniProfProfile(const std::string& path, const ProfileFileOptions& options = {});

/// SIMPACK profile (.prr rail, .prw wheel): header.begin/end block (version, type 0 rail / 1 wheel),
/// spline.begin/end block with its keywords (units.len.f, shift.y/z, rotate, units.ang.f, mirror.y/z,
/// inversion, ...) and point.begin/end table of "y z [weight]". The spline-block modifications are
/// applied as SIMPACK defines them; SIMPACK's y (toward the field side) and z (down) are then negated.
/// type_out receives the header type (0 rail, 1 wheel) if not null.
ProfilePoints readSimpackProfile(const std::string& path, const ProfileFileOptions& options = {},
                                 int* type_out = nullptr);

/// Points reordered so that y increases (field side -> gauge side for a rail, field side -> flange for a
/// wheel), the order ProfileCurve's SolidSide assumes; a file may list them either way.
ProfilePoints orderByIncreasingY(ProfilePoints points_yz);

/// Dispatches on the extension: .ban/.whl MiniProf, .prr/.prw SIMPACK, anything else plain text.
ProfilePoints readProfilePoints(const std::string& path, const ProfileFileOptions& options = {});

/// Reads a rail profile and builds its curve (points reordered field -> gauge if needed), tilted by
/// inclination (tan of the cant angle; 0 for a file whose profile is inclined already).
ProfileCurve loadRailProfile(const std::string& path, const ProfileFileOptions& options = {},
                             const ProfileCurveOptions& curve_options = {}, double inclination = 0.0);
/// Reads a wheel profile and splits it (points reordered field -> flange if needed).
WheelProfile loadWheelProfile(const std::string& path, const ProfileFileOptions& options = {},
                              double split_angle = kDefaultSplitAngle, const ProfileCurveOptions& curve_options = {});

/// Writers (library frame in, each format's convention out; mm in the files). Throw std::runtime_error
/// if the file cannot be written.
void writePlainProfile(const std::string& path, const ProfilePoints& points_yz, const std::string& comment = "");
void writeMiniProfProfile(const std::string& path, const ProfilePoints& points_yz);
void writeSimpackProfile(const std::string& path, const ProfilePoints& points_yz, int type,
                         const std::string& comment = "");

}  // namespace contact
}  // namespace rail
