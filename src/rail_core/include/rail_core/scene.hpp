// The scene: one YAML file that describes a simulation completely, resolved into plain structs.
//
// A scene is loaded and validated once (loadSceneFile / loadSceneText), with every default filled
// in, and is constant afterwards. Builders read it and build, or do not build, each component; the
// effects below are the single place where a scene says what is simulated. Defaults are the member
// initialisers of these structs and nowhere else. SI units throughout; radians inside.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <rail_contact/enum_words.hpp>
#include <rail_contact/track_defects.hpp>
#include <rail_contact/wheel_defects.hpp>

#include "rail_core/support_zone.hpp"

namespace rail::core {

using contact::Word;
using contact::wordOf;

// How the track is represented (effects.track_model).
enum class TrackModel {
  kRigid,     // "rigid": vehicle alone on the rigid track geometry (the standard approach)
  kRigidFe,   // "rigid_fe": co-simulation with the FE nodal displacements neglected (no FE integration)
  kFlexible,  // "flexible": co-simulation with the flexible finite-element track
};
enum class CreepLaw { kPolach };
enum class Transport { kService, kTopic, kShm };
enum class SegmentType { kStraight, kTransition, kCircular };
enum class Direction { kNone, kLeft, kRight };
enum class IrregularitySource { kNone, kFile, kPsd };
enum class VehicleMethod { kAuto, kBdf, kAdams };
enum class EndKind { kTime, kArcLength };
enum class LoadRail { kBoth, kLeft, kRight };

// The scene file's words for these values (rail_contact/enum_words.hpp): what the loader accepts and toString writes.
inline constexpr Word<TrackModel> kTrackModelWords[] = {
    {"rigid", TrackModel::kRigid}, {"rigid_fe", TrackModel::kRigidFe}, {"flexible", TrackModel::kFlexible}};
inline constexpr Word<CreepLaw> kCreepLawWords[] = {{"polach", CreepLaw::kPolach}};
inline constexpr Word<Transport> kTransportWords[] = {
    {"service", Transport::kService}, {"topic", Transport::kTopic}, {"shm", Transport::kShm}};
inline constexpr Word<SegmentType> kSegmentTypeWords[] = {{"straight", SegmentType::kStraight},
                                                          {"transition", SegmentType::kTransition},
                                                          {"circular", SegmentType::kCircular}};
// "none" (a straight's) is written, never read: a curve's direction is left or right.
inline constexpr Word<Direction> kDirectionWords[] = {
    {"none", Direction::kNone}, {"left", Direction::kLeft}, {"right", Direction::kRight}};
inline constexpr Word<IrregularitySource> kIrregularitySourceWords[] = {
    {"none", IrregularitySource::kNone}, {"file", IrregularitySource::kFile}, {"psd", IrregularitySource::kPsd}};
inline constexpr Word<VehicleMethod> kVehicleMethodWords[] = {
    {"auto", VehicleMethod::kAuto}, {"bdf", VehicleMethod::kBdf}, {"adams", VehicleMethod::kAdams}};
inline constexpr Word<EndKind> kEndKindWords[] = {{"time", EndKind::kTime}, {"arc_length", EndKind::kArcLength}};
inline constexpr Word<contact::DefectShape> kDefectShapeWords[] = {{"dipped_joint", contact::DefectShape::kDippedJoint},
                                                                   {"weld", contact::DefectShape::kWeld}};
inline constexpr Word<contact::WheelDefectShape> kWheelDefectShapeWords[] = {
    {"flat", contact::WheelDefectShape::kFlat}, {"out_of_round", contact::WheelDefectShape::kOutOfRound}};
// A flat's edges: sharp (as cut by a sliding wheel) or rounded by wear.
inline constexpr Word<bool> kFlatShapeWords[] = {{"new", false}, {"rounded", true}};
inline constexpr Word<LoadRail> kLoadRailWords[] = {
    {"both", LoadRail::kBoth}, {"left", LoadRail::kLeft}, {"right", LoadRail::kRight}};

// A data file named by the scene: the path as the user wrote it and the path it resolves to (relative
// paths are taken from the scene file's directory).
struct DataFile {
  std::string as_written;
  std::string path;
  bool empty() const { return as_written.empty(); }
};

// One piece of the track's centre line.
struct Segment {
  SegmentType type = SegmentType::kStraight;
  double length = 0.0;                     // [m]
  Direction direction = Direction::kNone;  // curving to the left or right; none on a straight
  double radius = 0.0;                     // circular: [m]
  double radius_start = 0.0;               // transition: radius at its start [m], 0 = straight (infinite)
  double radius_end = 0.0;                 // transition: radius at its end [m], 0 = straight (infinite)
  double cant = 0.0;                       // straight, circular: superelevation of the outer rail [m]
  double cant_start = 0.0;                 // transition: cant at its start [m]
  double cant_end = 0.0;                   // transition: cant at its end [m]
  double gradient = 0.0;                   // rise over run [-]
  bool jump_allowed = false;               // the scene accepts a curvature or cant jump at this segment's start

  // Signed values used by the geometry: curvature > 0 curves left; cant > 0 raises the right rail.
  double curvatureAtStart() const;
  double curvatureAtEnd() const;
  double signedCantAtStart() const;
  double signedCantAtEnd() const;
};

struct Irregularities {
  IrregularitySource source = IrregularitySource::kNone;
  DataFile file;                  // source: file; CSV of s, alignment, level, cross level, gauge [m]
  std::string psd;                // source: psd; a published spectrum, e.g. "fra_class_4"
  std::uint64_t seed = 1;         // source: psd; realisation seed
  double wavelength_min = 1.0;    // source: psd; shortest wavelength generated [m]
  double wavelength_max = 120.0;  // source: psd; longest wavelength generated [m]
};

struct Track {
  double gauge = 1.435;                  // between the rails' gauge faces [m]
  double gauge_measuring_depth = 0.014;  // below the running surface, EN 13848-1 [m]
  double cant_reference_width = 0.0;     // base of the cant [m]; 0 in the file = gauge + 0.065
  std::string rail_profile = "uic60";    // a built-in profile name or a profile file (see profiles.md)
  DataFile rail_profile_file;            // set when rail_profile names a file
  double rail_inclination = 0.05;        // tan of the rails' tilt toward the track centre (1/20)
  double sleeper_spacing = 0.6;          // [m]
  int rail_elements_between_sleepers = 6;
  double start_arc_length = 0.0;  // s at the start of the first segment [m]
  DataFile data;                  // track materials (Tables 1 and 2 of the paper)
  std::vector<Segment> segments;
  Irregularities irregularities;
  // Local defects of the rails (dipped joints, welds), applied with effects.track_defects.
  std::vector<contact::RailDefect> defects;
  // Zones of scaled pad and ballast stiffness and damping, applied with effects.support_variation.
  std::vector<SupportZone> support;

  double length() const;  // sum of the segment lengths [m]
  double endArcLength() const { return start_arc_length + length(); }
};

struct Vehicle {
  DataFile data;                        // bodies, joints and suspension
  double start_arc_length = 0.0;        // s of the leading wheelset at t = 0 [m]
  double speed = 0.0;                   // forward speed [m/s]
  std::string wheel_profile = "s1002";  // a built-in profile name or a profile file
  DataFile wheel_profile_file;          // set when wheel_profile names a file
  double nominal_radius = 0.445;        // nominal rolling radius r0 [m]
  double back_to_back = 1.360;          // distance between the wheels' inner (back) faces [m]
  int wheelsets = 4;                    // must match the vehicle data file
  // Flats and out-of-roundness, one entry per wheel (WheelDefect::wheel = 2 * wheelset + side), applied
  // with effects.wheel_defects.
  std::vector<contact::WheelDefect> wheel_defects;
};

// Standalone track scenario: prescribed loads travelling along the track (no vehicle).
struct MovingLoad {
  double offset = 0.0;  // behind the first load [m]
  LoadRail rail = LoadRail::kBoth;
  double vertical = 0.0;  // [N] per rail, downward positive
  double lateral = 0.0;   // [N] per rail, toward the field side positive
};
struct MovingLoads {
  bool present = false;
  double start_arc_length = 0.0;  // s of the first load at t = 0 [m]
  double speed = 0.0;             // [m/s], >= 0 (0 = static load)
  std::vector<MovingLoad> loads;
};

// Wheel-rail interface data a user varies between runs (rail condition, contact damping). The rest of the
// contact data (materials, Polach's reduction factors, detection settings) is rail_contact's.
struct Contact {
  double friction = 0.3;                // mu0, maximum friction coefficient [-] (dry rail 0.3-0.4, wet 0.1-0.2)
  double restitution = 0.5;             // e of the Hertz normal damping (paper eq. 9) [-], 0..1
  double impact_velocity_floor = 0.01;  // floor on the impact penetration rate in eq. 9 [m/s]
};

// What is simulated. An effect that is off is not built and costs nothing.
struct Effects {
  TrackModel track_model = TrackModel::kFlexible;
  bool irregularities = false;     // apply track.irregularities to the rails
  bool track_defects = false;      // apply track.defects (dipped joints, welds) to the rails
  bool wheel_defects = false;      // apply vehicle.wheel_defects (flats, out-of-roundness) to the wheels
  bool support_variation = false;  // apply track.support (zones of scaled pads and ballast) to the FE track
  bool flange_contact = true;      // flange-rail contact searched besides tread-rail
  bool spin_creepage = true;       // spin in the creep forces
  CreepLaw creep_law = CreepLaw::kPolach;
  bool track_damping = true;               // Rayleigh damping of the beams and the dampers of pads/ballast
  bool absorbing_ends = true;              // dashpots at both track ends
  bool rail_deflection_output = true;      // publish rail deflections at output.deflection_sections
  bool contact_point_output = true;        // publish contact points
  bool rviz_markers = false;               // publish visualization markers
  bool floor_acceleration_output = false;  // carbody floor accelerations at the vehicle's measurement points
  bool pad_force_output = false;           // rail-pad forces and rail displacements under the train (flexible)
  bool energy_output = false;              // mechanical energy of the vehicle (and of the flexible track)
};

// The on/off effects by their key in the scene's effects section, in the order of the file: read by the
// loader, written by writeScene and listed in the cost profile from this one table.
struct EffectSwitch {
  const char* key;
  bool Effects::*on;
};
inline constexpr EffectSwitch kEffectSwitches[] = {
    {"irregularities", &Effects::irregularities},
    {"track_defects", &Effects::track_defects},
    {"wheel_defects", &Effects::wheel_defects},
    {"support_variation", &Effects::support_variation},
    {"flange_contact", &Effects::flange_contact},
    {"spin_creepage", &Effects::spin_creepage},
    {"track_damping", &Effects::track_damping},
    {"absorbing_ends", &Effects::absorbing_ends},
    {"rail_deflection_output", &Effects::rail_deflection_output},
    {"contact_point_output", &Effects::contact_point_output},
    {"rviz_markers", &Effects::rviz_markers},
    {"floor_acceleration_output", &Effects::floor_acceleration_output},
    {"pad_force_output", &Effects::pad_force_output},
    {"energy_output", &Effects::energy_output},
};

struct End {
  EndKind kind = EndKind::kArcLength;
  double value = 0.0;  // [s] or [m]; arc length 0 in the file = track end
};

// The flexible track integrated over a window that moves with the vehicle (rail_track_node
// doc/track_window.md): its cost per step no longer grows with the track's length. Off: the whole track.
struct TrackWindow {
  bool enabled = false;  // off: the full-length FE track (the reference)
  double behind = 5.0;   // kept behind the last wheel [m]
  double ahead = 5.0;    // kept ahead of the first wheel [m]
  double shift = 3.0;    // distance of one move [m], whole sleeper bays
  double length = 0.0;   // window length [m]; 0 = the minimum the vehicle and margins need
};

struct Solver {
  double track_step = 2.0e-5;        // Newmark fixed step [s] (the paper's converged value)
  double vehicle_rtol = 1.0e-6;      // CVODE relative tolerance
  double vehicle_atol = 1.0e-8;      // CVODE absolute tolerance
  double vehicle_max_step = 2.0e-5;  // CVODE maximum step [s] in co-simulation; <= track_step
  double standalone_max_step = 0.0;  // CVODE maximum step [s] without a track node; 0 = none (error control)
  VehicleMethod vehicle_method = VehicleMethod::kAuto;
  Transport transport = Transport::kShm;
  double exchange_timeout = 10.0;   // longest wait for the peer during a run [s]
  double handshake_timeout = 30.0;  // longest wait for the peer to appear [s]
  End end;
  TrackWindow track_window;  // flexible track only
};

struct Output {
  std::string bag;                          // bag file; empty = no bag; relative = under the run's output dir
  double rate = 1000.0;                     // publishing rate of the outputs [Hz]
  std::vector<std::string> topics;          // which topics go to the bag (see kKnownTopics)
  std::vector<double> deflection_sections;  // arc lengths where rail deflections are published [m]
  double pad_force_margin = 3.0;  // pad forces from this far behind the last wheelset to ahead of the first [m]
};

// The resolved scene.
struct Scene {
  std::string file;  // the scene file as given (names it in messages)
  std::string name;  // scene.name, or the file's stem
  std::string description;
  Track track;
  bool has_vehicle = false;
  Vehicle vehicle;
  MovingLoads moving_loads;
  Contact contact;  // with a vehicle only
  Effects effects;
  Solver solver;
  Output output;
  std::uint64_t hash = 0;  // of the resolved scene and the contents of its data files

  int wheelCount() const { return has_vehicle ? 2 * vehicle.wheelsets : 0; }
  bool cosimulation() const { return has_vehicle && effects.track_model != TrackModel::kRigid; }
  bool needsTrackNode() const { return effects.track_model != TrackModel::kRigid; }
  bool runsFeIntegration() const { return effects.track_model == TrackModel::kFlexible; }
};

// Topics a scene may record (output.topics).
extern const std::vector<std::string> kKnownTopics;

// The scene file's word of a value (the tables above).
inline const char* toString(TrackModel v) { return wordOf(kTrackModelWords, v); }
inline const char* toString(Transport v) { return wordOf(kTransportWords, v); }
inline const char* toString(CreepLaw v) { return wordOf(kCreepLawWords, v); }
inline const char* toString(SegmentType v) { return wordOf(kSegmentTypeWords, v); }
inline const char* toString(Direction v) { return wordOf(kDirectionWords, v); }
inline const char* toString(IrregularitySource v) { return wordOf(kIrregularitySourceWords, v); }
inline const char* toString(VehicleMethod v) { return wordOf(kVehicleMethodWords, v); }
inline const char* toString(EndKind v) { return wordOf(kEndKindWords, v); }
inline const char* toString(LoadRail v) { return wordOf(kLoadRailWords, v); }

}  // namespace rail::core
