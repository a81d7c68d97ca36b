// Loading, validating, printing and summarising scenes. ROS-free.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "rail_core/scene.hpp"

namespace rail::core {

// A scene (or one of its data files) that cannot be used. The message names the file and the field:
//   "scene.yaml: track.segments[2].radius: must be positive, got -500 (line 23)".
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The rules of the solver settings, stated once: the loader reports a broken one with the file, field and
// line; a core given settings built in code (not loaded) checks them again through the same function. Each
// returns "" when the value obeys, else what is wrong ("must be between ..., got ...").
std::string trackStepRule(double track_step);                                // solver.track_step, s
std::string vehicleMaxStepRule(double vehicle_max_step, double track_step);  // in co-simulation, s
std::string windowShiftRule(double shift);                                   // solver.track_window.shift, m

// Changes to a scene applied before it is read, each "dotted.key=value" with a YAML value, e.g.
// "effects.track_model=flexible", "solver.end={time: 1.5}", "output.bag=run.bag". Keys of maps are
// created when absent; a key that walks through a non-map (e.g. into a list) is refused; "key=" with
// nothing after '=' changes nothing (a launch argument left empty). The scene
// then validates as if its file said so (the summary and the hash include the change). Used by the
// three-run launch files and the runner to run one scene with each track model.
using SceneOverrides = std::vector<std::string>;

// Splits a whitespace-separated list of overrides (the launch files' `overrides` argument); spaces inside
// quotes or a YAML flow collection ({...}, [...]) do not separate.
SceneOverrides splitOverrides(const std::string& text);

// Reads, validates and resolves a scene file. Throws SceneError.
Scene loadSceneFile(const std::string& path, const SceneOverrides& overrides = {});

// The same from the file's text (e.g. handed over the ROS parameter server): `file` names the scene in
// messages and `base_dir` is where relative data-file paths start.
Scene loadSceneText(const std::string& text, const std::string& file, const std::string& base_dir,
                    const SceneOverrides& overrides = {});

// The same, for a scene handed over as text with the path it was read from (relative data files are taken
// from that path's directory).
Scene loadSceneHandedOver(const std::string& text, const std::string& file, const SceneOverrides& overrides = {});

// Why `topic` cannot be recorded by a run of `scene` (the effect or track model it needs), or "" when it can.
// The loader refuses output.topics by this rule.
std::string topicNeeds(const Scene& scene, const std::string& topic);

// The topics a run of `scene` can record (topicNeeds empty), in the order of the known topics.
std::vector<std::string> recordableTopics(const Scene& scene);

// What a valid scene asks for more finely than it says: one line per setting too coarse for an effect that
// is on (e.g. a track step too long for an impact's first peak), naming the setting, its value and the value
// wanted. describe() lists them as "warning:" lines; empty when nothing is too coarse.
std::vector<std::string> sceneWarnings(const Scene& scene);

// The fully resolved scene as YAML (every default filled in). Loading this text again gives the same
// scene (same hash).
std::string toYaml(const Scene& scene);

// Which process a summary is for.
enum class Role { kVehicle, kTrack, kValidator };

// What a run of this scene simulates, from one node's side: the effects that are on and the components
// it builds. Human-readable, several lines.
std::string describe(const Scene& scene, Role role);

// 64-bit FNV-1a, for the scene hash.
std::uint64_t fnv1a64(const std::string& bytes, std::uint64_t seed = 14695981039346656037ULL);

}  // namespace rail::core
