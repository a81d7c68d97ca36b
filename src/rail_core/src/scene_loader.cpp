// Scene loading and validation: YAML text -> resolved Scene, one clear error per bad input.
#include "rail_core/scene_loader.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include <unistd.h>

#include <rail_contact/format.hpp>

#include "rail_core/yaml_reader.hpp"

namespace rail::core {

using contact::formatNumber;

namespace {
[[noreturn]] void raiseSceneError(const std::string& message) { throw SceneError(message); }

// "<file>: <path>: <what> (line N)" as a SceneError.
[[noreturn]] void failScene(const std::string& file, const std::string& path, const std::string& what, int line) {
  failAt(file, path, what, line, raiseSceneError);
}
}  // namespace

const std::vector<std::string> kKnownTopics = {
    "wheel_states", "contact_wrenches",    "contact_points", "rail_deflection", "wheelset_kinematics", "markers", "tf",
    "clock",        "floor_accelerations", "pad_forces",     "vehicle_energy",  "track_energy"};

std::string topicNeeds(const Scene& s, const std::string& t) {
  const char* needs = nullptr;
  if (t == "rail_deflection" && !s.effects.rail_deflection_output) needs = "effects.rail_deflection_output: true";
  if (t == "contact_points" && !s.effects.contact_point_output) needs = "effects.contact_point_output: true";
  if (t == "markers" && !s.effects.rviz_markers) needs = "effects.rviz_markers: true";
  if (t == "floor_accelerations" && !s.effects.floor_acceleration_output)
    needs = "effects.floor_acceleration_output: true";
  if (t == "pad_forces" && !s.effects.pad_force_output) needs = "effects.pad_force_output: true";
  if ((t == "vehicle_energy" || t == "track_energy") && !s.effects.energy_output) needs = "effects.energy_output: true";
  if (needs) return "'" + t + "' is recorded only with " + needs;
  if (t == "rail_deflection" && s.effects.track_model == TrackModel::kRigid)
    return "'rail_deflection' needs a track node: effects.track_model flexible, or rigid_fe (rails that do not move: "
           "zeros)";
  if (t == "track_energy" && s.effects.track_model != TrackModel::kFlexible)
    return "'track_energy' needs the integrated FE track: effects.track_model flexible";
  if (t == "pad_forces" && s.effects.track_model != TrackModel::kFlexible)
    return "'pad_forces' needs the integrated FE track: effects.track_model flexible";
  if ((t == "wheel_states" || t == "wheelset_kinematics" || t == "contact_wrenches" || t == "floor_accelerations") &&
      !s.has_vehicle)
    return "'" + t + "' needs a vehicle in the scene";
  return {};
}

// Impacts (a dipped joint, a wheel flat): their first peak P1 needs the track step of the paper's converged
// value; at 4e-5 s a 10 mrad joint's P1 at 110 km/h came out 56 % high and at 8e-5 s 66 % (P2 moved by
// 1-2 %), and output below 5 kHz under-samples an impact of about a millisecond (docs/defects.md).
constexpr double kImpactTrackStep = 2e-5;
constexpr double kImpactOutputRate = 5000.0;

std::vector<std::string> sceneWarnings(const Scene& s) {
  std::vector<std::string> w;
  bool joint = false, flat = false;
  if (s.effects.track_defects)
    for (const contact::RailDefect& d : s.track.defects) joint = joint || d.shape == contact::DefectShape::kDippedJoint;
  if (s.effects.wheel_defects && s.has_vehicle)
    for (const contact::WheelDefect& d : s.vehicle.wheel_defects)
      flat = flat || d.shape == contact::WheelDefectShape::kFlat;
  if (!joint && !flat) return w;
  const std::string what = joint && flat ? "a dipped joint's and a wheel flat's"
                           : joint       ? "a dipped joint's"
                                         : "a wheel flat's";
  if (s.needsTrackNode() && s.solver.track_step > kImpactTrackStep * (1.0 + 1e-9)) {
    w.push_back("solver.track_step " + formatNumber(s.solver.track_step) + " s is coarser than the " +
                formatNumber(kImpactTrackStep) + " s that " + what +
                " impact peak P1 needs (its P2 converges at coarser steps; docs/defects.md)");
  }
  if (s.output.rate < kImpactOutputRate) {
    w.push_back("output.rate " + formatNumber(s.output.rate) + " Hz under-samples " + what +
                " impact (about 1 ms): " + formatNumber(kImpactOutputRate) + " Hz or more resolves its P1 in the bag");
  }
  return w;
}

std::vector<std::string> recordableTopics(const Scene& scene) {
  std::vector<std::string> topics;
  for (const std::string& t : kKnownTopics)
    if (topicNeeds(scene, t).empty()) topics.push_back(t);
  return topics;
}

// Built-in profiles (everything else names a profile file).
static const std::vector<std::string> kBuiltinRailProfiles = {"uic60"};
static const std::vector<std::string> kBuiltinWheelProfiles = {"s1002"};
// Published track-irregularity spectra a realisation can be drawn from (see rail_contact's geometry
// notes for their sources).
static const std::vector<std::string> kKnownPsds = {"fra_class_1", "fra_class_2", "fra_class_3", "fra_class_4",
                                                    "fra_class_5", "fra_class_6", "german_low",  "german_high"};

namespace {

bool contains(const std::vector<std::string>& v, const std::string& s) {
  for (const auto& x : v)
    if (x == s) return true;
  return false;
}

std::string got(double v) { return ", got " + formatNumber(v); }

// A limit derived from other values, to 4 significant digits (a message's figure, not the rule's).
std::string derived(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.4g", v);
  return formatNumber(std::strtod(text, nullptr));
}

// Value checks: each names the rule and the offending value.
void positive(MapReader& r, const char* key, double v) {
  if (!(v > 0.0)) r.fail(key, "must be positive" + got(v));
}
void nonNegative(MapReader& r, const char* key, double v) {
  if (!(v >= 0.0)) r.fail(key, "must not be negative" + got(v));
}
std::string rangeRule(double v, double lo, double hi, const char* unit) {
  if (v >= lo && v <= hi) return "";
  return "must be between " + formatNumber(lo) + " and " + formatNumber(hi) + " " + unit + got(v);
}
void inRange(MapReader& r, const char* key, double v, double lo, double hi, const char* unit) {
  if (const std::string why = rangeRule(v, lo, hi, unit); !why.empty()) r.fail(key, why);
}
void obeys(MapReader& r, const char* key, const std::string& why) {
  if (!why.empty()) r.fail(key, why);
}

// Longer than any line (1000 km): a typing error, and the sleeper and node counts of the track would
// overflow.
constexpr double kMaxTrackLength = 1e6;  // [m]

// A curve radius tighter than any track a rail vehicle runs on (tram depots reach ~15 m; EN 13803 main
// lines 150 m and up) is a typing error, not a scenario: refused before it becomes a curvature of 1e300.
constexpr double kMinCurveRadius = 10.0;  // [m]
void minRadius(MapReader& r, const char* key, double v) {
  if (v < kMinCurveRadius) {
    r.fail(key, "must be at least " + formatNumber(kMinCurveRadius) + " m (0 = straight where allowed)" + got(v));
  }
}

std::string dirOf(const std::string& path) {
  const auto pos = path.find_last_of('/');
  if (pos == std::string::npos) return ".";
  return pos == 0 ? "/" : path.substr(0, pos);
}

std::string stemOf(const std::string& path) {
  std::string base = path.substr(path.find_last_of('/') == std::string::npos ? 0 : path.find_last_of('/') + 1);
  const auto dot = base.find_last_of('.');
  return dot == std::string::npos ? base : base.substr(0, dot);
}

struct Context {
  std::string file;
  std::string base_dir;
};

// A data file named by the scene must exist and be readable.
DataFile resolveFile(MapReader& r, const char* key, const std::string& as_written, const Context& ctx) {
  DataFile f;
  f.as_written = as_written;
  f.path = (!as_written.empty() && as_written[0] == '/') ? as_written : ctx.base_dir + "/" + as_written;
  std::ifstream in(f.path, std::ios::binary);
  if (!in) {
    r.fail(key, "cannot read '" + as_written + "' (resolved to " + f.path + "): " + std::strerror(errno));
  }
  return f;
}

DataFile readFileKey(MapReader& r, const char* key, bool required, const Context& ctx) {
  if (required) r.require(key);
  std::string s;
  r.string(key, s);
  if (s.empty()) return {};
  return resolveFile(r, key, s, ctx);
}

// Each item of the list `key` in r (a sequence of maps), handed to `read` with its own reader named
// path[i]; absent: nothing; not a list: refused naming the key.
template <class Read>
void readList(MapReader& r, const char* key, const std::string& path, const char* what, const Context& ctx, Read read) {
  const YAML::Node seq = r.child(key);
  if (!seq) return;
  if (!seq.IsSequence()) r.fail(key, std::string("must be a list of ") + what);
  for (std::size_t i = 0; i < seq.size(); ++i) {
    MapReader item(seq[i], path + "[" + std::to_string(i) + "]", ctx.file, raiseSceneError);
    read(item);
  }
}

// track.defects: each defect lies wholly on the track; its shape's own figure is in range.
void readDefects(MapReader& r, Track& t, const Context& ctx) {
  readList(r, "defects", "track.defects", "defects", ctx, [&](MapReader& dr) {
    contact::RailDefect d;
    dr.require("type");
    dr.choice("type", d.shape, kDefectShapeWords);
    dr.require("s");
    dr.number("s", d.s_centre);
    dr.require("length");
    dr.number("length", d.length);
    inRange(dr, "length", d.length, 1e-3, 20.0, "m");
    if (!(d.s_centre - 0.5 * d.length >= t.start_arc_length && d.s_centre + 0.5 * d.length <= t.endArcLength())) {
      dr.fail("s", "the defect (" + formatNumber(d.length) + " m long) must lie on the track (" +
                       formatNumber(t.start_arc_length) + " .. " + formatNumber(t.endArcLength()) + " m)" +
                       got(d.s_centre));
    }
    LoadRail rails = LoadRail::kBoth;
    dr.choice("rail", rails, kLoadRailWords);
    d.left = rails != LoadRail::kRight;
    d.right = rails != LoadRail::kLeft;
    if (d.shape == contact::DefectShape::kDippedJoint) {
      dr.require("dip_angle");
      dr.number("dip_angle", d.dip_angle);
      inRange(dr, "dip_angle", d.dip_angle, 1e-4, 0.1, "rad (the total angle between the two ramps)");
      dr.number("gap", d.gap);
      if (!(d.gap >= 0.0 && d.gap <= std::min(0.05, d.length)))
        dr.fail("gap", "must be >= 0 and at most 0.05 m and the joint's length (" + formatNumber(d.length) + " m)" +
                           got(d.gap));
    } else {
      dr.require("height");
      dr.number("height", d.height);
      if (!(d.height != 0.0 && std::abs(d.height) <= 0.005))
        dr.fail("height", "must be non-zero and at most 0.005 m in size (> 0 a bump, < 0 a dip)" + got(d.height));
    }
    dr.finish();
    t.defects.push_back(d);
  });
}

// track.support: zones on the track, their ramps inside them, factors in a physical range.
void readSupport(MapReader& r, Track& t, const Context& ctx) {
  readList(r, "support", "track.support", "support zones", ctx, [&](MapReader& zr) {
    SupportZone z;
    zr.require("s_from");
    zr.number("s_from", z.s_from);
    zr.require("s_to");
    zr.number("s_to", z.s_to);
    if (!(z.s_from >= t.start_arc_length && z.s_from < z.s_to && z.s_to <= t.endArcLength())) {
      zr.fail("s_to", "the zone " + formatNumber(z.s_from) + " .. " + formatNumber(z.s_to) +
                          " m must lie on the track (" + formatNumber(t.start_arc_length) + " .. " +
                          formatNumber(t.endArcLength()) + " m) and end after it starts");
    }
    zr.number("ramp", z.ramp);
    if (!(z.ramp >= 0.0 && 2.0 * z.ramp <= z.s_to - z.s_from)) {
      zr.fail("ramp", "must be between 0 and half the zone's length (" + formatNumber(0.5 * (z.s_to - z.s_from)) +
                          " m)" + got(z.ramp));
    }
    for (auto [key, value] : {std::pair<const char*, double*>{"pad_stiffness", &z.pad_stiffness},
                              {"pad_damping", &z.pad_damping},
                              {"ballast_stiffness", &z.ballast_stiffness},
                              {"ballast_damping", &z.ballast_damping}}) {
      zr.number(key, *value);
      inRange(zr, key, *value, 0.01, 100.0, "(a factor on the track data's value)");
    }
    if (zr.has("sleeper_gap")) {
      z.hanging = true;
      zr.number("sleeper_gap", z.sleeper_gap);
      inRange(zr, "sleeper_gap", z.sleeper_gap, 0.0, 0.02, "m (the void under each sleeper of the zone)");
      // Sleepers lie at start_arc_length + k sleeper_spacing: the zone must hold one.
      const double a = t.sleeper_spacing;
      const double k_first = std::ceil((z.s_from - t.start_arc_length) / a - 1e-9);
      if (!(t.start_arc_length + k_first * a <= z.s_to + 1e-9))
        zr.fail("sleeper_gap", "the zone " + formatNumber(z.s_from) + " .. " + formatNumber(z.s_to) +
                                   " m holds no sleeper (every " + formatNumber(a) +
                                   " m from s = " + formatNumber(t.start_arc_length) + " m)");
    }
    zr.finish();
    t.support.push_back(z);
  });
}

void readDirection(MapReader& r, Segment& seg, bool required) {
  if (required) r.require("direction");
  r.choice("direction", seg.direction, kDirectionWords, 1);
}

Segment readSegment(const YAML::Node& node, const std::string& path, const Context& ctx) {
  MapReader r(node, path, ctx.file, raiseSceneError);
  Segment seg;
  r.require("type");
  r.choice("type", seg.type, kSegmentTypeWords);
  r.require("length");
  r.number("length", seg.length);
  positive(r, "length", seg.length);
  if (seg.length > kMaxTrackLength) {
    r.fail("length", "must be at most " + formatNumber(kMaxTrackLength) + " m (the longest track a run builds)" +
                         got(seg.length));
  }
  r.number("gradient", seg.gradient);
  inRange(r, "gradient", seg.gradient, -0.1, 0.1, "(rise over run)");
  r.boolean("jump_allowed", seg.jump_allowed);
  switch (seg.type) {
    case SegmentType::kStraight:
      r.number("cant", seg.cant);
      inRange(r, "cant", seg.cant, 0.0, 0.25, "m");
      readDirection(r, seg, seg.cant != 0.0);
      break;
    case SegmentType::kCircular:
      readDirection(r, seg, true);
      r.require("radius");
      r.number("radius", seg.radius);
      positive(r, "radius", seg.radius);
      minRadius(r, "radius", seg.radius);
      r.number("cant", seg.cant);
      inRange(r, "cant", seg.cant, 0.0, 0.25, "m");
      break;
    case SegmentType::kTransition:
      r.number("radius_start", seg.radius_start);
      nonNegative(r, "radius_start", seg.radius_start);
      if (seg.radius_start > 0.0) minRadius(r, "radius_start", seg.radius_start);
      r.number("radius_end", seg.radius_end);
      nonNegative(r, "radius_end", seg.radius_end);
      if (seg.radius_end > 0.0) minRadius(r, "radius_end", seg.radius_end);
      r.number("cant_start", seg.cant_start);
      inRange(r, "cant_start", seg.cant_start, 0.0, 0.25, "m");
      r.number("cant_end", seg.cant_end);
      inRange(r, "cant_end", seg.cant_end, 0.0, 0.25, "m");
      readDirection(r, seg, seg.radius_start > 0 || seg.radius_end > 0 || seg.cant_start > 0 || seg.cant_end > 0);
      if (seg.radius_start == 0.0 && seg.radius_end == 0.0 && seg.cant_start == seg.cant_end) {
        r.failHere("a transition must change the curvature or the cant (both ends straight and equal cant)");
      }
      break;
  }
  r.finish();
  return seg;
}

void checkChain(const Track& t, const YAML::Node& seq, const std::string& file) {
  for (std::size_t i = 1; i < t.segments.size(); ++i) {
    const Segment& a = t.segments[i - 1];
    const Segment& b = t.segments[i];
    if (b.jump_allowed) continue;
    const std::string path = "track.segments[" + std::to_string(i) + "]";
    const std::string prev = "track.segments[" + std::to_string(i - 1) + "]";
    const int line = seq[i].Mark().line >= 0 ? seq[i].Mark().line + 1 : 0;
    const double k0 = a.curvatureAtEnd(), k1 = b.curvatureAtStart();
    if (std::abs(k0 - k1) > 1e-9) {
      failScene(file, path,
                "curvature jumps at its start from " + formatNumber(k0) + " to " + formatNumber(k1) + " 1/m (" + prev +
                    " ends there); make the chain continuous (a transition) or mark the "
                    "jump with jump_allowed: true",
                line);
    }
    const double c0 = a.signedCantAtEnd(), c1 = b.signedCantAtStart();
    if (std::abs(c0 - c1) > 1e-6) {
      failScene(file, path,
                "cant jumps at its start from " + formatNumber(std::abs(c0)) + " to " + formatNumber(std::abs(c1)) +
                    " m (" + prev +
                    " ends there); make the chain continuous (a cant ramp) or mark the jump with "
                    "jump_allowed: true",
                line);
    }
  }
}

double parseInclination(MapReader& r, const char* key, double fallback) {
  if (!r.has(key)) {
    r.child(key);  // mark as read
    return fallback;
  }
  std::string text;
  r.string(key, text);
  const auto slash = text.find('/');
  if (slash != std::string::npos) {
    double num = 0, den = 0;
    std::istringstream a(text.substr(0, slash)), b(text.substr(slash + 1));
    if (!(a >> num) || !(b >> den) || !a.eof() || !b.eof() || den == 0.0) {
      r.fail(key, "must be a ratio such as 1/20 or a number, got '" + text + "'");
    }
    return num / den;
  }
  double v = 0.0;
  r.number(key, v);
  return v;
}

void readTrack(MapReader& root, Scene& s, const Context& ctx) {
  MapReader r(root.requireChild("track"), "track", ctx.file, raiseSceneError);
  Track& t = s.track;
  r.number("gauge", t.gauge);
  inRange(r, "gauge", t.gauge, 0.6, 2.0, "m");
  r.number("gauge_measuring_depth", t.gauge_measuring_depth);
  inRange(r, "gauge_measuring_depth", t.gauge_measuring_depth, 0.0, 0.03, "m");
  r.number("cant_reference_width", t.cant_reference_width);
  if (t.cant_reference_width == 0.0) t.cant_reference_width = t.gauge + 0.065;
  if (!(t.cant_reference_width >= t.gauge && t.cant_reference_width <= t.gauge + 0.2)) {
    // Named against the gauge, and the gauge's origin when the scene left it to its default.
    r.fail("cant_reference_width",
           "must be between track.gauge (" + formatNumber(t.gauge) + " m) and track.gauge + 0.2 m" +
               got(t.cant_reference_width) +
               (r.has("gauge") ? std::string()
                               : "; track.gauge is not set, so its default " + formatNumber(t.gauge) + " m applies"));
  }
  r.string("rail_profile", t.rail_profile);
  if (!contains(kBuiltinRailProfiles, t.rail_profile)) {
    t.rail_profile_file = resolveFile(r, "rail_profile", t.rail_profile, ctx);
  }
  t.rail_inclination = parseInclination(r, "rail_inclination", t.rail_inclination);
  inRange(r, "rail_inclination", t.rail_inclination, 0.0, 0.1, "(tan of the tilt, e.g. 1/20)");
  r.number("sleeper_spacing", t.sleeper_spacing);
  inRange(r, "sleeper_spacing", t.sleeper_spacing, 0.3, 1.5, "m");
  r.integer("rail_elements_between_sleepers", t.rail_elements_between_sleepers);
  if (t.rail_elements_between_sleepers < 1 || t.rail_elements_between_sleepers > 50) {
    r.fail("rail_elements_between_sleepers",
           "must be between 1 and 50, got " + std::to_string(t.rail_elements_between_sleepers));
  }
  r.number("start_arc_length", t.start_arc_length);
  t.data = readFileKey(r, "data", s.needsTrackNode() || s.moving_loads.present, ctx);

  const YAML::Node seq = r.requireChild("segments");
  if (!seq.IsSequence() || seq.size() == 0) r.fail("segments", "must be a non-empty list of segments");
  for (std::size_t i = 0; i < seq.size(); ++i) {
    t.segments.push_back(readSegment(seq[i], "track.segments[" + std::to_string(i) + "]", ctx));
  }
  checkChain(t, seq, ctx.file);
  if (t.length() > kMaxTrackLength) {
    r.fail("segments", "the track must be at most " + formatNumber(kMaxTrackLength) + " m long, got " +
                           formatNumber(t.length()) + " m");
  }
  if (t.length() < 2.0 * t.sleeper_spacing) {
    r.fail("segments", "the track must be at least two sleeper spacings long, got " + formatNumber(t.length()) + " m");
  }

  Irregularities& irr = t.irregularities;
  if (const YAML::Node n = r.child("irregularities")) {
    MapReader ir(n, "track.irregularities", ctx.file, raiseSceneError);
    ir.choice("source", irr.source, kIrregularitySourceWords);
    if (irr.source == IrregularitySource::kFile) {
      irr.file = readFileKey(ir, "file", true, ctx);
    } else if (irr.source == IrregularitySource::kPsd) {
      ir.require("psd");
      ir.string("psd", irr.psd);
      if (!contains(kKnownPsds, irr.psd)) {
        ir.fail("psd", "must be one of " + join(kKnownPsds) + ", got '" + irr.psd + "'");
      }
      ir.unsigned64("seed", irr.seed);
      ir.number("wavelength_min", irr.wavelength_min);
      positive(ir, "wavelength_min", irr.wavelength_min);
      ir.number("wavelength_max", irr.wavelength_max);
      if (!(irr.wavelength_max > irr.wavelength_min)) {
        ir.fail("wavelength_max", "must be greater than wavelength_min (" + formatNumber(irr.wavelength_min) + ")" +
                                      got(irr.wavelength_max));
      }
    }
    ir.finish();
  }
  readDefects(r, t, ctx);
  readSupport(r, t, ctx);
  r.finish();
}

// vehicle.wheel_defects: on an existing wheelset; a flat no longer than a quarter of the circumference and,
// rounded, no deeper than the wheel can follow; an out-of-roundness of a sensible order and amplitude.
void readWheelDefects(MapReader& r, Vehicle& v, const Context& ctx) {
  constexpr double kPi = 3.14159265358979323846;
  readList(r, "wheel_defects", "vehicle.wheel_defects", "wheel defects", ctx, [&](MapReader& dr) {
    contact::WheelDefect d;
    dr.require("type");
    dr.choice("type", d.shape, kWheelDefectShapeWords);
    dr.require("wheelset");
    int wheelset = 0;
    dr.integer("wheelset", wheelset);
    if (wheelset < 0 || wheelset >= v.wheelsets) {
      dr.fail("wheelset", "must be a wheelset of the vehicle, 0 .. " + std::to_string(v.wheelsets - 1) + ", got " +
                              std::to_string(wheelset));
    }
    LoadRail sides = LoadRail::kBoth;
    dr.choice("side", sides, kLoadRailWords);
    dr.number("angle", d.angle);
    inRange(dr, "angle", d.angle, -kPi, kPi, "rad (from straight down toward forward at the start)");
    if (d.shape == contact::WheelDefectShape::kFlat) {
      dr.require("length");
      dr.number("length", d.length);
      const double quarter = 0.5 * kPi * v.nominal_radius;
      if (!(d.length >= 1e-3 && d.length <= quarter)) {
        dr.fail("length", "must be between 0.001 m and a quarter of the wheel's circumference (" + derived(quarter) +
                              " m)" + got(d.length));
      }
      dr.choice("shape", d.rounded, kFlatShapeWords);
      if (d.rounded) {
        dr.require("depth");
        dr.number("depth", d.depth);
        const double deepest = contact::WheelDefects::roundedFlatMaxDepth(d.length, v.nominal_radius);
        if (!(d.depth > 0.0 && d.depth <= deepest)) {
          dr.fail("depth", "must be positive and at most length^2 / (2 pi^2 r0) = " + derived(deepest) +
                               " m (deeper, the wheel could not follow the dip's curvature)" + got(d.depth));
        }
      } else if (dr.has("depth")) {
        dr.fail("depth", "applies to a rounded flat only (a new flat " + formatNumber(d.length) + " m long is " +
                             derived(contact::WheelDefects::newFlatDepth(d.length, v.nominal_radius)) + " m deep)");
      }
    } else {
      dr.require("order");
      dr.integer("order", d.order);
      if (d.order < 1 || d.order > 40) {
        dr.fail("order", "must be between 1 and 40 (harmonics round the wheel), got " + std::to_string(d.order));
      }
      dr.require("amplitude");
      dr.number("amplitude", d.amplitude);
      if (!(d.amplitude > 0.0 && d.amplitude <= 1e-3)) {
        dr.fail("amplitude", "must be positive and at most 0.001 m" + got(d.amplitude));
      }
    }
    dr.finish();
    for (int side = 0; side < 2; ++side) {
      if ((side == 0 && sides == LoadRail::kRight) || (side == 1 && sides == LoadRail::kLeft)) continue;
      d.wheel = static_cast<std::uint32_t>(2 * wheelset + side);
      v.wheel_defects.push_back(d);
    }
  });
}

void readVehicle(MapReader& root, Scene& s, const Context& ctx) {
  MapReader r(root.child("vehicle"), "vehicle", ctx.file, raiseSceneError);
  Vehicle& v = s.vehicle;
  v.data = readFileKey(r, "data", true, ctx);
  r.require("start_arc_length");
  r.number("start_arc_length", v.start_arc_length);
  if (v.start_arc_length < s.track.start_arc_length || v.start_arc_length >= s.track.endArcLength()) {
    r.fail("start_arc_length", "must lie on the track [" + formatNumber(s.track.start_arc_length) + ", " +
                                   formatNumber(s.track.endArcLength()) + ") m" + got(v.start_arc_length));
  }
  r.require("speed");
  r.number("speed", v.speed);
  inRange(r, "speed", v.speed, 0.0, 150.0, "m/s");
  r.string("wheel_profile", v.wheel_profile);
  if (!contains(kBuiltinWheelProfiles, v.wheel_profile)) {
    v.wheel_profile_file = resolveFile(r, "wheel_profile", v.wheel_profile, ctx);
  }
  r.number("nominal_radius", v.nominal_radius);
  inRange(r, "nominal_radius", v.nominal_radius, 0.2, 0.7, "m");
  r.number("back_to_back", v.back_to_back);
  if (!(v.back_to_back > s.track.gauge - 0.2 && v.back_to_back < s.track.gauge)) {
    r.fail("back_to_back", "must be between track.gauge - 0.2 and track.gauge (" + formatNumber(s.track.gauge) + ") m" +
                               got(v.back_to_back));
  }
  r.integer("wheelsets", v.wheelsets);
  if (v.wheelsets < 1 || v.wheelsets > 16) {
    r.fail("wheelsets", "must be between 1 and 16, got " + std::to_string(v.wheelsets));
  }
  readWheelDefects(r, v, ctx);
  r.finish();
}

// The reader of the scene's top-level section `key`, none when the file leaves it out.
std::optional<MapReader> sectionOf(MapReader& root, const char* key) {
  const YAML::Node n = root.child(key);
  if (!n) return std::nullopt;
  return MapReader(n, key, root.file(), raiseSceneError);
}

void readContact(MapReader& root, Scene& s) {
  std::optional<MapReader> section = sectionOf(root, "contact");
  if (!section) return;
  MapReader& r = *section;
  Contact& c = s.contact;
  // Bounds: a friction coefficient above 1 is not a wheel on a rail (sanded dry rail reaches ~0.5); e is a
  // ratio of velocities; the floor keeps eq. 9's damping finite and below a penetration rate of 10 m/s.
  r.number("friction", c.friction);
  if (!(c.friction > 0.0 && c.friction <= 1.0)) r.fail("friction", "must be positive and at most 1" + got(c.friction));
  r.number("restitution", c.restitution);
  inRange(r, "restitution", c.restitution, 0.0, 1.0, "(-)");
  r.number("impact_velocity_floor", c.impact_velocity_floor);
  inRange(r, "impact_velocity_floor", c.impact_velocity_floor, 1e-6, 10.0, "m/s");
  r.finish();
}

void readMovingLoads(MapReader& root, Scene& s, const Context& ctx) {
  MapReader r(root.child("moving_loads"), "moving_loads", ctx.file, raiseSceneError);
  MovingLoads& m = s.moving_loads;
  r.number("start_arc_length", m.start_arc_length);
  if (m.start_arc_length < s.track.start_arc_length || m.start_arc_length > s.track.endArcLength()) {
    r.fail("start_arc_length", "must lie on the track" + got(m.start_arc_length));
  }
  r.number("speed", m.speed);
  inRange(r, "speed", m.speed, 0.0, 150.0, "m/s");
  const YAML::Node seq = r.requireChild("loads");
  if (!seq.IsSequence() || seq.size() == 0) r.fail("loads", "must be a non-empty list of loads");
  for (std::size_t i = 0; i < seq.size(); ++i) {
    MapReader lr(seq[i], "moving_loads.loads[" + std::to_string(i) + "]", ctx.file, raiseSceneError);
    MovingLoad l;
    lr.number("offset", l.offset);
    nonNegative(lr, "offset", l.offset);
    lr.choice("rail", l.rail, kLoadRailWords);
    lr.number("vertical", l.vertical);
    inRange(lr, "vertical", l.vertical, -1e6, 1e6, "N");
    lr.number("lateral", l.lateral);
    inRange(lr, "lateral", l.lateral, -1e6, 1e6, "N");
    lr.finish();
    m.loads.push_back(l);
  }
  r.finish();
}

void readEffects(MapReader& root, Scene& s) {
  std::optional<MapReader> section = sectionOf(root, "effects");
  if (!section) return;
  MapReader& r = *section;
  Effects& e = s.effects;
  r.choice("track_model", e.track_model, kTrackModelWords);
  r.choice("creep_law", e.creep_law, kCreepLawWords);
  for (const EffectSwitch& sw : kEffectSwitches) r.boolean(sw.key, e.*sw.on);
  r.finish();
}

void readSolver(MapReader& root, Scene& s) {
  std::optional<MapReader> section = sectionOf(root, "solver");
  if (!section) return;
  MapReader& r = *section;
  Solver& v = s.solver;
  r.number("track_step", v.track_step);
  obeys(r, "track_step", trackStepRule(v.track_step));
  r.number("vehicle_rtol", v.vehicle_rtol);
  inRange(r, "vehicle_rtol", v.vehicle_rtol, 1e-12, 1e-1, "");
  r.number("vehicle_atol", v.vehicle_atol);
  inRange(r, "vehicle_atol", v.vehicle_atol, 1e-15, 1e-1, "");
  r.number("vehicle_max_step", v.vehicle_max_step);
  inRange(r, "vehicle_max_step", v.vehicle_max_step, 1e-8, 1e-1, "s");
  r.number("standalone_max_step", v.standalone_max_step);
  if (v.standalone_max_step != 0.0)
    inRange(r, "standalone_max_step", v.standalone_max_step, 1e-8, 1e-1, "s (or 0: none)");
  r.choice("vehicle_method", v.vehicle_method, kVehicleMethodWords);
  r.choice("transport", v.transport, kTransportWords);
  r.number("exchange_timeout", v.exchange_timeout);
  inRange(r, "exchange_timeout", v.exchange_timeout, 0.01, 3600.0, "s");
  r.number("handshake_timeout", v.handshake_timeout);
  inRange(r, "handshake_timeout", v.handshake_timeout, 0.01, 3600.0, "s");
  if (const YAML::Node wn = r.child("track_window")) {
    MapReader wr(wn, "solver.track_window", root.file(), raiseSceneError);
    TrackWindow& w = v.track_window;
    wr.boolean("enabled", w.enabled);
    wr.number("behind", w.behind);
    inRange(wr, "behind", w.behind, 0.0, 1e4, "m");
    wr.number("ahead", w.ahead);
    inRange(wr, "ahead", w.ahead, 0.0, 1e4, "m");
    wr.number("shift", w.shift);
    obeys(wr, "shift", windowShiftRule(w.shift));
    wr.number("length", w.length);
    inRange(wr, "length", w.length, 0.0, 1e6, "m");
    wr.finish();
  }
  if (const YAML::Node en = r.child("end")) {
    MapReader er(en, "solver.end", root.file(), raiseSceneError);
    const bool has_time = er.has("time"), has_s = er.has("arc_length");
    if (has_time == has_s) er.failHere("give exactly one of time [s] or arc_length [m]");
    if (has_time) {
      v.end.kind = EndKind::kTime;
      er.number("time", v.end.value);
      positive(er, "time", v.end.value);
    } else {
      v.end.kind = EndKind::kArcLength;
      er.number("arc_length", v.end.value);
    }
    er.finish();
  }
  r.finish();
}

void readOutput(MapReader& root, Scene& s) {
  std::optional<MapReader> section = sectionOf(root, "output");
  if (!section) return;
  MapReader& r = *section;
  Output& o = s.output;
  r.string("bag", o.bag);
  r.number("rate", o.rate);
  inRange(r, "rate", o.rate, 0.1, 1e5, "Hz");
  r.stringList("topics", o.topics);
  for (std::size_t i = 0; i < o.topics.size(); ++i) {
    const std::string key = "topics[" + std::to_string(i) + "]";
    const std::string& name = o.topics[i];
    if (!contains(kKnownTopics, name)) {
      r.fail(key.c_str(), "unknown topic '" + name + "' (known: " + join(kKnownTopics) + ")");
    }
    for (std::size_t j = 0; j < i; ++j)
      if (o.topics[j] == name) r.fail(key.c_str(), "'" + name + "' is listed twice");
  }
  r.numberList("deflection_sections", o.deflection_sections);
  for (std::size_t i = 0; i < o.deflection_sections.size(); ++i) {
    const double sec = o.deflection_sections[i];
    if (sec < s.track.start_arc_length || sec > s.track.endArcLength()) {
      const std::string key = "deflection_sections[" + std::to_string(i) + "]";
      r.fail(key.c_str(), "must lie on the track [" + formatNumber(s.track.start_arc_length) + ", " +
                              formatNumber(s.track.endArcLength()) + "] m" + got(sec));
    }
  }
  r.number("pad_force_margin", o.pad_force_margin);
  inRange(r, "pad_force_margin", o.pad_force_margin, 0.0, 100.0, "m");
  r.finish();
}

// Rules that involve more than one section.
void checkConsistency(MapReader& root, Scene& s, const YAML::Node& doc) {
  const std::string& file = root.file();
  auto line_of = [&](const char* a, const char* b) {
    const YAML::Node n = doc[a][b];
    return n.IsDefined() && n.Mark().line >= 0 ? n.Mark().line + 1 : 0;
  };
  if (s.moving_loads.present && s.effects.track_model != TrackModel::kFlexible) {
    failScene(
        file, "effects.track_model",
        std::string("moving_loads need the finite-element track (flexible), got ") + toString(s.effects.track_model),
        line_of("effects", "track_model"));
  }
  if (s.effects.irregularities && s.track.irregularities.source == IrregularitySource::kNone) {
    failScene(file, "effects.irregularities", "is on but track.irregularities gives no source (file or psd)",
              line_of("effects", "irregularities"));
  }
  if (s.effects.track_defects && s.track.defects.empty()) {
    failScene(file, "effects.track_defects", "is on but track.defects lists none", line_of("effects", "track_defects"));
  }
  for (std::size_t i = 0; i < s.track.defects.size() && !s.has_vehicle; ++i)
    if (s.track.defects[i].gap > 0.0)
      failScene(file, "track.defects[" + std::to_string(i) + "].gap",
                "needs a vehicle in the scene (the gap is what its wheels bridge)", line_of("track", "defects"));
  if (s.effects.support_variation && s.track.support.empty()) {
    failScene(file, "effects.support_variation", "is on but track.support lists no zone",
              line_of("effects", "support_variation"));
  }
  if (s.effects.support_variation && !s.runsFeIntegration()) {
    failScene(file, "effects.support_variation",
              std::string("needs the integrated FE track (effects.track_model: flexible), got ") +
                  toString(s.effects.track_model),
              line_of("effects", "support_variation"));
  }
  if (s.effects.wheel_defects && s.vehicle.wheel_defects.empty()) {
    failScene(file, "effects.wheel_defects",
              s.has_vehicle ? "is on but vehicle.wheel_defects lists none" : "needs a vehicle in the scene",
              line_of("effects", "wheel_defects"));
  }
  if (s.cosimulation()) {
    if (const std::string why = vehicleMaxStepRule(s.solver.vehicle_max_step, s.solver.track_step); !why.empty())
      failScene(file, "solver.vehicle_max_step", why, line_of("solver", "vehicle_max_step"));
  }
  // End condition: default is the track's end, reached by the leading wheelset (or first load).
  Solver& sol = s.solver;
  if (sol.end.kind == EndKind::kArcLength) {
    const double start = s.has_vehicle ? s.vehicle.start_arc_length : s.moving_loads.start_arc_length;
    const double speed = s.has_vehicle ? s.vehicle.speed : s.moving_loads.speed;
    if (sol.end.value == 0.0) sol.end.value = s.track.endArcLength();
    if (sol.end.value <= start || sol.end.value > s.track.endArcLength()) {
      failScene(file, "solver.end.arc_length",
                "must lie after the start (" + formatNumber(start) + " m) and on the track (end " +
                    formatNumber(s.track.endArcLength()) + " m)" + got(sol.end.value),
                0);
    }
    if (speed <= 0.0) {
      failScene(file, s.has_vehicle ? "vehicle.speed" : "moving_loads.speed",
                "must be positive when solver.end is an arc length (the run would never end), got 0", 0);
    }
  }
  const Output& o = s.output;
  for (std::size_t i = 0; i < o.topics.size(); ++i) {
    const std::string why = topicNeeds(s, o.topics[i]);
    if (!why.empty()) failScene(file, "output.topics[" + std::to_string(i) + "]", why, 0);
  }
}

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

std::uint64_t fnv1a64(const std::string& bytes, std::uint64_t seed) {
  std::uint64_t h = seed;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  return h;
}

std::string trackStepRule(double track_step) { return rangeRule(track_step, 1e-7, 1e-2, "s"); }

// The vehicle's CVODE steps end on every exchange: a larger maximum step would be cut there anyway. The
// relative slack absorbs the round-off of a value written as the track step's multiple.
std::string vehicleMaxStepRule(double vehicle_max_step, double track_step) {
  if (vehicle_max_step > 0.0 && vehicle_max_step <= track_step * (1.0 + 1e-12)) return "";
  return "must be at most solver.track_step (" + formatNumber(track_step) + " s) in co-simulation" +
         got(vehicle_max_step);
}

std::string windowShiftRule(double shift) { return rangeRule(shift, 1e-3, 1e4, "m"); }

SceneOverrides splitOverrides(const std::string& text) {
  // Whitespace separates overrides except inside quotes and YAML flow collections, so that
  // "solver.end={time: 1.5} output.bag='a b.bag'" gives two.
  SceneOverrides out;
  std::string item;
  int depth = 0;
  char quote = 0;
  for (const char c : text) {
    if (quote != 0) {
      if (c == quote) quote = 0;
    } else if (c == '\'' || c == '"') {
      quote = c;
    } else if (c == '{' || c == '[') {
      ++depth;
    } else if ((c == '}' || c == ']') && depth > 0) {
      --depth;
    } else if (depth == 0 && std::isspace(static_cast<unsigned char>(c))) {
      if (!item.empty()) out.push_back(item);
      item.clear();
      continue;
    }
    item += c;
  }
  if (!item.empty()) out.push_back(item);
  return out;
}

namespace {

// Sets node[parts[i]][parts[i+1]]... = value, creating missing maps. yaml-cpp nodes are handles: each
// level gets a fresh handle (a parameter), never a reassigned one.
void setAt(YAML::Node node, const std::vector<std::string>& parts, std::size_t i, const YAML::Node& value,
           const std::string& file, const std::string& item) {
  if (i + 1 == parts.size()) {
    node[parts[i]] = value;
    return;
  }
  const YAML::Node child = node[parts[i]];
  if (!child.IsDefined() || child.IsNull()) {
    node[parts[i]] = YAML::Node(YAML::NodeType::Map);
  } else if (!child.IsMap()) {
    failScene(file, item.substr(0, item.find('=')), "override '" + item + "': " + parts[i] + " is not a map of keys",
              0);
  }
  setAt(node[parts[i]], parts, i + 1, value, file, item);
}

// "{a:1, b:{c:2}}" -> "{a: 1, b: {c: 2}}": a space after each ':' outside quotes that has none.
std::string spacedColons(const std::string& text) {
  std::string out;
  char quote = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    out += c;
    if (quote != 0) {
      if (c == quote) quote = 0;
    } else if (c == '\'' || c == '"') {
      quote = c;
    } else if (c == ':' && i + 1 < text.size() && !std::isspace(static_cast<unsigned char>(text[i + 1]))) {
      out += ' ';
    }
  }
  return out;
}

// Applies "a.b.c=value" to doc (a map). Throws SceneError naming the override.
void applyOverride(YAML::Node& doc, const std::string& file, const std::string& item) {
  const std::size_t eq = item.find('=');
  const std::string key = eq == std::string::npos ? std::string() : item.substr(0, eq);
  if (eq == std::string::npos || key.empty()) {
    failScene(file, "", "override '" + item + "': expected key=value (e.g. effects.track_model=flexible)", 0);
  }
  // "key=" (nothing after '='): the key keeps the file's value (launch arguments left empty).
  if (eq + 1 == item.size()) return;
  YAML::Node value;
  try {
    value = YAML::Load(item.substr(eq + 1));
    // YAML reads "{time:1.0}" as the key "time:1.0" without a value; an override means {time: 1.0}.
    if (value.IsMap() && std::any_of(value.begin(), value.end(), [](const auto& kv) {
          return kv.first.IsScalar() && kv.first.Scalar().find(':') != std::string::npos && kv.second.IsNull();
        })) {
      value = YAML::Load(spacedColons(item.substr(eq + 1)));
    }
  } catch (const YAML::Exception& e) {
    failScene(file, key, "override '" + item + "': the value is not valid YAML: " + e.msg, 0);
  }
  std::vector<std::string> parts;
  for (std::size_t start = 0;;) {
    const std::size_t dot = key.find('.', start);
    parts.push_back(key.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  for (const std::string& part : parts) {
    if (part.empty()) failScene(file, key, "override '" + item + "': empty key", 0);
  }
  setAt(doc, parts, 0, value, file, item);
}

}  // namespace

Scene loadSceneText(const std::string& text, const std::string& file, const std::string& base_dir,
                    const SceneOverrides& overrides) {
  YAML::Node doc = parseYaml(text, file, raiseSceneError);
  if (!overrides.empty() && !doc.IsMap()) failScene(file, "", "must be a map of keys to values", 1);
  for (const std::string& item : overrides) applyOverride(doc, file, item);
  const Context ctx{file, base_dir.empty() ? "." : base_dir};
  MapReader root(doc, "", file, raiseSceneError);
  Scene s;
  s.file = file;
  s.name = stemOf(file);
  root.string("name", s.name);
  root.string("description", s.description);

  // Effects first: they decide which other parts are required.
  readEffects(root, s);
  s.has_vehicle = root.has("vehicle");
  s.moving_loads.present = root.has("moving_loads");
  if (s.has_vehicle == s.moving_loads.present) {
    failScene(file, "", "a scene has exactly one of vehicle (a run with a train) or moving_loads (the track alone)", 0);
  }
  readTrack(root, s, ctx);
  if (s.has_vehicle) {
    root.child("moving_loads");  // known, absent
    readVehicle(root, s, ctx);
    readContact(root, s);
  } else {
    root.child("vehicle");
    if (root.has("contact")) {
      failScene(file, "contact", "a moving-load scene has no wheel-rail contact; remove the section", 0);
    }
    readMovingLoads(root, s, ctx);
  }
  readSolver(root, s);
  readOutput(root, s);
  root.finish();
  checkConsistency(root, s, doc);

  // The hash covers the resolved scene and the bytes of every data file it names, so two nodes agree
  // only when they would build the same models.
  std::uint64_t h = fnv1a64(toYaml(s));
  for (const DataFile* f : {&s.track.data, &s.track.rail_profile_file, &s.track.irregularities.file, &s.vehicle.data,
                            &s.vehicle.wheel_profile_file}) {
    if (!f->empty()) h = fnv1a64(readAll(f->path), h);
  }
  s.hash = h;
  return s;
}

Scene loadSceneHandedOver(const std::string& text, const std::string& file, const SceneOverrides& overrides) {
  return loadSceneText(text, file, dirOf(file), overrides);
}

Scene loadSceneFile(const std::string& path, const SceneOverrides& overrides) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const std::string why = std::strerror(errno);
    // A relative path is taken from the working directory: say which one.
    std::string where;
    if (!path.empty() && path[0] != '/') {
      char cwd[4096];
      if (::getcwd(cwd, sizeof cwd) != nullptr) where = " (looked for " + std::string(cwd) + "/" + path + ")";
    }
    throw SceneError(path + ": cannot read the scene file" + where + ": " + why);
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  return loadSceneText(ss.str(), path, dirOf(path), overrides);
}

}  // namespace rail::core
