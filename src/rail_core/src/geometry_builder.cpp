// Scene -> track geometry (see geometry_builder.hpp).
#include "rail_core/geometry_builder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <string>
#include <utility>

#include "rail_core/scene_loader.hpp"

namespace rail::core {

namespace rc = rail::contact;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDefaultTableStep = 0.1;  // m, table spacing of the geometry (doc/geometry.md)
constexpr int kMinHarmonics = 4096;        // PSD harmonics, the rail_contact default

[[noreturn]] void fail(const Scene& scene, const std::string& field, const std::string& what) {
  throw SceneError(scene.file + ": " + field + ": " + what);
}

// "track geometry: segments[2].length = ..." -> "track.segments[2].length"; other messages -> "track".
std::string geometryField(const std::string& message) {
  const std::string prefix = "track geometry: ";
  if (message.compare(0, prefix.size(), prefix) != 0) return "track";
  const std::string rest = message.substr(prefix.size());
  const std::size_t end = rest.find_first_of(" =");
  const std::string key = rest.substr(0, end);
  if (key.compare(0, 9, "segments[") == 0) return "track." + key;
  if (key == "cant_reference_width" || key == "rail_inclination") return "track." + key;
  return "track";
}

rc::SegmentSpec::Type segmentType(SegmentType t) {
  switch (t) {
    case SegmentType::kStraight:
      return rc::SegmentSpec::Type::Straight;
    case SegmentType::kTransition:
      return rc::SegmentSpec::Type::Transition;
    case SegmentType::kCircular:
      return rc::SegmentSpec::Type::Circular;
  }
  return rc::SegmentSpec::Type::Straight;
}

bool irregularitiesOn(const Scene& scene) {
  return scene.effects.irregularities && scene.track.irregularities.source != IrregularitySource::kNone;
}

}  // namespace

rc::ProfileCurve railProfileCurve(const Scene& scene) {
  try {
    if (scene.track.rail_profile_file.empty()) return rc::makeUic60Rail(0.0);
    return rc::loadRailProfile(scene.track.rail_profile_file.path);
  } catch (const std::exception& e) {
    fail(scene, "track.rail_profile", e.what());
  }
}

rc::WheelProfile wheelProfile(const Scene& scene) {
  try {
    if (scene.vehicle.wheel_profile_file.empty()) return rc::makeS1002();
    return rc::loadWheelProfile(scene.vehicle.wheel_profile_file.path);
  } catch (const std::exception& e) {
    fail(scene, "vehicle.wheel_profile", e.what());
  }
}

SceneContact sceneContact(const Scene& scene) {
  SceneContact c;
  c.flange_contact = scene.effects.flange_contact;
  c.spin = scene.effects.spin_creepage;
  c.section = scene.contact;
  if (scene.effects.wheel_defects)
    c.wheel_defects = rc::WheelDefects(scene.vehicle.wheel_defects, scene.vehicle.nominal_radius);
  return c;
}

rc::WheelContactOptions SceneContact::over(rc::WheelContactOptions base) const {
  base.flange_contact = flange_contact;
  base.spin = spin;
  base.creep_law = rc::CreepLaw::kPolach;  // the scene's contact.creep_law has Polach only
  base.friction = section.friction;
  base.damping.restitution = section.restitution;
  base.damping.impact_velocity_floor = section.impact_velocity_floor;
  base.wheel_defects = wheel_defects;
  return base;
}

std::vector<DefectOutline> defectOutlines(const Scene& scene, const rc::TrackGeometry& geometry) {
  std::vector<DefectOutline> out;
  auto samples = [](double from, double to, double spacing) {
    return std::max(2, static_cast<int>(std::ceil((to - from) / spacing)) + 1);
  };
  char text[96];
  if (scene.effects.track_defects) {
    for (const rc::RailDefect& d : scene.track.defects) {
      if (d.shape == rc::DefectShape::kDippedJoint) {
        if (d.gap > 0.0)
          std::snprintf(text, sizeof(text), "dipped joint %.1f mrad, gap %.0f mm", d.dip_angle * 1e3, d.gap * 1e3);
        else
          std::snprintf(text, sizeof(text), "dipped joint %.1f mrad", d.dip_angle * 1e3);
      } else {
        std::snprintf(text, sizeof(text), "weld %+.2f mm", d.height * 1e3);
      }
      for (const rc::RailSide side : {rc::RailSide::kLeft, rc::RailSide::kRight}) {
        if (side == rc::RailSide::kLeft ? !d.left : !d.right) continue;
        DefectOutline o;
        o.label = text;
        const double from = d.s_centre - 0.5 * d.length, to = d.s_centre + 0.5 * d.length;
        const int n = samples(from, to, 0.1);
        rc::RailPoint rp;
        for (int i = 0; i < n; ++i) {
          geometry.rail(side, from + (to - from) * i / (n - 1), rp);
          o.points.push_back(rp.p_origin_in_world);
        }
        out.push_back(std::move(o));
      }
    }
  }
  if (scene.effects.support_variation) {
    for (const SupportZone& z : scene.track.support) {
      DefectOutline o;
      o.kind = DefectOutline::Kind::kSupportZone;
      std::string label;
      auto factor = [&](const char* what, double f) {
        if (f == 1.0) return;
        std::snprintf(text, sizeof(text), "%s%s x%.2f", label.empty() ? "" : ", ", what, f);
        label += text;
      };
      factor("pads", z.pad_stiffness);
      factor("pad damping", z.pad_damping);
      factor("ballast", z.ballast_stiffness);
      factor("ballast damping", z.ballast_damping);
      if (z.hanging) {
        std::snprintf(text, sizeof(text), "%shanging sleepers, gap %.1f mm", label.empty() ? "" : ", ",
                      z.sleeper_gap * 1e3);
        label += text;
      }
      o.label = label.empty() ? "support zone" : label;
      const int n = samples(z.s_from, z.s_to, 1.0);
      rc::TrackPoint tp;
      for (int i = 0; i < n; ++i) {
        geometry.centre(z.s_from + (z.s_to - z.s_from) * i / (n - 1), tp);
        o.points.push_back(tp.p_center_in_world);
      }
      out.push_back(std::move(o));
    }
  }
  return out;
}

Eigen::Vector2d gaugePointInTrackPlane(const rc::ProfileCurve& rail_own_frame, double inclination, double depth) {
  // tiltProfile takes the tan of the tilt.
  const rc::ProfilePoints tilted = rc::tiltProfile(rail_own_frame.nodes(), std::tan(inclination));
  const rc::ProfileCurve curve(tilted, rc::SolidSide::Right);
  return rc::gaugePoint(curve, depth);
}

double railHalfSpacing(double gauge, const Eigen::Vector2d& gauge_point_in_track_plane) {
  // Left rail: the profile's y points toward the centre (-n), so its gauge point sits at h - y_g from the
  // centre line; the two gauge points are 2 (h - y_g) = gauge apart.
  return 0.5 * gauge + gauge_point_in_track_plane.x();
}

rc::GeometrySpec geometrySpec(const Scene& scene) {
  const Track& t = scene.track;
  rc::GeometrySpec spec;
  spec.s_start = t.start_arc_length;
  spec.cant_reference_width = t.cant_reference_width;
  spec.rail_inclination = std::atan(t.rail_inclination);
  spec.rail_vertical_offset = 0.0;
  for (const Segment& s : t.segments) {
    rc::SegmentSpec g;
    g.type = segmentType(s.type);
    g.length = s.length;
    g.curvature_start = s.curvatureAtStart();
    g.curvature_end = s.curvatureAtEnd();
    g.cant_start = s.signedCantAtStart();
    g.cant_end = s.signedCantAtEnd();
    g.gradient = s.gradient;
    spec.segments.push_back(g);
  }
  const rc::ProfileCurve rail = railProfileCurve(scene);
  Eigen::Vector2d gp;
  try {
    gp = gaugePointInTrackPlane(rail, spec.rail_inclination, t.gauge_measuring_depth);
  } catch (const std::exception& e) {
    fail(scene, "track.gauge_measuring_depth", e.what());
  }
  spec.rail_half_spacing = railHalfSpacing(t.gauge, gp);
  spec.table_step = kDefaultTableStep;
  if (irregularitiesOn(scene)) {
    const Irregularities& irr = t.irregularities;
    if (irr.source == IrregularitySource::kPsd) spec.table_step = std::min(spec.table_step, irr.wavelength_min / 8.0);
    // A table's shortest wavelength is only known once it is read: buildTrackGeometry refines then.
  }
  return spec;
}

rc::Irregularities buildIrregularities(const Scene& scene) {
  if (!irregularitiesOn(scene)) return rc::Irregularities();
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

rc::TrackGeometry buildTrackGeometry(const Scene& scene) {
  rc::GeometrySpec spec = geometrySpec(scene);
  const rc::Irregularities irr = buildIrregularities(scene);
  if (!irr.empty()) spec.table_step = std::min(spec.table_step, irr.shortestWavelength() / 8.0);
  rc::TrackDefects defects;
  if (scene.effects.track_defects) {
    std::vector<rc::RailDefect> list = scene.track.defects;
    for (rc::RailDefect& d : list) d.wheel_radius = scene.has_vehicle ? scene.vehicle.nominal_radius : 0.0;
    defects = rc::TrackDefects(std::move(list));
  }
  try {
    return rc::TrackGeometry(spec, irr, std::move(defects));
  } catch (const std::exception& e) {
    fail(scene, geometryField(e.what()), e.what());
  }
}

}  // namespace rail::core
