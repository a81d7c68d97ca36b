// Benchmark (not a test): wall time of one co-simulation track step (CosimTrack::step) with the 8 wheels of
// the paper's coach on the paper's 500 m track (config/scenes/paper_demo.yaml): rigid_fe, and flexible with
// the semi-implicit (default) and the explicit coupling. The wheels roll at the scene's speed, 50
// micrometres into the rails. Prints build time, the median, 90th and 99th percentile and the largest step
// time, the mean after the first integrated step and that first step's time (steps where wheels reach new
// rail nodes solve their influence columns: all of them in the first step), and for the semi-implicit
// coupling the influence solves and Newton iterations per step.
//   bench_cosim_track [steps]   (default 500)
#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <rail_contact/profile.hpp>
#include <rail_core/scene_loader.hpp>

#include "rail_track_node/cosim_track.hpp"

namespace rt = rail::track;
namespace rc = rail::contact;
namespace cc = rail::core::coupling;
using Clock = std::chrono::steady_clock;

static std::string configDir() {
#ifdef RAILSIM_CONFIG_DIR
  return RAILSIM_CONFIG_DIR;
#else
  return "config";
#endif
}

static void run(rail::core::Scene scene, rail::core::TrackModel model, rt::CosimCoupling coupling, int steps) {
  scene.effects.track_model = model;
  const Clock::time_point t0 = Clock::now();
  rt::CosimTrackOptions options;
  options.coupling = coupling;
  rt::CosimTrack track(scene, options);
  const double build = std::chrono::duration<double>(Clock::now() - t0).count();
  const double V = scene.vehicle.speed, r0 = scene.vehicle.nominal_radius, h = scene.solver.track_step;
  const double taping_y = 0.5 * scene.vehicle.back_to_back + rc::flangeBackY(rc::makeS1002());
  const double offsets[4] = {0.0, 2.7, 16.4, 19.1};  // paper coach wheelsets behind the leading one, m
  cc::WheelStateFrame frame(8);
  cc::WrenchFrame out(8);
  std::vector<double> times;
  times.reserve(static_cast<std::size_t>(steps));
  double fz = 0.0;
  for (int k = 0; k <= steps; ++k) {
    frame.count = 8;
    frame.step = static_cast<std::uint64_t>(k);
    frame.time = k * h;
    for (int i = 0; i < 8; ++i) {
      cc::WheelState& w = frame.wheels[static_cast<std::size_t>(i)];
      w.id = static_cast<std::uint32_t>(i);
      const double s = scene.vehicle.start_arc_length - offsets[i / 2] + V * k * h;
      w.arc_length = s;
      w.p_wheel_in_world = Eigen::Vector3d(s, i % 2 == 0 ? taping_y : -taping_y, r0 - 5e-5);
      w.q_wheelset_to_world = Eigen::Quaterniond::Identity();
      w.v_wheel_in_world = Eigen::Vector3d(V, 0.0, 0.0);
      w.omega_wheelset_in_world = Eigen::Vector3d(0.0, V / r0, 0.0);
    }
    const Clock::time_point a = Clock::now();
    track.step(frame, out);
    const double dt = std::chrono::duration<double>(Clock::now() - a).count();
    if (k > 0) times.push_back(dt);
    fz += out.wheels[0].f_wheel_in_world.z();
  }
  // Mean over the steps after the first integrated one (which solves the first influence columns).
  double mean = 0.0;
  for (std::size_t i = 1; i < times.size(); ++i) mean += times[i];
  mean /= static_cast<double>(times.size() - 1);
  const double first = times.front();
  std::sort(times.begin(), times.end());
  const int dofs = track.sceneTrack() ? track.sceneTrack()->model.system.size() : 0;
  const char* name = model == rail::core::TrackModel::kRigidFe        ? "rigid_fe"
                     : coupling == rt::CosimCoupling::kSemiImplicit ? "flexible semi-implicit"
                                                                     : "flexible explicit";
  std::printf("%-22s free DOFs %6d  build %.2f s  step median %.3f ms  mean %.3f ms  p90 %.3f ms  p99 %.3f ms  "
              "first %.1f ms  (%d steps, mean Fz wheel 0 %.0f N)\n",
              name, dofs, build, 1e3 * times[times.size() / 2], 1e3 * mean, 1e3 * times[times.size() * 9 / 10],
              1e3 * times[times.size() * 99 / 100], 1e3 * first, steps, fz / (steps + 1));
  if (track.flexible() && coupling == rt::CosimCoupling::kSemiImplicit)
    std::printf("%-22s influence window %d DOFs, %.3f influence solves and %.2f Newton iterations per step\n", "",
                track.influenceWindow(), static_cast<double>(track.influenceSolves()) / steps,
                static_cast<double>(track.newtonIterations()) / steps);
}

int main(int argc, char** argv) {
  const int steps = argc > 1 ? std::max(10, std::atoi(argv[1])) : 500;
  const rail::core::Scene scene = rail::core::load_scene_file(configDir() + "/scenes/paper_demo.yaml");
  run(scene, rail::core::TrackModel::kRigidFe, rt::CosimCoupling::kExplicit, steps);
  run(scene, rail::core::TrackModel::kFlexible, rt::CosimCoupling::kSemiImplicit, steps);
  run(scene, rail::core::TrackModel::kFlexible, rt::CosimCoupling::kExplicit, steps);
  return 0;
}
