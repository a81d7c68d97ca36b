// railsim_validate_scene: checks a scene without starting ROS.
//   railsim_validate_scene <scene.yaml> [--set key=value ...] [--summary | --hash | --plan | --topics]
// Prints the fully resolved scene and exits 0, or prints the one error naming the file and field and
// exits 1. --summary: what a run simulates; --hash: the scene hash; --plan: which launch file runs it
// (vehicle_standalone, cosim or track_standalone); --topics: the topics a run of it can record (one line,
// comma-separated; the loader's own rule, recordableTopics). --set applies an override (scene_loader.hpp), as the
// launch files' `overrides` argument does. `railsim_validate_scene --split "<overrides>"` prints the
// overrides of such an argument one per line.
#include <cstdio>
#include <cstring>
#include <iostream>

#include <rail_contact/tool_args.hpp>

#include "rail_core/scene_loader.hpp"

namespace {
const char* const kUsage =
    "usage: railsim_validate_scene <scene.yaml> [--set key=value ...] [--summary | --hash | --plan | --topics]\n"
    "  prints the resolved scene (exit 0) or the error (exit 1)\n";
}  // namespace

int main(int argc, char** argv) {
  const char* path = nullptr;
  bool summary = false, hash_only = false, plan = false, topics = false;
  rail::core::SceneOverrides overrides;
  if (argc == 3 && std::strcmp(argv[1], "--split") == 0) {
    // One override per line, as the launch files' `overrides` argument splits them (for scripts).
    for (const std::string& o : rail::core::splitOverrides(argv[2])) std::cout << o << "\n";
    return 0;
  }
  if (rail::tools::startTool(argc, argv, kUsage, rail::tools::kOwnOptions)) return 0;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--set") == 0) {
      if (i + 1 >= argc) {
        std::cerr << "railsim_validate_scene: --set needs key=value\n";
        return 1;
      }
      overrides.push_back(argv[++i]);
    } else if (std::strcmp(argv[i], "--summary") == 0) {
      summary = true;
    } else if (std::strcmp(argv[i], "--plan") == 0) {
      plan = true;
    } else if (std::strcmp(argv[i], "--topics") == 0) {
      topics = true;
    } else if (std::strcmp(argv[i], "--hash") == 0) {
      hash_only = true;
    } else if (path == nullptr) {
      path = argv[i];
    } else {
      std::cerr << "railsim_validate_scene: unexpected argument '" << argv[i] << "'\n";
      return 1;
    }
  }
  if (path == nullptr) {
    std::cerr << kUsage;
    return 1;
  }
  try {
    const rail::core::Scene scene = rail::core::loadSceneFile(path, overrides);
    if (plan) {
      std::cout << (!scene.has_vehicle     ? "track_standalone"
                    : scene.cosimulation() ? "cosim"
                                           : "vehicle_standalone")
                << "\n";
    } else if (topics) {
      const std::vector<std::string> names = rail::core::recordableTopics(scene);
      for (std::size_t i = 0; i < names.size(); ++i) std::cout << (i > 0 ? ", " : "") << names[i];
      std::cout << "\n";
    } else if (hash_only) {
      std::printf("%016llx\n", static_cast<unsigned long long>(scene.hash));
    } else if (summary) {
      std::cout << rail::core::describe(scene, rail::core::Role::kValidator);
    } else {
      std::cout << "# resolved scene, hash " << std::hex << scene.hash << std::dec << "\n" << rail::core::toYaml(scene);
    }
    return 0;
  } catch (const rail::core::SceneError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
}
