// Benchmark (not a test): cost of the moving track window against the full-length FE track, on the paper's
// 500 m scene (config/scenes/paper_demo.yaml: straight, transition, R = 500 m curve) and on a 5 km straight
// line with the same track data. The coach's 8 wheel loads (72.9 kN per wheel, wheelsets 0, 2.7, 19.0 and
// 21.7 m behind the leading one, paper Table 3) roll at the scene's speed with the scene's Newmark step.
// Prints the build time, the median time per Newmark step (loads re-placed each step), and the median
// time per window move (split into moves that rebuild and factorise the matrices and moves that reuse them).
//   bench_track_window [steps] [full_5km_steps]   (defaults 300 and 20)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <rail_core/scene_loader.hpp>

#include "rail_contact/tool_args.hpp"
#include "rail_core/testing/fixtures.hpp"
#include "rail_track_node/newmark.hpp"
#include "rail_track_node/scene_track.hpp"
#include "rail_track_node/track_simulator.hpp"
#include "rail_track_node/track_window.hpp"

namespace rt = rail::track;
using Clock = rail::tools::BenchClock;
using rail::tools::median;
using rail::tools::secondsSince;

namespace {
const char* const kUsage =
    "usage: bench_track_window [steps] [full_5km_steps]\n"
    "Moving track window against the full-length FE track on the paper scene and a 5 km straight: build\n"
    "time, median step, median window move. Defaults 300 and 20.\n";

constexpr double kOffsets[4] = {0.0, 2.7, 19.0, 21.7};  // m behind the leading wheelset (paper Table 3)
constexpr double kWheelLoad = 72.9e3;                   // N per wheel

void placeCoach(const rt::TrackMesh& mesh, const rt::TrackData& data, double s_front, rt::NodalLoads& loads) {
  loads.clear();
  const double arm = rt::SceneTrackOptions().rail_height - data.layout.rail_centroid_height;
  for (double off : kOffsets)
    for (int r = 0; r < 2; ++r)
      rt::addRailHeadLoad(mesh, data.layout.rail_inclination, arm, r, s_front - off, kWheelLoad, 0.0, loads);
}

// Full-length model: build (mesh + assembly), K_eff factorisation, median step.
void benchFull(const rail::core::Scene& scene, double s_front0, int steps) {
  Clock::time_point t0 = Clock::now();
  const rt::SceneTrack track = rt::buildSceneTrack(scene);
  const double t_build = secondsSince(t0);
  const double h = scene.solver.track_step;
  t0 = Clock::now();
  rt::NewmarkIntegrator integrator(track.model.system, h, true);
  const double t_factor = secondsSince(t0);
  const int n = track.model.system.size();
  rt::NewmarkState st;
  st.d = Eigen::VectorXd::Zero(n);
  st.v = Eigen::VectorXd::Zero(n);
  st.a = Eigen::VectorXd::Zero(n);
  rt::NodalLoads loads(24 * 4 + 1);
  std::vector<double> times;
  for (int k = 1; k <= steps; ++k) {
    const Clock::time_point a = Clock::now();
    placeCoach(track.model.mesh, track.model.data, s_front0 + scene.vehicle.speed * k * h, loads);
    integrator.step(st, loads);
    times.push_back(secondsSince(a));
  }
  std::printf("  full    %7.0f m  free DOFs %7d  build %6.2f s  factorise %6.2f s  step median %8.3f ms  (%d steps)\n",
              track.model.mesh.n_sleepers * track.model.mesh.sleeper_spacing, n, t_build, t_factor, 1e3 * median(times),
              steps);
}

// Window: build, median step over `steps` steps rolling, then moves along [s_from, s_to] one shift at a time.
void benchWindow(const rail::core::Scene& scene, const rt::TrackWindowSettings& set, double s_front0, int steps,
                 double s_from, double s_to) {
  Clock::time_point t0 = Clock::now();
  rt::TrackWindowSettings own = set;
  own.track_step = scene.solver.track_step;
  rt::TrackWindow win(rt::resolveTrackLine(scene), own, s_front0 - set.vehicle_length, s_front0);
  const double t_build = secondsSince(t0);
  const double h = win.trackStep();
  rt::NodalLoads loads(24 * 4 + 1);
  std::vector<double> times;
  for (int k = 1; k <= steps; ++k) {
    const Clock::time_point a = Clock::now();
    const double s_front = s_front0 + scene.vehicle.speed * k * h;
    win.follow(s_front - set.vehicle_length, s_front);
    placeCoach(win.mesh(), win.data(), s_front, loads);
    win.step(loads);
    times.push_back(secondsSince(a));
  }
  // Moves: the vehicle jumps ahead by one shift distance at a time.
  std::vector<double> rebuild, reuse;
  const double shift = win.shiftBays() * win.data().layout.sleeper_spacing;
  for (double s = s_from; s <= s_to; s += shift) {
    const int before = win.stats().rebuilds;
    if (!win.follow(s - set.vehicle_length, s)) continue;
    (win.stats().rebuilds > before ? rebuild : reuse).push_back(win.stats().last_shift_s);
  }
  const double steps_per_shift = shift / (scene.vehicle.speed * h);
  const double worst_shift = std::max(median(rebuild), median(reuse));
  std::printf(
      "  window  %5.1f m  free DOFs %7d  build %6.2f s  step median %8.3f ms  move median: rebuild %7.1f ms "
      "(%zu), reuse %6.1f ms (%zu); a move every %.0f steps: <= %.3f ms per step amortised\n",
      win.bays() * win.data().layout.sleeper_spacing, win.model().system.size(), t_build, 1e3 * median(times),
      1e3 * median(rebuild), rebuild.size(), 1e3 * median(reuse), reuse.size(), steps_per_shift,
      1e3 * (median(times) + worst_shift / steps_per_shift));
}

}  // namespace

int main(int argc, char** argv) {
  if (rail::tools::startTool(argc, argv, kUsage, 2)) return 0;
  const int steps = static_cast<int>(rail::tools::positionalNumber(argc, argv, 1, 300, 10, kUsage));
  const int full_long_steps = static_cast<int>(rail::tools::positionalNumber(argc, argv, 2, 20, 0, kUsage));
  rt::TrackWindowSettings set;
  set.vehicle_length = kOffsets[3];

  const rail::core::Scene paper =
      rail::core::loadSceneFile(rail::core::fixtures::configDir() + "/scenes/paper_demo.yaml");
  std::printf("paper scene (%s): %.0f m, h = %g s, %.2f m/s; window behind %.1f m, ahead %.1f m, shift %.1f m\n",
              paper.file.c_str(), paper.track.length(), paper.solver.track_step, paper.vehicle.speed, set.behind,
              set.ahead, set.shift);
  benchWindow(paper, set, paper.vehicle.start_arc_length, steps, 60.0, 480.0);
  benchFull(paper, paper.vehicle.start_arc_length, steps);

  // 5 km straight line, same data, step and speed.
  const std::string text =
      "name: line_5km\ntrack:\n  gauge: 1.668\n  cant_reference_width: 1.733\n"
      "  rail_inclination: 1/20\n  data: ../track/paper_track.yaml\n  segments:\n"
      "    - {type: straight, length: 5000.0}\n"
      "vehicle:\n  data: ../vehicle/paper_coach.yaml\n  start_arc_length: 2500.0\n"
      "  speed: " +
      std::to_string(paper.vehicle.speed) +
      "\n  back_to_back: 1.592\neffects:\n  track_model: flexible\nsolver:\n  track_step: " +
      std::to_string(paper.solver.track_step) + "\n";
  const rail::core::Scene line =
      rail::core::loadSceneText(text, "line_5km.yaml", rail::core::fixtures::configDir() + "/scenes");
  std::printf("5 km straight line: h = %g s, %.2f m/s\n", line.solver.track_step, line.vehicle.speed);
  benchWindow(line, set, 2500.0, steps, 2500.0, 2800.0);
  if (full_long_steps > 0) benchFull(line, 2500.0, full_long_steps);
  return 0;
}
