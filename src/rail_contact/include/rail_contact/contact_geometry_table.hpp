// Contact-geometry table of a wheelset on straight rigid track (the pre-processing of railway vehicle
// dynamics): against the wheelset's lateral displacement y (and optionally a yaw angle), the contact
// points on wheel and rail, contact angles, rolling radii, the rolling-radius difference
// Delta r = r_left - r_right and, from Delta r(y), the equivalent conicity by the EN 15302 principle
// (kinematic wavelength of the nonlinear Klingel motion, see equivalentConicity). With a vertical wheel
// load, speed and friction the table adds normal loads, contact ellipses, creepages and creep forces.
//
// The rows are computed with the online detection (contact_detection.hpp) on a straight TrackGeometry:
// for each y the wheelset's height z and roll angle are solved so that both wheels touch their rails
// with zero penetration (rigid columns), or so that each wheel carries the vertical load Q (loaded
// columns, Hertz penetration). Frames: world x forward, y left, z up; y > 0 moves the wheelset left.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "rail_contact/wheel_contact.hpp"

namespace rail {
namespace contact {

/// Wheelset and track data of the table.
struct WheelsetTrackSpec {
  double track_gauge = 1.435;   ///< m, between the gauge points (gauge_depth below the rail tops)
  double gauge_depth = 0.014;   ///< m, EN 13848-1 measuring depth
  double back_to_back = 1.360;  ///< m, distance between the flange back faces
  /// m, flange back face to taping line (the wheel profile frame's origin), whatever the profile's extent
  double taping_line_from_flange_back = kTapingLineFromFlangeBack;
  double nominal_radius = 0.46;  ///< m, r0 at the taping line
  /// Rail section centre in the rail profile frame (only for rail wrenches), m; NaN: railSectionCentre
  /// of the rail at the UIC60 centroid depth.
  Eigen::Vector2d rail_section_centre_yz = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
};

/// Optional load case (wheel_load > 0 to enable). The wheelset's height and roll are solved so that each
/// wheel carries wheel_load vertically, and with free_rolling its pitch rate so that the contact forces
/// have no net moment about the axle (a wheelset without traction or braking torque).
struct LoadCase {
  double wheel_load = 0.0;   ///< vertical load Q per wheel, N
  double speed = 0.0;        ///< forward speed, m/s
  bool free_rolling = true;  ///< false: pitch rate fixed at V / r0 (pure rolling of the nominal circle)
};

/// One wheel's contact in a row. kind: 0 tread, 1 flange, -1 none found.
struct ContactGeometryWheel {
  int kind = -1;
  double y_wheel = 0.0, z_wheel = 0.0;  ///< contact point, wheel profile frame, m
  double y_rail = 0.0, z_rail = 0.0;    ///< contact point, rail profile frame, m
  double y_rail_from_top = 0.0;         ///< contact point from the rail's highest point, toward the gauge side, m
  double contact_angle = 0.0;           ///< rad, normal's inclination toward the track centre
  double rolling_radius = 0.0;          ///< m
  double flange_gap = 0.0;              ///< gap between flange and rail along the flange normal, m (< 0: contact)
  // Loaded columns (zero without a load case):
  double N = 0.0, a = 0.0, b = 0.0;          ///< N, m, m
  double nu_x = 0.0, nu_y = 0.0, phi = 0.0;  ///< -, -, 1/m
  double F_long = 0.0, F_lat = 0.0;          ///< N
};

/// One row of the table.
struct ContactGeometryRow {
  bool ok = false;           ///< both wheels in contact and the position solved
  bool loaded_ok = false;    ///< the load case (if any) solved too; else its columns are NaN
  std::string failure;       ///< why the row is not ok or its loaded columns are empty: which solve, which wheel
  double y = 0.0;            ///< lateral displacement of the wheelset, m
  double yaw = 0.0;          ///< rad
  double z = 0.0;            ///< height of the wheelset centre (rigid solution), m
  double roll = 0.0;         ///< roll angle (rigid solution), rad
  double delta_r = 0.0;      ///< r_left - r_right, m
  double z_loaded = 0.0;     ///< height of the wheelset centre under the load case, m
  double roll_loaded = 0.0;  ///< roll angle under the load case, rad
  double pitch_rate = 0.0;   ///< wheelset angular velocity about its axle under the load case, rad/s
  ContactGeometryWheel left, right;
};

/// Builds tables for one wheel profile / rail profile / wheelset. Not for use in a time step.
class ContactGeometryTable {
 public:
  /// rail: the rail profile curve in its (inclined) profile frame, e.g. makeUic60Rail(1.0 / 40).
  /// Throws std::runtime_error on non-physical data.
  ContactGeometryTable(const WheelProfile& wheel, const ProfileCurve& rail, const WheelsetTrackSpec& spec,
                       const WheelContactOptions& options = {});

  /// Row at lateral displacement y (m) and yaw (rad); with a load case, the loaded columns too.
  ContactGeometryRow row(double y, double yaw = 0.0, const LoadCase& load = {});
  /// Rows for y = y_min, y_min + dy, ..., y_max, at yaw + yaw_per_y * y (rad, rad/m).
  std::vector<ContactGeometryRow> table(double y_min, double y_max, double dy, double yaw = 0.0,
                                        const LoadCase& load = {}, double yaw_per_y = 0.0);

  /// Half the lateral distance between the two wheels' contact points at y = 0, m (EN 15302's e0).
  double contactHalfDistance();
  /// Lateral distance between the wheel centres (taping-line planes) / 2, m.
  double wheelHalfDistance() const { return e_wheel_; }
  /// Rail profile origin distance from the track centre, m.
  double railHalfSpacing() const { return h_rail_; }
  const TrackGeometry& track() const { return *track_; }
  const WheelContactModel& model() const { return *model_; }
  const WheelsetTrackSpec& spec() const { return spec_; }

 private:
  bool solveRigid(double y, double yaw, double& z, double& roll);
  bool solveLoaded(double y, double yaw, const LoadCase& load, double& z, double& roll, double& omega,
                   std::string* why);
  void place(double y, double yaw, double z, double roll, double speed, double omega, WheelState& left,
             WheelState& right) const;
  double wheelGap(const ContactGeometry* g, int& kind) const;
  void detectBoth(double y, double yaw, double z, double roll, ContactGeometry (&left)[2], ContactGeometry (&right)[2]);

  WheelsetTrackSpec spec_;
  std::unique_ptr<TrackGeometry> track_;
  std::unique_ptr<WheelContactModel> model_;
  double e_wheel_ = 0.0, h_rail_ = 0.0, x0_ = 0.0, z_guess_ = 0.0, roll_guess_ = 0.0;
  Eigen::Vector2d rail_top_yz_ = Eigen::Vector2d::Zero();  // highest point of the rail, profile frame
  WheelContactWork work_[2];
};

/// Equivalent conicity by the EN 15302 principle: the wavelength lambda of the kinematic (Klingel) motion
///   d^2 y / dx^2 = -Delta r(y) / (2 e0 r0),   y(0) = amplitude, y'(0) = 0,
/// integrated with Delta r(y) interpolated linearly in the table (y_table increasing, m), gives the
/// conicity of the conical wheelset with the same wavelength: gamma_e = e0 r0 (2 pi / lambda)^2.
/// e0: half the lateral distance between the contact points (m), r0: nominal rolling radius (m).
/// Returns NaN if the motion does not oscillate within the table range; wavelength_out (m) if not null.
double equivalentConicity(const std::vector<double>& y_table, const std::vector<double>& delta_r_table,
                          double amplitude, double e0, double r0, double* wavelength_out = nullptr);

/// Writes the solved rows (ok) as CSV with a header of named columns with units and returns how many it
/// wrote; rows that are not ok are left out (the caller reports them). Throws std::runtime_error if the
/// file cannot be written.
int writeContactGeometryCsv(const std::string& path, const std::vector<ContactGeometryRow>& rows);

}  // namespace contact
}  // namespace rail
