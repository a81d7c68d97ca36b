// Scene helpers: signed curvature and cant, names of the choices, the resolved YAML form and the
// human-readable summary of what a run simulates.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <sstream>

#include <rail_contact/format.hpp>

#include "rail_core/scene.hpp"
#include "rail_core/scene_loader.hpp"
#include "rail_core/yaml_reader.hpp"

namespace rail::core {

using contact::formatNumber;

namespace {
double sideSign(Direction d) { return d == Direction::kRight ? -1.0 : 1.0; }
double curvatureOf(double radius, Direction d) { return radius > 0.0 ? sideSign(d) / radius : 0.0; }
}  // namespace

double Segment::curvatureAtStart() const {
  switch (type) {
    case SegmentType::kStraight:
      return 0.0;
    case SegmentType::kCircular:
      return curvatureOf(radius, direction);
    case SegmentType::kTransition:
      return curvatureOf(radius_start, direction);
  }
  return 0.0;
}
double Segment::curvatureAtEnd() const {
  return type == SegmentType::kTransition ? curvatureOf(radius_end, direction) : curvatureAtStart();
}
// The outer rail of a left curve is the right rail: positive cant raises the right rail.
double Segment::signedCantAtStart() const {
  return sideSign(direction) * (type == SegmentType::kTransition ? cant_start : cant);
}
double Segment::signedCantAtEnd() const {
  return sideSign(direction) * (type == SegmentType::kTransition ? cant_end : cant);
}

double Track::length() const {
  double l = 0.0;
  for (const auto& s : segments) l += s.length;
  return l;
}

namespace {

// A number as a YAML float: formatNumber's exact text, ".0" on a whole number (so YAML reads a float, not an
// integer), YAML's spellings of nan and inf.
std::string yamlNumber(double v) {
  if (std::isnan(v)) return ".nan";
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  std::string s = formatNumber(v);
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

// Emits numbers in their shortest exact form so the resolved scene reads back bit for bit.
YAML::Emitter& num(YAML::Emitter& e, const char* key, double v) {
  return e << YAML::Key << key << YAML::Value << yamlNumber(v);
}
template <typename T>
YAML::Emitter& kv(YAML::Emitter& e, const char* key, const T& v) {
  return e << YAML::Key << key << YAML::Value << v;
}

void emitSegment(YAML::Emitter& e, const Segment& s) {
  e << YAML::BeginMap;
  kv(e, "type", toString(s.type));
  num(e, "length", s.length);
  if (s.direction != Direction::kNone) kv(e, "direction", toString(s.direction));
  switch (s.type) {
    case SegmentType::kStraight:
      num(e, "cant", s.cant);
      break;
    case SegmentType::kCircular:
      num(e, "radius", s.radius);
      num(e, "cant", s.cant);
      break;
    case SegmentType::kTransition:
      num(e, "radius_start", s.radius_start);
      num(e, "radius_end", s.radius_end);
      num(e, "cant_start", s.cant_start);
      num(e, "cant_end", s.cant_end);
      break;
  }
  num(e, "gradient", s.gradient);
  kv(e, "jump_allowed", s.jump_allowed);
  e << YAML::EndMap;
}

}  // namespace

std::string toYaml(const Scene& s) {
  YAML::Emitter e;
  e << YAML::BeginMap;
  kv(e, "name", s.name);
  if (!s.description.empty()) kv(e, "description", s.description);

  const Track& t = s.track;
  e << YAML::Key << "track" << YAML::Value << YAML::BeginMap;
  num(e, "gauge", t.gauge);
  num(e, "gauge_measuring_depth", t.gauge_measuring_depth);
  num(e, "cant_reference_width", t.cant_reference_width);
  kv(e, "rail_profile", t.rail_profile);
  num(e, "rail_inclination", t.rail_inclination);
  num(e, "sleeper_spacing", t.sleeper_spacing);
  kv(e, "rail_elements_between_sleepers", t.rail_elements_between_sleepers);
  num(e, "start_arc_length", t.start_arc_length);
  if (!t.data.empty()) kv(e, "data", t.data.as_written);
  e << YAML::Key << "segments" << YAML::Value << YAML::BeginSeq;
  for (const auto& seg : t.segments) emitSegment(e, seg);
  e << YAML::EndSeq;
  const Irregularities& irr = t.irregularities;
  e << YAML::Key << "irregularities" << YAML::Value << YAML::BeginMap;
  kv(e, "source", toString(irr.source));
  if (irr.source == IrregularitySource::kFile) kv(e, "file", irr.file.as_written);
  if (irr.source == IrregularitySource::kPsd) {
    kv(e, "psd", irr.psd);
    kv(e, "seed", irr.seed);
    num(e, "wavelength_min", irr.wavelength_min);
    num(e, "wavelength_max", irr.wavelength_max);
  }
  e << YAML::EndMap;
  if (!t.defects.empty()) {
    e << YAML::Key << "defects" << YAML::Value << YAML::BeginSeq;
    for (const contact::RailDefect& d : t.defects) {
      e << YAML::BeginMap;
      kv(e, "type", wordOf(kDefectShapeWords, d.shape));
      num(e, "s", d.s_centre);
      num(e, "length", d.length);
      kv(e, "rail", toString(d.left && d.right ? LoadRail::kBoth : d.left ? LoadRail::kLeft : LoadRail::kRight));
      if (d.shape == contact::DefectShape::kDippedJoint) num(e, "dip_angle", d.dip_angle);
      if (d.gap > 0.0) num(e, "gap", d.gap);
      if (d.shape == contact::DefectShape::kWeld) num(e, "height", d.height);
      e << YAML::EndMap;
    }
    e << YAML::EndSeq;
  }
  if (!t.support.empty()) {
    e << YAML::Key << "support" << YAML::Value << YAML::BeginSeq;
    for (const SupportZone& z : t.support) {
      e << YAML::BeginMap;
      num(e, "s_from", z.s_from);
      num(e, "s_to", z.s_to);
      num(e, "ramp", z.ramp);
      num(e, "pad_stiffness", z.pad_stiffness);
      num(e, "pad_damping", z.pad_damping);
      num(e, "ballast_stiffness", z.ballast_stiffness);
      num(e, "ballast_damping", z.ballast_damping);
      if (z.hanging) num(e, "sleeper_gap", z.sleeper_gap);
      e << YAML::EndMap;
    }
    e << YAML::EndSeq;
  }
  e << YAML::EndMap;

  if (s.has_vehicle) {
    const Vehicle& v = s.vehicle;
    e << YAML::Key << "vehicle" << YAML::Value << YAML::BeginMap;
    kv(e, "data", v.data.as_written);
    num(e, "start_arc_length", v.start_arc_length);
    num(e, "speed", v.speed);
    kv(e, "wheel_profile", v.wheel_profile);
    num(e, "nominal_radius", v.nominal_radius);
    num(e, "back_to_back", v.back_to_back);
    kv(e, "wheelsets", v.wheelsets);
    if (!v.wheel_defects.empty()) {
      e << YAML::Key << "wheel_defects" << YAML::Value << YAML::BeginSeq;
      for (const contact::WheelDefect& d : v.wheel_defects) {
        e << YAML::BeginMap;
        kv(e, "type", wordOf(kWheelDefectShapeWords, d.shape));
        kv(e, "wheelset", static_cast<int>(d.wheel / 2));
        kv(e, "side", toString(d.wheel % 2 == 0 ? LoadRail::kLeft : LoadRail::kRight));
        num(e, "angle", d.angle);
        if (d.shape == contact::WheelDefectShape::kFlat) {
          num(e, "length", d.length);
          kv(e, "shape", wordOf(kFlatShapeWords, d.rounded));
          if (d.rounded) num(e, "depth", d.depth);
        } else {
          kv(e, "order", d.order);
          num(e, "amplitude", d.amplitude);
        }
        e << YAML::EndMap;
      }
      e << YAML::EndSeq;
    }
    e << YAML::EndMap;
  } else {
    const MovingLoads& m = s.moving_loads;
    e << YAML::Key << "moving_loads" << YAML::Value << YAML::BeginMap;
    num(e, "start_arc_length", m.start_arc_length);
    num(e, "speed", m.speed);
    e << YAML::Key << "loads" << YAML::Value << YAML::BeginSeq;
    for (const auto& l : m.loads) {
      e << YAML::BeginMap;
      num(e, "offset", l.offset);
      kv(e, "rail", toString(l.rail));
      num(e, "vertical", l.vertical);
      num(e, "lateral", l.lateral);
      e << YAML::EndMap;
    }
    e << YAML::EndSeq << YAML::EndMap;
  }

  if (s.has_vehicle) {
    const Contact& c = s.contact;
    e << YAML::Key << "contact" << YAML::Value << YAML::BeginMap;
    num(e, "friction", c.friction);
    num(e, "restitution", c.restitution);
    num(e, "impact_velocity_floor", c.impact_velocity_floor);
    e << YAML::EndMap;
  }

  const Effects& f = s.effects;
  e << YAML::Key << "effects" << YAML::Value << YAML::BeginMap;
  kv(e, "track_model", toString(f.track_model));
  kv(e, "creep_law", toString(f.creep_law));
  for (const EffectSwitch& sw : kEffectSwitches) kv(e, sw.key, f.*sw.on);
  e << YAML::EndMap;

  const Solver& v = s.solver;
  e << YAML::Key << "solver" << YAML::Value << YAML::BeginMap;
  num(e, "track_step", v.track_step);
  num(e, "vehicle_rtol", v.vehicle_rtol);
  num(e, "vehicle_atol", v.vehicle_atol);
  num(e, "vehicle_max_step", v.vehicle_max_step);
  num(e, "standalone_max_step", v.standalone_max_step);
  kv(e, "vehicle_method", toString(v.vehicle_method));
  kv(e, "transport", toString(v.transport));
  num(e, "exchange_timeout", v.exchange_timeout);
  num(e, "handshake_timeout", v.handshake_timeout);
  e << YAML::Key << "end" << YAML::Value << YAML::BeginMap;
  num(e, toString(v.end.kind), v.end.value);
  e << YAML::EndMap;
  e << YAML::Key << "track_window" << YAML::Value << YAML::BeginMap;
  kv(e, "enabled", v.track_window.enabled);
  num(e, "behind", v.track_window.behind);
  num(e, "ahead", v.track_window.ahead);
  num(e, "shift", v.track_window.shift);
  num(e, "length", v.track_window.length);
  e << YAML::EndMap << YAML::EndMap;

  const Output& o = s.output;
  e << YAML::Key << "output" << YAML::Value << YAML::BeginMap;
  kv(e, "bag", o.bag);
  num(e, "rate", o.rate);
  e << YAML::Key << "topics" << YAML::Value << YAML::Flow << o.topics;
  e << YAML::Key << "deflection_sections" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (double d : o.deflection_sections) e << yamlNumber(d);
  e << YAML::EndSeq;
  num(e, "pad_force_margin", o.pad_force_margin);
  e << YAML::EndMap;

  e << YAML::EndMap;
  return std::string(e.c_str()) + "\n";
}

namespace {

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

std::string segmentLine(const Segment& s) {
  std::string out = std::string(toString(s.type)) + " " + fixed(s.length, 1) + " m";
  switch (s.type) {
    case SegmentType::kStraight:
      if (s.cant > 0) out += ", cant " + fixed(s.cant * 1e3, 0) + " mm";
      break;
    case SegmentType::kCircular:
      out += ", R " + fixed(s.radius, 0) + " m " + toString(s.direction) + ", cant " + fixed(s.cant * 1e3, 0) + " mm";
      break;
    case SegmentType::kTransition: {
      auto r = [](double x) { return x > 0 ? "R " + fixed(x, 0) + " m" : std::string("straight"); };
      out += ", " + r(s.radius_start) + " -> " + r(s.radius_end);
      if (s.direction != Direction::kNone) out += std::string(" ") + toString(s.direction);
      out += ", cant " + fixed(s.cant_start * 1e3, 0) + " -> " + fixed(s.cant_end * 1e3, 0) + " mm";
      break;
    }
  }
  if (s.gradient != 0.0) out += ", gradient " + fixed(s.gradient * 1e3, 1) + " per mille";
  return out;
}

}  // namespace

std::string describe(const Scene& s, Role role) {
  std::ostringstream o;
  const Track& t = s.track;
  const Effects& f = s.effects;
  char hash[32];
  std::snprintf(hash, sizeof(hash), "%016llx", static_cast<unsigned long long>(s.hash));
  o << "scene '" << s.name << "' (" << s.file << "), hash " << hash << "\n";
  o << "track: " << fixed(t.length(), 1) << " m from s = " << fixed(t.start_arc_length, 1) << " m, gauge "
    << fixed(t.gauge * 1e3, 0) << " mm, rail " << t.rail_profile
    << (t.rail_inclination == 0.0 ? std::string(" with no inclination added (as the profile gives it)")
                                  : " at 1/" + fixed(1.0 / t.rail_inclination, 0))
    << ", sleepers every " << fixed(t.sleeper_spacing, 2) << " m\n";
  for (std::size_t i = 0; i < t.segments.size(); ++i) {
    o << "  segment " << i << ": " << segmentLine(t.segments[i]) << "\n";
  }
  if (f.track_defects) {
    for (std::size_t i = 0; i < t.defects.size(); ++i) {
      const contact::RailDefect& d = t.defects[i];
      o << "  defect " << i << ": " << wordOf(kDefectShapeWords, d.shape) << " at s = " << fixed(d.s_centre, 2)
        << " m, "
        << (d.left && d.right ? "both rails"
            : d.left          ? "left rail"
                              : "right rail")
        << ", " << fixed(d.length, 3) << " m long, "
        << (d.shape == contact::DefectShape::kDippedJoint
                ? "total angle " + fixed(d.dip_angle * 1e3, 1) + " mrad" +
                      (d.gap > 0.0 ? ", gap " + fixed(d.gap * 1e3, 1) + " mm" : std::string())
                : "height " + fixed(d.height * 1e3, 2) + " mm")
        << "\n";
    }
  }
  if (f.support_variation) {
    for (std::size_t i = 0; i < t.support.size(); ++i) {
      const SupportZone& z = t.support[i];
      o << "  support zone " << i << ": s = " << fixed(z.s_from, 2) << " .. " << fixed(z.s_to, 2) << " m, ramps "
        << fixed(z.ramp, 2) << " m; pads x" << fixed(z.pad_stiffness, 2) << " stiffness, x" << fixed(z.pad_damping, 2)
        << " damping; ballast x" << fixed(z.ballast_stiffness, 2) << " stiffness, x" << fixed(z.ballast_damping, 2)
        << " damping" << (z.hanging ? "; hanging sleepers, gap " + fixed(z.sleeper_gap * 1e3, 2) + " mm" : "") << "\n";
    }
  }
  if (s.has_vehicle) {
    const Vehicle& v = s.vehicle;
    o << "vehicle: " << v.data.as_written << ", " << v.wheelsets << " wheelsets, " << fixed(v.speed * 3.6, 1)
      << " km/h from s = " << fixed(v.start_arc_length, 1) << " m, wheel " << v.wheel_profile
      << " r0 = " << fixed(v.nominal_radius, 3) << " m\n";
    if (f.wheel_defects) {
      for (std::size_t i = 0; i < v.wheel_defects.size(); ++i) {
        const contact::WheelDefect& d = v.wheel_defects[i];
        o << "  wheel defect " << i << ": " << wordOf(kWheelDefectShapeWords, d.shape) << " on wheelset " << d.wheel / 2
          << " " << (d.wheel % 2 == 0 ? "left" : "right") << " at " << fixed(d.angle, 2) << " rad, ";
        if (d.shape == contact::WheelDefectShape::kOutOfRound) {
          o << "order " << d.order << ", amplitude " << fixed(d.amplitude * 1e3, 3) << " mm";
        } else {
          const double depth = d.rounded ? d.depth : contact::WheelDefects::newFlatDepth(d.length, v.nominal_radius);
          o << wordOf(kFlatShapeWords, d.rounded) << ", " << fixed(d.length * 1e3, 1) << " mm long, "
            << fixed(depth * 1e3, 3) << " mm deep";
        }
        o << "\n";
      }
    }
  } else {
    o << "moving loads: " << s.moving_loads.loads.size() << " load(s) at " << fixed(s.moving_loads.speed, 2)
      << " m/s from s = " << fixed(s.moving_loads.start_arc_length, 1) << " m\n";
  }
  std::vector<std::string> on{std::string("track_model=") + toString(f.track_model)}, off;
  auto flag = [&](const char* name, bool v) { (v ? on : off).push_back(name); };
  flag("irregularities", f.irregularities);
  flag("track_defects", f.track_defects);
  flag("wheel_defects", f.wheel_defects && s.has_vehicle);
  flag("support_variation", f.support_variation && s.runsFeIntegration());
  // Contact exists only with a vehicle (moving loads are prescribed forces).
  flag("flange_contact", f.flange_contact && s.has_vehicle);
  flag("spin_creepage", f.spin_creepage && s.has_vehicle);
  if (s.has_vehicle) on.push_back(std::string("creep_law=") + toString(f.creep_law));
  // The track's own effects exist only where the FE track is integrated.
  flag("track_damping", f.track_damping && s.runsFeIntegration());
  flag("absorbing_ends", f.absorbing_ends && s.runsFeIntegration());
  flag("rail_deflection_output", f.rail_deflection_output && s.runsFeIntegration());
  flag("contact_point_output", f.contact_point_output && s.has_vehicle);
  flag("rviz_markers", f.rviz_markers);
  flag("floor_acceleration_output", f.floor_acceleration_output && s.has_vehicle);
  flag("pad_force_output", f.pad_force_output && s.effects.track_model == TrackModel::kFlexible);
  flag("energy_output", f.energy_output && s.has_vehicle);
  o << "effects on: " << join(on) << "\n";
  o << "effects off: " << (off.empty() ? "none" : join(off)) << "\n";
  const Solver& v = s.solver;
  o << "solver: "
    << (v.end.kind == EndKind::kTime ? "until t = " + fixed(v.end.value, 3) + " s"
                                     : "until s = " + fixed(v.end.value, 1) + " m");
  if (s.needsTrackNode()) o << ", track step " << formatNumber(v.track_step) << " s";
  if (s.runsFeIntegration() && s.has_vehicle) {
    o << (v.track_window.enabled ? ", moving track window (" + fixed(v.track_window.behind, 1) + " m behind, " +
                                       fixed(v.track_window.ahead, 1) + " m ahead)"
                                 : ", whole track integrated");
  }
  if (s.has_vehicle) {
    // The cap this run uses: the co-simulation's, or the vehicle alone's (solver.standalone_max_step).
    const double max_step = s.cosimulation() ? v.vehicle_max_step : v.standalone_max_step;
    o << ", vehicle rtol " << formatNumber(v.vehicle_rtol) << " atol " << formatNumber(v.vehicle_atol) << " max step "
      << (max_step > 0.0 ? formatNumber(max_step) + " s" : std::string("none")) << " (" << toString(v.vehicle_method)
      << ")";
  }
  if (s.cosimulation())
    o << ", transport " << toString(v.transport) << ", timeout " << fixed(v.exchange_timeout, 1) << " s";
  o << "\n";

  // Components this process builds (the FE sizes follow the mesh rules of the track model).
  // The loader bounds the length (1000 km), so the count fits; clamped all the same rather than overflow.
  const double sleepers_d = std::floor(t.length() / t.sleeper_spacing + 1e-9) + 1.0;
  const long sleepers = std::isfinite(sleepers_d) && sleepers_d < 1e12 ? static_cast<long>(sleepers_d) : 0;
  const long rail_nodes = (sleepers - 1) * t.rail_elements_between_sleepers + 1;
  const long free_nodes = 2 * rail_nodes + 6 * sleepers;
  std::string builds;
  auto add = [&](const std::string& x) { builds += "  - " + x + "\n"; };
  const bool vehicle_side = role == Role::kVehicle || role == Role::kValidator;
  const bool track_side = role == Role::kTrack || role == Role::kValidator;
  if (vehicle_side && s.has_vehicle) {
    add("vehicle: multibody model from " + s.vehicle.data.as_written + ", " + std::to_string(s.wheelCount()) +
        " wheels, integrated by CVODE");
    if (f.track_model == TrackModel::kRigid) {
      add(std::string("wheel-rail contact on the rigid track geometry: tread") +
          (f.flange_contact ? " and flange" : " only") + ", Hertz normal force, Polach creep forces" +
          (f.spin_creepage ? " with spin" : " without spin"));
    } else {
      add(std::string("wheel-centre wrenches from the track node over ") + toString(v.transport) +
          ", extrapolated between track steps");
    }
  }
  if (track_side && s.needsTrackNode()) {
    if (s.runsFeIntegration()) {
      add("FE track: " + std::to_string(sleepers) + " sleepers, " + std::to_string(2 * rail_nodes) +
          " rail nodes, about " + std::to_string(6 * free_nodes) + " DOF, Newmark step " + formatNumber(v.track_step) +
          " s, CHOLMOD factor");
      add(std::string("track damping ") + (f.track_damping ? "on" : "off") + ", absorbing ends " +
          (f.absorbing_ends ? "on" : "off"));
    } else {
      add("rigid FE rails: contact on the undeformed rails, no FE integration");
    }
    if (s.has_vehicle) {
      add(std::string("wheel-rail contact on the ") + (s.runsFeIntegration() ? "deformed" : "undeformed") +
          " rails: tread" + (f.flange_contact ? " and flange" : " only") + ", Polach" +
          (f.spin_creepage ? " with spin" : " without spin"));
    } else {
      add(std::to_string(s.moving_loads.loads.size()) + " prescribed moving load(s)");
    }
    if (f.rail_deflection_output && s.runsFeIntegration()) {
      add("rail deflection output at " + std::to_string(s.output.deflection_sections.size()) + " section(s)");
    }
  }
  if (role == Role::kTrack && !s.needsTrackNode()) add("nothing: track_model is rigid, the vehicle runs alone");
  if (role == Role::kVehicle && !s.has_vehicle) add("nothing: the scene has no vehicle");
  if (!builds.empty()) o << "builds:\n" << builds;
  o << "output: " << (s.output.bag.empty() ? "no bag" : "bag " + s.output.bag) << ", " << fixed(s.output.rate, 0)
    << " Hz";
  if (!s.output.topics.empty()) {
    o << ", topics";
    for (const auto& tp : s.output.topics) o << " " << tp;
  }
  o << "\n";
  for (const std::string& w : sceneWarnings(s)) o << "warning: " << w << "\n";
  return o.str();
}

}  // namespace rail::core
