// Fixtures shared by the packages' unit tests: where the repository's config/ folder is, and scenes loaded
// from it or written in the test as YAML text (their relative data paths then taken from config/scenes/, as
// if the text were a file there). ROS-free; header only.
#pragma once

#include <string>

#include "rail_core/scene_loader.hpp"

namespace rail::core::fixtures {

// The repository's config/ folder: RAILSIM_CONFIG_DIR when the test's CMake defines it, else found from this
// header's own path in the source tree.
inline std::string configDir() {
#ifdef RAILSIM_CONFIG_DIR
  return RAILSIM_CONFIG_DIR;
#else
  const std::string here = __FILE__;
  return here.substr(0, here.rfind("/src/rail_core/")) + "/config";
#endif
}

// config/scenes/<file>
inline std::string scenePath(const std::string& file) { return configDir() + "/scenes/" + file; }

// A scene of config/scenes/, loaded and validated as the nodes load it.
inline Scene loadConfigScene(const std::string& file) { return loadSceneFile(scenePath(file)); }

// A scene written in the test; `name` stands for its file name in messages.
inline Scene sceneFromText(const std::string& yaml, const std::string& name = "test.yaml") {
  return loadSceneText(yaml, name, configDir() + "/scenes");
}

}  // namespace rail::core::fixtures
