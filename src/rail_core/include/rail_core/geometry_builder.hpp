// Scene -> rail_contact: the track geometry (the GeometrySpec of segments, cant base, rail spacing and
// inclination; the irregularities; the TrackGeometry built from them), the profiles and the contact options,
// built here once for both sides of a co-simulation. ROS-free; used at build time only. Errors of the geometry, profile
// or irregularity code come back as SceneError naming the scene file and the field.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include <rail_contact/irregularities.hpp>
#include <rail_contact/profile.hpp>
#include <rail_contact/track_geometry.hpp>
#include <rail_contact/wheel_contact.hpp>

#include "rail_core/scene.hpp"

namespace rail::core {

// The scene's rail profile in the rail's own cross-section frame (untilted: origin on top of the head,
// y toward the track centre, z up the rail axis). The built-in "uic60" is the EN 13674-1 60E1 head; a
// profile file is read as given (its coordinates are taken in the rail's own frame, like the built-in).
rail::contact::ProfileCurve railProfileCurve(const Scene& scene);

// The scene's wheel profile: the built-in S1002 (EN 13715), or vehicle.wheel_profile's file. Throws
// SceneError naming vehicle.wheel_profile.
rail::contact::WheelProfile wheelProfile(const Scene& scene);

// What the scene says about the wheel-rail contact, resolved once; over(base) writes it over a side's
// contact data (the caller's numerical settings: materials, Polach's parameters, detection).
struct SceneContact {
  bool flange_contact = true;                 // effects.flange_contact
  bool spin = true;                           // effects.spin_creepage
  Contact section;                            // contact: friction, restitution, impact-velocity floor
  rail::contact::WheelDefects wheel_defects;  // effects.wheel_defects: the vehicle's defects, else none
  // base with flange_contact, spin, Polach's creep law, the friction and the impact damping of the section,
  // and the wheel defects.
  rail::contact::WheelContactOptions over(rail::contact::WheelContactOptions base) const;
};
SceneContact sceneContact(const Scene& scene);

// Where a scene's local defects are, for the picture (rviz): a dipped joint or a weld as a line along the
// top of each rail it is on, a support zone as a line along the centre line at the sleepers' level, each with
// a short label. Only the effects that are on; empty when none is. Points at most 0.1 m (rail defects) or
// 1 m (zones) apart, world frame.
struct DefectOutline {
  enum class Kind { kRailDefect, kSupportZone };
  Kind kind = Kind::kRailDefect;
  std::string label;  // e.g. "dipped joint 10.0 mrad", "ballast x4.00"
  std::vector<Eigen::Vector3d> points;
};
std::vector<DefectOutline> defectOutlines(const Scene& scene, const rail::contact::TrackGeometry& geometry);

// Gauge point of a rail (EN 13848-1: on the gauge face, depth below the running surface) in a frame
// aligned with the track plane with its origin at the rail profile origin: y toward the track centre,
// z normal to the track plane (m). The profile is tilted by the inclination (rad) first, so "below the
// running surface" is measured normal to the track plane.
Eigen::Vector2d gaugePointInTrackPlane(const rail::contact::ProfileCurve& rail_own_frame, double inclination,
                                       double depth);

// Centre line to each rail's profile origin, in the track plane (m), such that the two gauge points are
// `gauge` apart: gauge / 2 + y of the gauge point (gauge_point_in_track_plane).
double railHalfSpacing(double gauge, const Eigen::Vector2d& gauge_point_in_track_plane);

// GeometrySpec of the scene: signed curvature and cant per segment (curvature > 0 curves left, cant > 0
// raises the right rail), cant_reference_width, rail inclination atan(ratio), rail_half_spacing from the
// gauge and the gauge point, rail profile origins on the centre line's level (rail_vertical_offset 0),
// table step 0.1 m or finer when the irregularities need it. Throws SceneError.
rail::contact::GeometrySpec geometrySpec(const Scene& scene);

// The scene's irregularities when effects.irregularities is on and track.irregularities has a source,
// else "none" (empty; nothing is read or generated). A PSD realisation gets enough harmonics that it does
// not repeat within the track. Throws SceneError.
rail::contact::Irregularities buildIrregularities(const Scene& scene);

// The track geometry of the scene (geometrySpec + buildIrregularities). Throws SceneError.
rail::contact::TrackGeometry buildTrackGeometry(const Scene& scene);

}  // namespace rail::core
