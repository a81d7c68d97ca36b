// Scene loading: shipped scenes load and round-trip; each class of malformed scene gets its message.
#include <gtest/gtest.h>

#include <dirent.h>

#include <string>
#include <vector>

#include "rail_core/geometry_builder.hpp"
#include "rail_core/scene_loader.hpp"
#include "rail_core/testing/fixtures.hpp"

using namespace rail::core;

namespace {

const std::string kData = RAILSIM_TEST_DATA_DIR;
const std::string kConfig = rail::core::fixtures::configDir();

// A small valid scene; each malformed case below changes one thing in it.
const std::string kBase = R"(name: base
track:
  gauge: 1.668
  data: track_data.yaml
  segments:
    - {type: straight, length: 50.0}
    - {type: transition, length: 40.0, direction: left, radius_start: 0, radius_end: 500.0, cant_start: 0.0, cant_end: 0.1}
    - {type: circular, length: 60.0, direction: left, radius: 500.0, cant: 0.1}
vehicle:
  data: vehicle_data.yaml
  start_arc_length: 25.0
  speed: 30.0
  back_to_back: 1.592
effects:
  track_model: rigid_fe
solver:
  track_step: 2.0e-5
  vehicle_max_step: 1.0e-5
output:
  topics: [wheel_states]
)";

Scene load(const std::string& text) { return loadSceneText(text, "scene.yaml", kData); }

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << "test set-up: '" << from << "' not in the base scene";
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

// The error message of loading `text`, or "" when it loads.
std::string errorOf(const std::string& text) {
  try {
    load(text);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

std::vector<std::string> shippedScenes() {
  std::vector<std::string> out;
  const std::string dir = kConfig + "/scenes";
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string n = e->d_name;
      if (n.size() > 5 && n.substr(n.size() - 5) == ".yaml") out.push_back(dir + "/" + n);
    }
    closedir(d);
  }
  return out;
}

}  // namespace

TEST(Scene, BaseSceneLoadsWithDefaults) {
  const Scene s = load(kBase);
  EXPECT_EQ(s.name, "base");
  EXPECT_DOUBLE_EQ(s.track.gauge, 1.668);
  EXPECT_DOUBLE_EQ(s.track.cant_reference_width, 1.668 + 0.065);  // default: gauge + 65 mm
  EXPECT_DOUBLE_EQ(s.track.rail_inclination, 0.05);               // default 1/20
  EXPECT_EQ(s.track.segments.size(), 3u);
  EXPECT_DOUBLE_EQ(s.track.length(), 150.0);
  EXPECT_EQ(s.effects.track_model, TrackModel::kRigidFe);
  EXPECT_TRUE(s.effects.flange_contact);  // default on
  EXPECT_EQ(s.solver.end.kind, EndKind::kArcLength);
  EXPECT_DOUBLE_EQ(s.solver.end.value, 150.0);  // default: the track's end
  EXPECT_EQ(s.wheelCount(), 8);
  EXPECT_TRUE(s.cosimulation());
  EXPECT_FALSE(s.runsFeIntegration());
  // Left curve: positive curvature, the right (outer) rail raised: positive cant.
  EXPECT_DOUBLE_EQ(s.track.segments[2].curvatureAtStart(), 1.0 / 500.0);
  EXPECT_DOUBLE_EQ(s.track.segments[2].signedCantAtStart(), 0.1);
}

TEST(Scene, EveryShippedSceneLoadsAndRoundTrips) {
  const auto scenes = shippedScenes();
  ASSERT_GE(scenes.size(), 3u) << "expected the paper, straight and tight-curve scenes in config/scenes";
  for (const auto& path : scenes) {
    SCOPED_TRACE(path);
    Scene a;
    ASSERT_NO_THROW(a = loadSceneFile(path));
    const std::string resolved = toYaml(a);
    // The resolved form loads again to the same scene: same text, same hash.
    const Scene b = loadSceneText(resolved, path, kConfig + "/scenes");
    EXPECT_EQ(toYaml(b), resolved);
    EXPECT_EQ(a.hash, b.hash);
    EXPECT_FALSE(describe(a, Role::kValidator).empty());
  }
}

TEST(Scene, ThePaperSceneIsTheOneTheIssueDescribes) {
  const Scene s = loadSceneFile(kConfig + "/scenes/paper_demo.yaml");
  EXPECT_DOUBLE_EQ(s.track.length(), 500.0);
  EXPECT_DOUBLE_EQ(s.track.gauge, 1.668);
  EXPECT_NEAR(s.vehicle.speed * 3.6, 110.0, 1e-3);
  ASSERT_EQ(s.track.segments.size(), 5u);
  EXPECT_EQ(s.track.segments[2].type, SegmentType::kCircular);
  EXPECT_DOUBLE_EQ(s.track.segments[2].radius, 500.0);
  EXPECT_EQ(s.track.segments[2].direction, Direction::kLeft);
  EXPECT_EQ(s.output.deflection_sections, (std::vector<double>{66.0, 255.0}));
}

TEST(Scene, HashChangesWithTheSceneAndNotWithComments) {
  const Scene a = load(kBase);
  const Scene b = load(kBase + "# a comment changes nothing\n");
  const Scene c = load(replaced(kBase, "speed: 30.0", "speed: 31.0"));
  EXPECT_EQ(a.hash, b.hash);
  EXPECT_NE(a.hash, c.hash);
}

TEST(Scene, InclinationAcceptsARatioOrANumber) {
  EXPECT_DOUBLE_EQ(
      load(replaced(kBase, "gauge: 1.668", "gauge: 1.668\n  rail_inclination: 1/40")).track.rail_inclination, 0.025);
  EXPECT_DOUBLE_EQ(
      load(replaced(kBase, "gauge: 1.668", "gauge: 1.668\n  rail_inclination: 0.025")).track.rail_inclination, 0.025);
  EXPECT_EQ(errorOf(replaced(kBase, "gauge: 1.668", "gauge: 1.668\n  rail_inclination: 1/zero")),
            "scene.yaml: track.rail_inclination: must be a ratio such as 1/20 or a number, got '1/zero' (line 4)");
}

// Each class of malformed scene, with the exact message a user sees.
struct Malformed {
  const char* what;
  std::string text;
  std::string message;
};

TEST(Scene, MalformedScenesAreRefusedWithOneMessageNamingFileAndField) {
  const std::vector<Malformed> cases = {
      {"negative radius", replaced(kBase, "radius: 500.0, cant: 0.1}", "radius: -500, cant: 0.1}"),
       "scene.yaml: track.segments[2].radius: must be positive, got -500 (line 8)"},
      {"unknown key", kBase + "effects2: 1\n",
       "scene.yaml: effects2: unknown key (known here: contact, description, effects, moving_loads, name, output, "
       "solver, track, vehicle) (line 21)"},
      {"misspelt effect", replaced(kBase, "track_model: rigid_fe", "track_model: rigid_fe\n  flange_contat: true"),
       "scene.yaml: effects.flange_contat: unknown key (known here: absorbing_ends, contact_point_output, "
       "creep_law, energy_output, flange_contact, floor_acceleration_output, irregularities, pad_force_output, "
       "rail_deflection_output, rviz_markers, spin_creepage, support_variation, track_damping, track_defects, "
       "track_model, wheel_defects) (line 16)"},
      {"missing field", replaced(kBase, "  speed: 30.0\n", ""),
       "scene.yaml: vehicle.speed: required key missing (line 10)"},
      {"wrong type", replaced(kBase, "speed: 30.0", "speed: fast"),
       "scene.yaml: vehicle.speed: must be a number, got 'fast' (line 12)"},
      {"wrong type: map for a number", replaced(kBase, "gauge: 1.668", "gauge: {value: 1.668}"),
       "scene.yaml: track.gauge: must be a number, got {value: 1.668} (line 3)"},
      {"not finite", replaced(kBase, "speed: 30.0", "speed: .nan"),
       "scene.yaml: vehicle.speed: must be a finite number, got .nan (line 12)"},
      {"negative length", replaced(kBase, "length: 50.0", "length: -50.0"),
       "scene.yaml: track.segments[0].length: must be positive, got -50 (line 6)"},
      {"zero speed where one is needed", replaced(kBase, "speed: 30.0", "speed: 0"),
       "scene.yaml: vehicle.speed: must be positive when solver.end is an arc length (the run would never end), got 0"},
      {"bad choice", replaced(kBase, "track_model: rigid_fe", "track_model: elastic"),
       "scene.yaml: effects.track_model: must be one of rigid, rigid_fe, flexible, got 'elastic' (line 15)"},
      {"curvature jump", replaced(kBase, "radius_end: 500.0", "radius_end: 400.0"),
       "scene.yaml: track.segments[2]: curvature jumps at its start from 0.0025 to 0.002 1/m (track.segments[1] "
       "ends there); make the chain continuous (a transition) or mark the jump with jump_allowed: true (line 8)"},
      {"cant jump", replaced(kBase, "radius: 500.0, cant: 0.1}", "radius: 500.0, cant: 0.12}"),
       "scene.yaml: track.segments[2]: cant jumps at its start from 0.1 to 0.12 m (track.segments[1] ends there); "
       "make the chain continuous (a cant ramp) or mark the jump with jump_allowed: true (line 8)"},
      {"missing data file", replaced(kBase, "data: vehicle_data.yaml", "data: no_such_coach.yaml"),
       "scene.yaml: vehicle.data: cannot read 'no_such_coach.yaml' (resolved to " + kData +
           "/no_such_coach.yaml): No such file or directory (line 10)"},
      {"missing profile file", replaced(kBase, "gauge: 1.668", "gauge: 1.668\n  rail_profile: worn.prr"),
       "scene.yaml: track.rail_profile: cannot read 'worn.prr' (resolved to " + kData +
           "/worn.prr): No such file or directory (line 4)"},
      {"vehicle step above the track step", replaced(kBase, "vehicle_max_step: 1.0e-5", "vehicle_max_step: 5.0e-5"),
       "scene.yaml: solver.vehicle_max_step: must be at most solver.track_step (2e-05 s) in co-simulation, got 5e-05 "
       "(line 18)"},
      {"vehicle-alone step out of range", replaced(kBase, "vehicle_max_step: 1.0e-5", "standalone_max_step: 1.0"),
       "scene.yaml: solver.standalone_max_step: must be between 1e-08 and 0.1 s (or 0: none), got 1 (line 18)"},
      {"output needs a track node",
       replaced(replaced(kBase, "topics: [wheel_states]", "topics: [wheel_states, rail_deflection]"),
                "track_model: rigid_fe", "track_model: rigid"),
       "scene.yaml: output.topics[1]: 'rail_deflection' needs a track node: effects.track_model flexible, or "
       "rigid_fe (rails that do not move: zeros)"},
      {"unknown topic", replaced(kBase, "topics: [wheel_states]", "topics: [wheel_state]"),
       "scene.yaml: output.topics[0]: unknown topic 'wheel_state' (known: wheel_states, contact_wrenches, "
       "contact_points, rail_deflection, wheelset_kinematics, markers, tf, clock, floor_accelerations, pad_forces, "
       "vehicle_energy, track_energy) "
       "(line 20)"},
      {"floor accelerations recorded with the effect off",
       replaced(kBase, "topics: [wheel_states]", "topics: [wheel_states, floor_accelerations]"),
       "scene.yaml: output.topics[1]: 'floor_accelerations' is recorded only with "
       "effects.floor_acceleration_output: true"},
      {"pad forces without the integrated FE track",
       replaced(replaced(kBase, "topics: [wheel_states]", "topics: [wheel_states, pad_forces]"),
                "track_model: rigid_fe", "track_model: rigid_fe\n  pad_force_output: true"),
       "scene.yaml: output.topics[1]: 'pad_forces' needs the integrated FE track: effects.track_model flexible"},
      {"energy recorded with the effect off",
       replaced(kBase, "topics: [wheel_states]", "topics: [wheel_states, vehicle_energy]"),
       "scene.yaml: output.topics[1]: 'vehicle_energy' is recorded only with effects.energy_output: true"},
      {"track energy without the integrated FE track",
       replaced(replaced(kBase, "topics: [wheel_states]", "topics: [track_energy]"), "track_model: rigid_fe",
                "track_model: rigid_fe\n  energy_output: true"),
       "scene.yaml: output.topics[0]: 'track_energy' needs the integrated FE track: effects.track_model flexible"},
      {"negative pad force margin",
       replaced(kBase, "topics: [wheel_states]", "topics: [wheel_states]\n  pad_force_margin: -1"),
       "scene.yaml: output.pad_force_margin: must be between 0 and 100 m, got -1 (line 21)"},
      {"friction above 1", kBase + "contact: {friction: 1.5}\n",
       "scene.yaml: contact.friction: must be positive and at most 1, got 1.5 (line 21)"},
      {"restitution not a number", kBase + "contact:\n  restitution: high\n",
       "scene.yaml: contact.restitution: must be a number, got 'high' (line 22)"},
      {"zero impact-velocity floor", kBase + "contact: {impact_velocity_floor: 0}\n",
       "scene.yaml: contact.impact_velocity_floor: must be between 1e-06 and 10 m/s, got 0 (line 21)"},
      {"unknown contact key", kBase + "contact: {mu: 0.4}\n",
       "scene.yaml: contact.mu: unknown key (known here: friction, impact_velocity_floor, restitution) (line 21)"},
      {"contact data without a vehicle",
       replaced(
           replaced(
               kBase,
               "vehicle:\n  data: vehicle_data.yaml\n  start_arc_length: 25.0\n  speed: 30.0\n  back_to_back: 1.592\n",
               "moving_loads:\n  loads: [{vertical: 1.0e5}]\ncontact: {friction: 0.4}\n"),
           "track_model: rigid_fe", "track_model: flexible"),
       "scene.yaml: contact: a moving-load scene has no wheel-rail contact; remove the section"},
      {"radius of a few nanometres", replaced(kBase, "radius: 500.0, cant: 0.1}", "radius: 1e-300, cant: 0.1}"),
       "scene.yaml: track.segments[2].radius: must be at least 10 m (0 = straight where allowed), got 1e-300 (line 8)"},
      {"transition to a 5 m radius", replaced(kBase, "radius_end: 500.0", "radius_end: 5.0"),
       "scene.yaml: track.segments[1].radius_end: must be at least 10 m (0 = straight where allowed), got 5 (line 7)"},
      {"gauge left to its default under a wide cant reference",
       replaced(kBase, "  gauge: 1.668\n", "  cant_reference_width: 1.733\n"),
       "scene.yaml: track.cant_reference_width: must be between track.gauge (1.435 m) and track.gauge + 0.2 m, got "
       "1.733; track.gauge is not set, so its default 1.435 m applies (line 3)"},
      {"vehicle off the track", replaced(kBase, "start_arc_length: 25.0", "start_arc_length: 150.0"),
       "scene.yaml: vehicle.start_arc_length: must lie on the track [0, 150) m, got 150 (line 11)"},
      {"irregularities on without a source",
       replaced(kBase, "track_model: rigid_fe", "track_model: rigid_fe\n  irregularities: true"),
       "scene.yaml: effects.irregularities: is on but track.irregularities gives no source (file or psd) (line 16)"},
      {"unknown spectrum",
       replaced(kBase, "  data: track_data.yaml\n",
                "  data: track_data.yaml\n  irregularities: {source: psd, psd: fra_class_9}\n"),
       "scene.yaml: track.irregularities.psd: must be one of fra_class_1, fra_class_2, fra_class_3, fra_class_4, "
       "fra_class_5, fra_class_6, german_low, german_high, got 'fra_class_9' (line 5)"},
      {"track defects on without defects",
       replaced(kBase, "track_model: rigid_fe", "track_model: rigid_fe\n  track_defects: true"),
       "scene.yaml: effects.track_defects: is on but track.defects lists none (line 16)"},
      {"defect off the track",
       replaced(kBase, "  data: track_data.yaml\n",
                "  data: track_data.yaml\n  defects: [{type: dipped_joint, s: 149.5, length: 2.0, dip_angle: 0.01}]\n"),
       "scene.yaml: track.defects[0].s: the defect (2 m long) must lie on the track (0 .. 150 m), got 149.5 (line 5)"},
      {"joint angle out of range",
       replaced(kBase, "  data: track_data.yaml\n",
                "  data: track_data.yaml\n  defects: [{type: dipped_joint, s: 40, length: 2.0, dip_angle: 0.5}]\n"),
       "scene.yaml: track.defects[0].dip_angle: must be between 0.0001 and 0.1 rad (the total angle between the two "
       "ramps), got 0.5 (line 5)"},
      {"joint gap wider than allowed",
       replaced(kBase, "  data: track_data.yaml\n",
                "  data: track_data.yaml\n  defects: [{type: dipped_joint, s: 40, length: 2.0, dip_angle: 0.01, "
                "gap: 0.08}]\n"),
       "scene.yaml: track.defects[0].gap: must be >= 0 and at most 0.05 m and the joint's length (2 m), got 0.08 "
       "(line 5)"},
      {"gap on a weld",
       replaced(kBase, "  data: track_data.yaml\n",
                "  data: track_data.yaml\n  defects: [{type: weld, s: 40, length: 0.2, height: 0.001, gap: 0.01}]\n"),
       "scene.yaml: track.defects[0].gap: unknown key (known here: height, length, rail, s, type) (line 5)"},
      {"weld of no height",
       replaced(kBase, "  data: track_data.yaml\n",
                "  data: track_data.yaml\n  defects: [{type: weld, s: 40, length: 0.2, height: 0}]\n"),
       "scene.yaml: track.defects[0].height: must be non-zero and at most 0.005 m in size (> 0 a bump, < 0 a dip), "
       "got 0 (line 5)"},
      {"wheel defects on without defects",
       replaced(kBase, "track_model: rigid_fe", "track_model: rigid_fe\n  wheel_defects: true"),
       "scene.yaml: effects.wheel_defects: is on but vehicle.wheel_defects lists none (line 16)"},
      {"flat on a wheelset the vehicle lacks",
       replaced(kBase, "  speed: 30.0\n",
                "  speed: 30.0\n  wheel_defects: [{type: flat, wheelset: 4, length: 0.05}]\n"),
       "scene.yaml: vehicle.wheel_defects[0].wheelset: must be a wheelset of the vehicle, 0 .. 3, got 4 (line 13)"},
      {"flat longer than a quarter of the wheel",
       replaced(kBase, "  speed: 30.0\n", "  speed: 30.0\n  wheel_defects: [{type: flat, wheelset: 1, length: 0.8}]\n"),
       "scene.yaml: vehicle.wheel_defects[0].length: must be between 0.001 m and a quarter of the wheel's "
       "circumference (0.699 m), got 0.8 (line 13)"},
      {"rounded flat deeper than the wheel can follow",
       replaced(
           kBase, "  speed: 30.0\n",
           "  speed: 30.0\n  wheel_defects: [{type: flat, wheelset: 1, length: 0.1, shape: rounded, depth: 0.002}]\n"),
       "scene.yaml: vehicle.wheel_defects[0].depth: must be positive and at most length^2 / (2 pi^2 r0) = "
       "0.001138 m (deeper, the wheel could not follow the dip's curvature), got 0.002 (line 13)"},
      {"new flat given a depth",
       replaced(kBase, "  speed: 30.0\n",
                "  speed: 30.0\n  wheel_defects: [{type: flat, wheelset: 1, length: 0.05, depth: 0.001}]\n"),
       "scene.yaml: vehicle.wheel_defects[0].depth: applies to a rounded flat only (a new flat 0.05 m long is "
       "0.0007028 m deep) (line 13)"},
      {"out-of-roundness of order zero",
       replaced(kBase, "  speed: 30.0\n",
                "  speed: 30.0\n  wheel_defects: [{type: out_of_round, wheelset: 0, order: 0, amplitude: 1e-4}]\n"),
       "scene.yaml: vehicle.wheel_defects[0].order: must be between 1 and 40 (harmonics round the wheel), got 0 "
       "(line 13)"},
      {"support zone off the track",
       replaced(kBase, "  data: track_data.yaml\n",
                "  data: track_data.yaml\n  support: [{s_from: 140, s_to: 160, ballast_stiffness: 3}]\n"),
       "scene.yaml: track.support[0].s_to: the zone 140 .. 160 m must lie on the track (0 .. 150 m) and end after "
       "it starts (line 5)"},
      {"support ramps longer than the zone",
       replaced(kBase, "  data: track_data.yaml\n",
                "  data: track_data.yaml\n  support: [{s_from: 40, s_to: 50, ramp: 6, ballast_stiffness: 3}]\n"),
       "scene.yaml: track.support[0].ramp: must be between 0 and half the zone's length (5 m), got 6 (line 5)"},
      {"support factor out of range",
       replaced(kBase, "  data: track_data.yaml\n",
                "  data: track_data.yaml\n  support: [{s_from: 40, s_to: 50, pad_stiffness: 0}]\n"),
       "scene.yaml: track.support[0].pad_stiffness: must be between 0.01 and 100 (a factor on the track data's "
       "value), got 0 (line 5)"},
      {"hanging sleepers with too large a void",
       replaced(kBase, "  data: track_data.yaml\n",
                "  data: track_data.yaml\n  support: [{s_from: 59.9, s_to: 60.1, sleeper_gap: 0.05}]\n"),
       "scene.yaml: track.support[0].sleeper_gap: must be between 0 and 0.02 m (the void under each sleeper of the "
       "zone), got 0.05 (line 5)"},
      {"hanging sleepers in a zone without a sleeper",
       replaced(kBase, "  data: track_data.yaml\n",
                "  data: track_data.yaml\n  support: [{s_from: 60.1, s_to: 60.4, sleeper_gap: 0.001}]\n"),
       "scene.yaml: track.support[0].sleeper_gap: the zone 60.1 .. 60.4 m holds no sleeper (every 0.6 m from s = 0 "
       "m) (line 5)"},
      {"support variation without the FE track",
       replaced(replaced(kBase, "  data: track_data.yaml\n",
                         "  data: track_data.yaml\n  support: [{s_from: 40, s_to: 50, pad_stiffness: 2}]\n"),
                "track_model: rigid_fe", "track_model: rigid_fe\n  support_variation: true"),
       "scene.yaml: effects.support_variation: needs the integrated FE track (effects.track_model: flexible), got "
       "rigid_fe (line 17)"},
      {"unknown defect",
       replaced(kBase, "  data: track_data.yaml\n",
                "  data: track_data.yaml\n  defects: [{type: squat, s: 40, length: 0.2}]\n"),
       "scene.yaml: track.defects[0].type: must be one of dipped_joint, weld, got 'squat' (line 5)"},
      {"not YAML", "track: [unclosed\n", "scene.yaml: not valid YAML: end of sequence flow not found (line 2)"},
      {"vehicle and moving loads", kBase + "moving_loads: {speed: 1.0}\n",
       "scene.yaml: a scene has exactly one of vehicle (a run with a train) or moving_loads (the track alone)"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    EXPECT_EQ(errorOf(c.text), c.message);
  }
}

// Local defects reach the scene, its resolved print-out (which loads back to the same hash) and its summary;
// listed with the effect off they are kept in the scene but not applied.
TEST(Scene, TrackDefectsRoundTripAndAreSummarised) {
  const std::string text =
      replaced(replaced(kBase, "  data: track_data.yaml\n",
                        "  data: track_data.yaml\n  defects:\n"
                        "    - {type: dipped_joint, s: 30.0, length: 1.0, dip_angle: 0.01, rail: left}\n"
                        "    - {type: weld, s: 45.0, length: 0.2, height: -0.0003}\n"
                        "    - {type: dipped_joint, s: 60.0, length: 1.0, dip_angle: 0.008, gap: 0.012}\n"),
               "track_model: rigid_fe", "track_model: rigid_fe\n  track_defects: true");
  const Scene s = load(text);
  ASSERT_EQ(s.track.defects.size(), 3u);
  EXPECT_DOUBLE_EQ(s.track.defects[2].gap, 0.012);
  EXPECT_TRUE(s.track.defects[0].left);
  EXPECT_FALSE(s.track.defects[0].right);
  EXPECT_DOUBLE_EQ(s.track.defects[1].height, -0.0003);
  const Scene again = loadSceneText(toYaml(s), "scene.yaml", kData);
  EXPECT_EQ(again.hash, s.hash);
  const std::string summary = describe(s, Role::kValidator);
  EXPECT_NE(summary.find("  defect 0: dipped_joint at s = 30.00 m, left rail, 1.000 m long, total angle 10.0 mrad\n"),
            std::string::npos)
      << summary;
  EXPECT_NE(summary.find("  defect 1: weld at s = 45.00 m, both rails, 0.200 m long, height -0.30 mm\n"),
            std::string::npos)
      << summary;
  EXPECT_NE(summary.find("  defect 2: dipped_joint at s = 60.00 m, both rails, 1.000 m long, total angle 8.0 mrad, "
                         "gap 12.0 mm\n"),
            std::string::npos)
      << summary;
  EXPECT_NE(summary.find("effects on: track_model=rigid_fe, track_defects"), std::string::npos) << summary;
  const Scene off = load(replaced(text, "  track_defects: true", "  track_defects: false"));
  EXPECT_EQ(off.track.defects.size(), 3u);
  EXPECT_NE(off.hash, s.hash);
  EXPECT_EQ(describe(off, Role::kValidator).find("defect 0"), std::string::npos);
  // The geometry the contact sees carries them only with the effect on (off: nothing to evaluate).
  EXPECT_EQ(buildTrackGeometry(s).defects().defects().size(), 3u);
  // The gap's bridging wheels are the vehicle's.
  EXPECT_DOUBLE_EQ(buildTrackGeometry(s).defects().defects()[2].wheel_radius, s.vehicle.nominal_radius);
  EXPECT_TRUE(buildTrackGeometry(off).defects().empty());
}

// Wheel defects: a defect on both wheels is one entry per wheel; the print-out loads back to the same hash,
// the summary lists each with its depth, and the contact options carry them only with the effect on.
TEST(Scene, WheelDefectsRoundTripAndAreSummarised) {
  const std::string text =
      replaced(replaced(kBase, "  speed: 30.0\n",
                        "  speed: 30.0\n  wheel_defects:\n"
                        "    - {type: flat, wheelset: 0, length: 0.05, angle: 0.5}\n"
                        "    - {type: flat, wheelset: 2, side: right, length: 0.1, shape: rounded, depth: 0.0008}\n"
                        "    - {type: out_of_round, wheelset: 3, side: left, order: 3, amplitude: 5.0e-5}\n"),
               "track_model: rigid_fe", "track_model: rigid_fe\n  wheel_defects: true");
  const Scene s = load(text);
  ASSERT_EQ(s.vehicle.wheel_defects.size(), 4u);
  EXPECT_EQ(s.vehicle.wheel_defects[0].wheel, 0u);
  EXPECT_EQ(s.vehicle.wheel_defects[1].wheel, 1u);
  EXPECT_EQ(s.vehicle.wheel_defects[2].wheel, 5u);
  EXPECT_TRUE(s.vehicle.wheel_defects[2].rounded);
  EXPECT_EQ(s.vehicle.wheel_defects[3].wheel, 6u);
  EXPECT_EQ(s.vehicle.wheel_defects[3].order, 3);
  const Scene again = loadSceneText(toYaml(s), "scene.yaml", kData);
  EXPECT_EQ(again.hash, s.hash);
  const std::string summary = describe(s, Role::kValidator);
  // A new flat's depth r0 (1 - cos(asin(L / 2 r0))) = 0.7025 mm for L = 50 mm, r0 = 0.445 m.
  EXPECT_NE(summary.find("  wheel defect 0: flat on wheelset 0 left at 0.50 rad, new, 50.0 mm long, 0.703 mm deep\n"),
            std::string::npos)
      << summary;
  EXPECT_NE(summary.find("  wheel defect 2: flat on wheelset 2 right at 0.00 rad, rounded, 100.0 mm long, 0.800 mm "
                         "deep\n"),
            std::string::npos)
      << summary;
  EXPECT_NE(
      summary.find("  wheel defect 3: out_of_round on wheelset 3 left at 0.00 rad, order 3, amplitude 0.050 mm\n"),
      std::string::npos)
      << summary;
  EXPECT_NE(summary.find(", wheel_defects"), std::string::npos) << summary;
  const Scene off = load(replaced(text, "  wheel_defects: true", "  wheel_defects: false"));
  EXPECT_NE(off.hash, s.hash);
  EXPECT_EQ(describe(off, Role::kValidator).find("wheel defect 0"), std::string::npos);
  EXPECT_EQ(sceneContact(s).over(rail::contact::WheelContactOptions()).wheel_defects.defects().size(), 4u);
  EXPECT_TRUE(sceneContact(off).over(rail::contact::WheelContactOptions()).wheel_defects.empty());
}

// Support zones: the print-out loads back to the same hash, the summary lists them, and the FE track data
// carries them only with the effect on (rail_track_node's tests check the mesh).
TEST(Scene, SupportZonesRoundTripAndAreSummarised) {
  const std::string text =
      replaced(replaced(kBase, "  data: track_data.yaml\n",
                        "  data: track_data.yaml\n  support:\n"
                        "    - {s_from: 40.0, s_to: 70.0, ramp: 5.0, ballast_stiffness: 4.0, ballast_damping: 2.0}\n"
                        "    - {s_from: 100.0, s_to: 101.2, pad_stiffness: 0.3}\n"),
               "track_model: rigid_fe", "track_model: flexible\n  support_variation: true");
  const Scene s = load(text);
  ASSERT_EQ(s.track.support.size(), 2u);
  EXPECT_DOUBLE_EQ(s.track.support[0].ramp, 5.0);
  EXPECT_DOUBLE_EQ(s.track.support[0].pad_stiffness, 1.0);
  EXPECT_DOUBLE_EQ(s.track.support[1].pad_stiffness, 0.3);
  EXPECT_DOUBLE_EQ(s.track.support[1].ramp, 0.0);
  const Scene again = loadSceneText(toYaml(s), "scene.yaml", kData);
  EXPECT_EQ(again.hash, s.hash);
  const std::string summary = describe(s, Role::kValidator);
  EXPECT_NE(summary.find("  support zone 0: s = 40.00 .. 70.00 m, ramps 5.00 m; pads x1.00 stiffness, x1.00 damping; "
                         "ballast x4.00 stiffness, x2.00 damping\n"),
            std::string::npos)
      << summary;
  EXPECT_NE(summary.find(", support_variation"), std::string::npos) << summary;
  const Scene off = load(replaced(text, "  support_variation: true", "  support_variation: false"));
  EXPECT_NE(off.hash, s.hash);
  EXPECT_EQ(describe(off, Role::kValidator).find("support zone 0"), std::string::npos);
  // Half-way up the first zone's ramp (s = 42.5 m) the ballast is at half its change; overlapping nothing
  // else, the pads are untouched.
  const SupportFactors f = supportFactors(s.track.support, 42.5);
  EXPECT_DOUBLE_EQ(f.ballast_stiffness, 2.5);
  EXPECT_DOUBLE_EQ(f.ballast_damping, 1.5);
  EXPECT_DOUBLE_EQ(f.pad_stiffness, 1.0);
  EXPECT_DOUBLE_EQ(supportFactors(s.track.support, 39.9).ballast_stiffness, 1.0);
  EXPECT_DOUBLE_EQ(supportFactors(s.track.support, 55.0).ballast_stiffness, 4.0);
}

// A scene with an impact (a dipped joint here) is told when its track step or output rate is too coarse
// for the impact's first peak, in the summary the nodes and the validator print; without the effect, or fine
// enough, nothing is said.
TEST(Scene, ImpactsWarnOfACoarseTrackStepAndOutputRate) {
  const std::string text = replaced(
      replaced(kBase, "  data: track_data.yaml\n",
               "  data: track_data.yaml\n  defects: [{type: dipped_joint, s: 30.0, length: 1.0, dip_angle: 0.01}]\n"),
      "track_model: rigid_fe", "track_model: rigid_fe\n  track_defects: true");
  const Scene coarse =
      loadSceneText(text, "scene.yaml", kData, {"solver.track_step=4e-5", "solver.vehicle_max_step=4e-5"});
  const std::vector<std::string> w = sceneWarnings(coarse);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[0],
            "solver.track_step 4e-05 s is coarser than the 2e-05 s that a dipped joint's impact peak P1 needs "
            "(its P2 converges at coarser steps; docs/defects.md)");
  EXPECT_EQ(w[1],
            "output.rate 1000 Hz under-samples a dipped joint's impact (about 1 ms): 5000 Hz or more resolves "
            "its P1 in the bag");
  EXPECT_NE(describe(coarse, Role::kTrack).find("\nwarning: solver.track_step 4e-05 s is coarser"), std::string::npos);
  const Scene fine = loadSceneText(text, "scene.yaml", kData, {"output.rate=10000"});
  EXPECT_TRUE(sceneWarnings(fine).empty());
  const Scene off =
      loadSceneText(text, "scene.yaml", kData,
                    {"effects.track_defects=false", "solver.track_step=4e-5", "solver.vehicle_max_step=4e-5"});
  EXPECT_TRUE(sceneWarnings(off).empty());
  EXPECT_EQ(describe(off, Role::kTrack).find("warning:"), std::string::npos);
}

// What rviz draws of the defects: a joint on the left rail along that rail's top (dipped by the joint itself
// at its centre), a zone along the centre line, each labelled; nothing of an effect that is off.
TEST(Scene, DefectOutlinesFollowTheRailsAndTheCentreLine) {
  const std::string text = replaced(
      replaced(kBase, "  data: track_data.yaml\n",
               "  data: track_data.yaml\n"
               "  defects: [{type: dipped_joint, s: 30.0, length: 1.0, dip_angle: 0.01, rail: left}]\n"
               "  support: [{s_from: 40.0, s_to: 70.0, ramp: 5.0, ballast_stiffness: 4.0, ballast_damping: 2.0}]\n"),
      "track_model: rigid_fe", "track_model: flexible\n  track_defects: true\n  support_variation: true");
  const Scene s = load(text);
  const rail::contact::TrackGeometry geometry = buildTrackGeometry(s);
  const std::vector<DefectOutline> outlines = defectOutlines(s, geometry);
  ASSERT_EQ(outlines.size(), 2u);
  const DefectOutline& joint = outlines[0];
  EXPECT_EQ(joint.kind, DefectOutline::Kind::kRailDefect);
  EXPECT_EQ(joint.label, "dipped joint 10.0 mrad");
  ASSERT_EQ(joint.points.size(), 11u);  // 1 m at most 0.1 m apart
  rail::contact::RailPoint rp;
  geometry.rail(rail::contact::RailSide::kLeft, 29.5, rp);
  EXPECT_LT((joint.points.front() - rp.p_origin_in_world).norm(), 1e-12);
  // At the joint the rail top lies alpha L / 2 = 2.5 mm below the plain rail's (the geometry without defects).
  Scene plain = s;
  plain.effects.track_defects = false;
  buildTrackGeometry(plain).rail(rail::contact::RailSide::kLeft, 30.0, rp);
  EXPECT_NEAR((rp.p_origin_in_world - joint.points[5]).norm(), 2.5e-3, 1e-5);
  const DefectOutline& zone = outlines[1];
  EXPECT_EQ(zone.kind, DefectOutline::Kind::kSupportZone);
  EXPECT_EQ(zone.label, "ballast x4.00, ballast damping x2.00");
  ASSERT_EQ(zone.points.size(), 31u);
  rail::contact::TrackPoint tp;
  geometry.centre(70.0, tp);
  EXPECT_LT((zone.points.back() - tp.p_center_in_world).norm(), 1e-12);
  Scene off = s;
  off.effects.track_defects = off.effects.support_variation = false;
  EXPECT_TRUE(defectOutlines(off, geometry).empty());
}

TEST(Scene, ContactSectionReachesTheSceneAndItsHash) {
  const Scene base = load(kBase);
  EXPECT_DOUBLE_EQ(base.contact.friction, 0.3);  // the defaults are rail_contact's
  EXPECT_DOUBLE_EQ(base.contact.restitution, 0.5);
  EXPECT_DOUBLE_EQ(base.contact.impact_velocity_floor, 0.01);
  const Scene wet = load(kBase + "contact: {friction: 0.15, restitution: 0.8, impact_velocity_floor: 0.1}\n");
  EXPECT_DOUBLE_EQ(wet.contact.friction, 0.15);
  EXPECT_DOUBLE_EQ(wet.contact.restitution, 0.8);
  EXPECT_DOUBLE_EQ(wet.contact.impact_velocity_floor, 0.1);
  EXPECT_NE(wet.hash, base.hash);  // two nodes with different rail conditions refuse each other
  EXPECT_NE(toYaml(wet).find("contact:\n  friction: 0.15\n  restitution: 0.8\n  impact_velocity_floor: 0.1"),
            std::string::npos)
      << toYaml(wet);
  // Overrides reach it like any key.
  EXPECT_DOUBLE_EQ(loadSceneText(kBase, "scene.yaml", kData, {"contact.friction=0.45"}).contact.friction, 0.45);
}

TEST(Scene, MissingSceneFileNamesIt) {
  try {
    loadSceneFile("/nonexistent/scene.yaml");
    FAIL() << "a missing scene file was accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/scene.yaml: cannot read the scene file: No such file or directory");
  }
}

TEST(Scene, DescribeListsEffectsAndComponents) {
  const Scene s = load(kBase);
  const std::string v = describe(s, Role::kVehicle);
  EXPECT_NE(v.find("effects on: track_model=rigid_fe, flange_contact, spin_creepage, creep_law=polach"),
            std::string::npos)
      << v;
  EXPECT_NE(v.find("effects off: irregularities, track_defects, wheel_defects, support_variation, track_damping, "
                   "absorbing_ends, rail_deflection_output"),
            std::string::npos)
      << v;
  EXPECT_NE(v.find("wheel-centre wrenches from the track node over shm"), std::string::npos) << v;
  const std::string t = describe(s, Role::kTrack);
  EXPECT_NE(t.find("rigid FE rails: contact on the undeformed rails, no FE integration"), std::string::npos) << t;
}

TEST(Scene, TheVehicleAloneHasItsOwnStepCapAndTheSummarySaysWhichAppliesToTheRun) {
  // The scene's vehicle_max_step is the co-simulation cap; a run without a track node takes
  // standalone_max_step (0 = none) and the summary names the cap the run uses.
  const Scene cosim = load(kBase);
  EXPECT_DOUBLE_EQ(cosim.solver.standalone_max_step, 0.0);
  EXPECT_NE(describe(cosim, Role::kVehicle).find("max step 1e-05 s (auto)"), std::string::npos)
      << describe(cosim, Role::kVehicle);
  const Scene alone = loadSceneText(kBase, "scene.yaml", kData, {"effects.track_model=rigid"});
  EXPECT_NE(describe(alone, Role::kVehicle).find("max step none (auto)"), std::string::npos)
      << describe(alone, Role::kVehicle);
  const Scene capped =
      loadSceneText(kBase, "scene.yaml", kData, {"effects.track_model=rigid", "solver.standalone_max_step=1e-4"});
  EXPECT_DOUBLE_EQ(capped.solver.standalone_max_step, 1e-4);
  EXPECT_NE(describe(capped, Role::kVehicle).find("max step 0.0001 s (auto)"), std::string::npos)
      << describe(capped, Role::kVehicle);
  EXPECT_NE(capped.hash, alone.hash);
  EXPECT_NE(toYaml(capped).find("standalone_max_step: 0.0001"), std::string::npos) << toYaml(capped);
}

TEST(Scene, OverridesChangeKeysAsIfTheFileSaidSo) {
  // One scene run with each track model and a shorter end: the override gives the scene (and the hash) the
  // file would give with those keys written in it.
  const Scene over = loadSceneText(kBase, "scene.yaml", kData,
                                   {"effects.track_model=flexible", "solver.end={time: 0.5}", "output.bag=x.bag"});
  std::string edited = replaced(kBase, "track_model: rigid_fe", "track_model: flexible");
  edited = replaced(edited, "  vehicle_max_step: 1.0e-5\n", "  vehicle_max_step: 1.0e-5\n  end: {time: 0.5}\n");
  edited = replaced(edited, "output:\n", "output:\n  bag: x.bag\n");
  const Scene file = load(edited);
  EXPECT_EQ(over.effects.track_model, TrackModel::kFlexible);
  EXPECT_EQ(over.solver.end.kind, EndKind::kTime);
  EXPECT_DOUBLE_EQ(over.solver.end.value, 0.5);
  EXPECT_EQ(over.output.bag, "x.bag");
  EXPECT_EQ(over.hash, file.hash);
  EXPECT_EQ(toYaml(over), toYaml(file));
  // An empty value keeps the file's value (a launch argument left empty).
  EXPECT_EQ(loadSceneText(kBase, "scene.yaml", kData, {"effects.track_model="}).hash, load(kBase).hash);
  // A missing map is created.
  EXPECT_EQ(loadSceneText(kBase, "scene.yaml", kData, {"effects.irregularities=false"}).effects.irregularities, false);
  EXPECT_EQ(splitOverrides("  a=1 b.c=2\tc= "), (SceneOverrides{"a=1", "b.c=2", "c="}));
  EXPECT_EQ(splitOverrides("solver.end={time: 1.5} output.bag='a b.bag' t=[x, y]"),
            (SceneOverrides{"solver.end={time: 1.5}", "output.bag='a b.bag'", "t=[x, y]"}));
}

TEST(Scene, BadOverridesAreRefusedNamingTheOverride) {
  auto error = [](const SceneOverrides& o) -> std::string {
    try {
      loadSceneText(kBase, "scene.yaml", kData, o);
    } catch (const SceneError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error({"effects.track_model"}),
            "scene.yaml: override 'effects.track_model': expected key=value (e.g. effects.track_model=flexible)");
  EXPECT_EQ(error({"track.segments.length=3"}),
            "scene.yaml: track.segments.length: override 'track.segments.length=3': segments is not a map of keys");
  EXPECT_EQ(error({"effects..x=1"}), "scene.yaml: effects..x: override 'effects..x=1': empty key");
  // The overridden value is validated like any other.
  EXPECT_NE(error({"effects.track_model=elastic"})
                .find("scene.yaml: effects.track_model: must be one of rigid, rigid_fe, flexible, got 'elastic'"),
            std::string::npos);
  EXPECT_NE(error({"effects.flange_contat=true"}).find("effects.flange_contat: unknown key"), std::string::npos);
}

TEST(Scene, AKeyGivenTwiceIsRefusedNamingBothLines) {
  // yaml-cpp would keep the first value without a word.
  const std::string twice = replaced(kBase, "  speed: 30.0\n", "  speed: 30.0\n  speed: 10.0\n");
  const std::string e = errorOf(twice);
  EXPECT_NE(e.find("scene.yaml: vehicle.speed: given twice (lines "), std::string::npos) << e;
  // Inside a list item too.
  const std::string in_list =
      replaced(kBase, "{type: straight, length: 50.0}", "{type: straight, length: 50.0, length: 5}");
  EXPECT_NE(errorOf(in_list).find("track.segments[0].length: given twice"), std::string::npos) << errorOf(in_list);
}

TEST(Scene, AFlowMapOverrideWithoutSpacesReadsAsWritten) {
  // scene.launch's comment writes solver.end={time:1.0}; YAML alone would read the key "time:1.0".
  const Scene s = loadSceneText(kBase, "scene.yaml", kData, {"solver.end={time:1.0}"});
  EXPECT_EQ(s.solver.end.kind, EndKind::kTime);
  EXPECT_DOUBLE_EQ(s.solver.end.value, 1.0);
  EXPECT_EQ(loadSceneText(kBase, "scene.yaml", kData, {"output.bag='a:b.bag'"}).output.bag, "a:b.bag");
}

TEST(Scene, TrackLengthsThatWouldOverflowACountAreRefused) {
  const std::string e = errorOf(replaced(kBase, "length: 50.0", "length: 1e308"));
  EXPECT_NE(e.find("track.segments[0].length: must be at most 1e+06 m"), std::string::npos) << e;
}
