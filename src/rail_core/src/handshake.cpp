#include "rail_core/handshake.hpp"

#include <cmath>
#include <cstdio>

#include <rail_contact/format.hpp>

namespace rail::core {

using contact::formatNumber;

HandshakeInfo handshakeInfo(const Scene& scene, const std::string& node) {
  HandshakeInfo h;
  h.node = node;
  h.scene_file = scene.file;
  h.scene_hash = scene.hash;
  h.wheel_count = static_cast<std::uint32_t>(scene.wheelCount());
  h.track_step = scene.solver.track_step;
  h.transport = toString(scene.solver.transport);
  return h;
}

namespace {
std::string hex(std::uint64_t v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(v));
  return buf;
}
}  // namespace

std::string compareHandshake(const HandshakeInfo& mine, const HandshakeInfo& theirs) {
  std::string diffs;
  auto add = [&](const std::string& what, const std::string& a, const std::string& b) {
    diffs += (diffs.empty() ? "" : "; ") + what + " " + a + " here, " + b + " there";
  };
  if (mine.wheel_count != theirs.wheel_count)
    add("wheel_count", std::to_string(mine.wheel_count), std::to_string(theirs.wheel_count));
  if (std::abs(mine.track_step - theirs.track_step) > 1e-15)
    add("track_step", formatNumber(mine.track_step) + " s", formatNumber(theirs.track_step) + " s");
  if (mine.transport != theirs.transport) add("transport", mine.transport, theirs.transport);
  if (mine.scene_hash != theirs.scene_hash)
    add("scene_hash", hex(mine.scene_hash) + " (" + mine.scene_file + ")",
        hex(theirs.scene_hash) + " (" + theirs.scene_file + ")");
  if (diffs.empty()) return {};
  return "scene differs from " + theirs.node + "'s: " + diffs;
}

}  // namespace rail::core
