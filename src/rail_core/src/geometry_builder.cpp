// Scene -> track geometry (see geometry_builder.hpp).
#include "rail_core/geometry_builder.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <string>

#include "rail_core/scene_loader.hpp"

namespace rail::core {

namespace rc = rail::contact;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDefaultTableStep = 0.1;     // m, table spacing of the geometry (doc/geometry.md)
constexpr int kMinHarmonics = 4096;           // PSD harmonics, the rail_contact default

[[noreturn]] void fail(const Scene& scene, const std::string& field, const std::string& what) {
  throw SceneError(scene.file + ": " + field + ": " + what);
}

// "track geometry: segments[2].length = ..." -> "track.segments[2].length"; other messages -> "track".
std::string geometry_field(const std::string& message) {
  const std::string prefix = "track geometry: ";
  if (message.compare(0, prefix.size(), prefix) != 0) return "track";
  const std::string rest = message.substr(prefix.size());
  const std::size_t end = rest.find_first_of(" =");
  const std::string key = rest.substr(0, end);
  if (key.compare(0, 9, "segments[") == 0) return "track." + key;
  if (key == "cant_reference_width" || key == "rail_inclination") return "track." + key;
  return "track";
}

rc::SegmentSpec::Type segment_type(SegmentType t) {
  switch (t) {
    case SegmentType::kStraight: return rc::SegmentSpec::Type::Straight;
    case SegmentType::kTransition: return rc::SegmentSpec::Type::Transition;
    case SegmentType::kCircular: return rc::SegmentSpec::Type::Circular;
  }
  return rc::SegmentSpec::Type::Straight;
}

bool irregularities_on(const Scene& scene) {
  return scene.effects.irregularities && scene.track.irregularities.source != IrregularitySource::kNone;
}

}  // namespace

rc::ProfileCurve rail_profile_curve(const Scene& scene) {
  try {
    if (scene.track.rail_profile_file.empty()) return rc::makeUic60Rail(0.0);
    return rc::loadRailProfile(scene.track.rail_profile_file.path);
  } catch (const std::exception& e) {
    fail(scene, "track.rail_profile", e.what());
  }
}

rc::WheelProfile wheel_profile(const Scene& scene) {
  try {
    if (scene.vehicle.wheel_profile_file.empty()) return rc::makeS1002();
    return rc::loadWheelProfile(scene.vehicle.wheel_profile_file.path);
  } catch (const std::exception& e) {
    fail(scene, "vehicle.wheel_profile", e.what());
  }
}

rc::WheelContactOptions contact_options(const Scene& scene, rc::WheelContactOptions base) {
  base.flange_contact = scene.effects.flange_contact;
  base.spin = scene.effects.spin_creepage;
  base.creep_law = rc::CreepLaw::kPolach;  // the scene's contact.creep_law has Polach only
  base.friction = scene.contact.friction;
  base.damping.restitution = scene.contact.restitution;
  base.damping.impact_velocity_floor = scene.contact.impact_velocity_floor;
  return base;
}

Eigen::Vector2d gauge_point_in_track_plane(const rc::ProfileCurve& rail_own_frame, double inclination,
                                           double depth) {
  // tiltProfile takes the tan of the tilt.
  const rc::ProfilePoints tilted = rc::tiltProfile(rail_own_frame.nodes(), std::tan(inclination));
  const rc::ProfileCurve curve(tilted, rc::SolidSide::Right);
  return rc::gaugePoint(curve, depth);
}

double rail_half_spacing(double gauge, const Eigen::Vector2d& gauge_point_in_track_plane) {
  // Left rail: the profile's y points toward the centre (-n), so its gauge point sits at h - y_g from the
  // centre line; the two gauge points are 2 (h - y_g) = gauge apart.
  return 0.5 * gauge + gauge_point_in_track_plane.x();
}

rc::GeometrySpec geometry_spec(const Scene& scene) {
  const Track& t = scene.track;
  rc::GeometrySpec spec;
  spec.s_start = t.start_arc_length;
  spec.cant_reference_width = t.cant_reference_width;
  spec.rail_inclination = std::atan(t.rail_inclination);
  spec.rail_vertical_offset = 0.0;
  for (const Segment& s : t.segments) {
    rc::SegmentSpec g;
    g.type = segment_type(s.type);
    g.length = s.length;
    g.curvature_start = s.curvature_at_start();
    g.curvature_end = s.curvature_at_end();
    g.cant_start = s.signed_cant_at_start();
    g.cant_end = s.signed_cant_at_end();
    g.gradient = s.gradient;
    spec.segments.push_back(g);
  }
  const rc::ProfileCurve rail = rail_profile_curve(scene);
  Eigen::Vector2d gp;
  try {
    gp = gauge_point_in_track_plane(rail, spec.rail_inclination, t.gauge_measuring_depth);
  } catch (const std::exception& e) {
    fail(scene, "track.gauge_measuring_depth", e.what());
  }
  spec.rail_half_spacing = rail_half_spacing(t.gauge, gp);
  spec.table_step = kDefaultTableStep;
  if (irregularities_on(scene)) {
    const Irregularities& irr = t.irregularities;
    if (irr.source == IrregularitySource::kPsd)
      spec.table_step = std::min(spec.table_step, irr.wavelength_min / 8.0);
    // A table's shortest wavelength is only known once it is read: build_track_geometry refines then.
  }
  return spec;
}

rc::Irregularities build_irregularities(const Scene& scene) {
  if (!irregularities_on(scene)) return rc::Irregularities();
  const Irregularities& irr = scene.track.irregularities;
  if (irr.source == IrregularitySource::kFile) {
    try {
      return rc::Irregularities::fromCsvFile(irr.file.path);
    } catch (const std::exception& e) {
      fail(scene, "track.irregularities.file", e.what());
    }
  }
  rc::PsdRealisationSpec psd;
  try {
    psd.spectrum = rc::psdSpectrumFromName(irr.psd);
  } catch (const std::exception& e) {
    fail(scene, "track.irregularities.psd", e.what());
  }
  psd.seed = irr.seed;
  psd.wavelength_min = irr.wavelength_min;
  psd.wavelength_max = irr.wavelength_max;
  psd.s_reference = scene.track.start_arc_length;
  // repeat length 2 pi / dOmega = harmonics * 2 pi / (Omega_max - Omega_min) must exceed the track length.
  const double band = 2.0 * kPi / irr.wavelength_min - 2.0 * kPi / irr.wavelength_max;
  const double needed = std::ceil(1.1 * scene.track.length() * band / (2.0 * kPi));
  psd.harmonics = std::max(kMinHarmonics, static_cast<int>(std::min(needed, 1.0e6)));
  try {
    return rc::Irregularities::fromPsd(psd);
  } catch (const std::exception& e) {
    fail(scene, "track.irregularities", e.what());
  }
}

rc::TrackGeometry build_track_geometry(const Scene& scene) {
  rc::GeometrySpec spec = geometry_spec(scene);
  const rc::Irregularities irr = build_irregularities(scene);
  if (!irr.empty()) spec.table_step = std::min(spec.table_step, irr.shortestWavelength() / 8.0);
  try {
    return rc::TrackGeometry(spec, irr);
  } catch (const std::exception& e) {
    fail(scene, geometry_field(e.what()), e.what());
  }
}

}  // namespace rail::core
