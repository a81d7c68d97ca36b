// Benchmark (not a test): wall time of one co-simulation track step (CosimTrack::step) with the 8 wheels of
// the paper's coach on the paper's 500 m track (config/scenes/paper_demo.yaml): rigid_fe, and flexible with
// the semi-implicit (default) and the explicit coupling. The wheels roll at the scene's speed, 50
// micrometres into the rails. Prints build time, the median, 90th and 99th percentile and the largest step
// time, the mean after the first integrated step and that first step's time (steps where wheels reach new
// rail nodes solve their influence columns: all of them in the first step), and for the semi-implicit
// coupling the influence solves and Newton iterations per step.
// Then the moving track window (solver.track_window enabled, the scene's margins): the same steps against
// the full-length semi-implicit run, and two longer windowed runs (window_steps each) that cross window
// moves, one on the straight (moves reuse the factor) and one on the R = 500 m curve (every move
// refactorises): the median step without moves, the move steps (move + the influence columns solved
// again) and the moves' own time.
//   bench_cosim_track [steps] [window_steps] [cost 0|1] [solve_beside 0|1] [factor 0|1|2|3]
// (defaults 500, 20000 and 0; window_steps 0 skips the window runs; cost 1 passes a cost clock to the track,
// as the node does, so that the clock's own overhead can be measured against cost 0)
#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <rail_contact/profile.hpp>
#include <rail_core/cost_profile.hpp>
#include <rail_core/geometry_builder.hpp>
#include <rail_core/scene_loader.hpp>

#include "rail_contact/tool_args.hpp"
#include "rail_core/testing/fixtures.hpp"
#include "rail_track_node/cosim_track.hpp"

namespace rt = rail::track;
namespace rc = rail::contact;
namespace cc = rail::core::coupling;
using Clock = std::chrono::steady_clock;

namespace {
const char* const kUsage =
    "usage: bench_cosim_track [steps] [window_steps] [cost_clock 0|1] [solve_beside 0|1] [factor 0|1|2|3]\n"
    "Wall time of one co-simulation track step with the paper coach's 8 wheels on the paper scene: rigid_fe,\n"
    "flexible (semi-implicit and explicit coupling), and the moving track window (straight and curve runs\n"
    "of window_steps each). Defaults: 500, 20000, 0 (cost clock off), 1 (the next step's solve on a second\n"
    "thread), 0 (factor: 0 simplicial, 1 CHOLMOD's supernodal solve (the reference), 2 simplicial in two\n"
    "parts, each solve shared by both threads, 3 in blocks in two parts, the co-simulation's default).\n";

}  // namespace

// First to last wheelset of the paper coach (Table 3), m: the track window's vehicle length.
constexpr double kCoachWheelSpan = 21.7;

// The coach's 8 wheels at step k: wheelsets at s_front - offsets along the design track (track frame, cant
// included), rolling at V, 50 micrometres into the rails.
static void fillFrame(const rail::core::Scene& scene, const rc::TrackGeometry& geo, double s_front0, int k,
                      cc::WheelStateFrame& frame) {
  const double V = scene.vehicle.speed, r0 = scene.vehicle.nominal_radius, h = scene.solver.track_step;
  const double taping_y = 0.5 * scene.vehicle.back_to_back + rc::kTapingLineFromFlangeBack;
  const double offsets[4] = {0.0, 2.7, 19.0,
                             kCoachWheelSpan};  // paper coach (Table 3) wheelsets behind the leading one, m
  frame.count = 8;
  frame.step = static_cast<std::uint64_t>(k);
  frame.time = k * h;
  rc::TrackPoint tp;
  for (int i = 0; i < 8; ++i) {
    cc::WheelState& w = frame.wheels[static_cast<std::size_t>(i)];
    w.id = static_cast<std::uint32_t>(i);
    const double s = s_front0 - offsets[i / 2] + V * k * h;
    geo.centre(s, tp);
    w.arc_length = s;
    w.p_wheel_in_world =
        tp.p_center_in_world + tp.R_track_to_world * Eigen::Vector3d(0.0, i % 2 == 0 ? taping_y : -taping_y, r0 - 5e-5);
    w.R_wheelset_to_world = tp.R_track_to_world;
    w.v_wheel_in_world = V * tp.R_track_to_world.col(0);
    w.omega_wheelset_in_world = tp.R_track_to_world.col(1) * (V / r0) + tp.R_track_to_world.col(2) * (V * tp.curvature);
  }
}

// Windowed semi-implicit run of `steps` steps from s_front0: per-step times split into move steps and the
// others.
static bool g_cost = false;                                            // pass a cost clock to the track (argument 3)
static bool g_beside = true;                                           // CosimTrackOptions::solve_beside (argument 4)
static rt::CholeskyLayout g_layout = rt::CholeskyLayout::kSimplicial;  // argument 5

static void printClock(const rail::core::CostClock& clock, long steps) {
  using CC = rail::core::CostClock;
  const double us = 1e6 / static_cast<double>(steps);
  std::printf(
      "%-22s per step (us): contact_detection %.1f, contact_forces %.1f, track_rhs %.1f, track_solve %.1f%s, "
      "track_solve_wait %.1f; %.1f creep evaluations\n",
      "", us * clock.contact.detection_seconds, us * clock.contact.forces_seconds, us * clock.seconds[CC::kTrackRhs],
      us * clock.seconds[CC::kTrackSolve], clock.track_solve_beside ? " (beside)" : "",
      us * clock.seconds[CC::kTrackSolveWait],
      static_cast<double>(clock.contact.creep_evaluations) / static_cast<double>(steps));
}

// The solves of the window's K_eff alone (warm, median of `repeats`): the step's solve and the influence
// columns of one rail node, with the simplicial factor (six columns one by one and in one pass) and with
// CHOLMOD's supernodal solve.
static void benchWindowSolves(const rt::TrackWindow& w, double h, int repeats) {
  const rt::LinearSystem& sys = w.model().system;
  const int n = sys.size();
  Eigen::VectorXd b = Eigen::VectorXd::Random(n), x(n);
  Eigen::MatrixXd cols(n, 6);
  const rt::TrackMesh& mesh = w.mesh();
  const int node = mesh.rail_nodes[0][mesh.rail_nodes[0].size() / 2];
  int dofs[6];
  for (int j = 0; j < 6; ++j) dofs[j] = mesh.dofIndex(node, j);
  auto median = [&](auto&& f) {
    std::vector<double> t;
    for (int r = 0; r < repeats; ++r) {
      const Clock::time_point a = Clock::now();
      f();
      t.push_back(std::chrono::duration<double>(Clock::now() - a).count());
    }
    std::sort(t.begin(), t.end());
    return 1e6 * t[t.size() / 2];
  };
  for (rt::CholeskyLayout layout : {rt::CholeskyLayout::kSimplicial, rt::CholeskyLayout::kSupernodal,
                                    rt::CholeskyLayout::kSimplicialTwoParts, rt::CholeskyLayout::kBlockedTwoParts}) {
    rt::NewmarkIntegrator integ(sys, h, false, nullptr, 0, layout);
    const double one = median([&] { integ.solveEffective(b, x); });
    const double six = median([&] {
      for (int j = 0; j < 6; ++j) integ.solveEffectiveColumns(dofs + j, 1, cols);
    });
    const double many = median([&] { integ.solveEffectiveColumns(dofs, 6, cols); });
    std::printf(
        "%-22s K_eff solves, %s factor (nnz(L) %.0f), median of %d, warm: one right-hand side %.1f us; a rail "
        "node's 6 influence columns one by one %.1f us, in one pass %.1f us\n",
        "window", rt::choleskyLayoutName(layout), integ.factor().factorNonZeros(), repeats, one, six, many);
  }
}

static void runWindow(rail::core::Scene scene, double s_front0, int steps, const char* label) {
  scene.effects.track_model = rail::core::TrackModel::kFlexible;
  scene.solver.track_window.enabled = true;
  scene.vehicle.start_arc_length = s_front0;
  const Clock::time_point t0 = Clock::now();
  rail::core::CostClock clock;
  rt::CosimTrackOptions options;
  options.window.vehicle_length = kCoachWheelSpan;
  options.solve_beside = g_beside;
  options.factor_layout = g_layout;
  if (g_cost) options.cost = &clock;
  rt::CosimTrack track(rt::resolveCosimTrack(scene), options);
  const double build = std::chrono::duration<double>(Clock::now() - t0).count();
  cc::WheelStateFrame frame(8);
  cc::WrenchFrame out(8);
  std::vector<double> plain, moving;
  plain.reserve(static_cast<std::size_t>(steps));
  long solves_after_first = 0;
  int bad = 0;
  for (int k = 0; k <= steps; ++k) {
    fillFrame(scene, track.geometry(), s_front0, k, frame);
    const int moves = track.windowMoves();
    const long solves = track.influenceSolves();
    const Clock::time_point a = Clock::now();
    if (track.step(frame, out) != rt::CosimStepStatus::kOk) ++bad;
    const double dt = std::chrono::duration<double>(Clock::now() - a).count();
    if (k > 1) solves_after_first += track.influenceSolves() - solves;
    if (k == 0) continue;
    (track.windowMoves() != moves ? moving : plain).push_back(dt);
  }
  double total = 0.0;
  for (double t : plain) total += t;
  for (double t : moving) total += t;
  std::sort(plain.begin(), plain.end());
  std::sort(moving.begin(), moving.end());
  const rt::TrackWindow& w = *track.trackWindow();
  std::printf(
      "%-22s %s: window %.1f m (%d free DOFs), build %.2f s, %d steps (%.2f m): step median %.3f ms, "
      "p99 %.3f ms, mean over all steps %.3f ms; %d moves (%d refactorised), move steps median %.1f ms "
      "(max %.1f ms), moves alone %.1f ms each; %.3f influence solves per step after the first, %.2f Newton "
      "iterations per step; %d refused\n",
      "window semi-implicit", label, w.sEnd() - w.sBegin(), static_cast<int>(w.state().d.size()), build, steps,
      scene.vehicle.speed * steps * scene.solver.track_step, 1e3 * plain[plain.size() / 2],
      1e3 * plain[plain.size() * 99 / 100], 1e3 * total / steps, track.windowMoves(), track.windowRebuilds(),
      moving.empty() ? 0.0 : 1e3 * moving[moving.size() / 2], moving.empty() ? 0.0 : 1e3 * moving.back(),
      track.windowMoves() > 0 ? 1e3 * track.windowMoveSeconds() / track.windowMoves() : 0.0,
      static_cast<double>(solves_after_first) / std::max(1, steps - 1),
      static_cast<double>(track.newtonIterations()) / steps, bad);
  if (g_cost) printClock(clock, steps);
  if (s_front0 == scene.vehicle.start_arc_length) benchWindowSolves(w, scene.solver.track_step, 1000);
}

static void run(rail::core::Scene scene, rail::core::TrackModel model, rt::CosimCoupling coupling, int steps,
                bool window = false) {
  scene.effects.track_model = model;
  scene.solver.track_window.enabled = window;
  const Clock::time_point t0 = Clock::now();
  rail::core::CostClock clock;
  rt::CosimTrackOptions options;
  options.coupling = coupling;
  options.solve_beside = g_beside;
  options.factor_layout = g_layout;
  if (g_cost) options.cost = &clock;
  options.window.vehicle_length = kCoachWheelSpan;
  rt::CosimTrack track(rt::resolveCosimTrack(scene), options);
  const double build = std::chrono::duration<double>(Clock::now() - t0).count();
  cc::WheelStateFrame frame(8);
  cc::WrenchFrame out(8);
  std::vector<double> times;
  times.reserve(static_cast<std::size_t>(steps));
  double fz = 0.0;
  for (int k = 0; k <= steps; ++k) {
    fillFrame(scene, track.geometry(), scene.vehicle.start_arc_length, k, frame);
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
  const int dofs = track.state() ? static_cast<int>(track.state()->d.size()) : 0;
  const char* name = model == rail::core::TrackModel::kRigidFe ? "rigid_fe"
                     : window
                         ? (coupling == rt::CosimCoupling::kSemiImplicit ? "window semi-implicit" : "window explicit")
                     : coupling == rt::CosimCoupling::kSemiImplicit ? "flexible semi-implicit"
                                                                    : "flexible explicit";
  std::printf(
      "%-22s free DOFs %6d  build %.2f s  step median %.3f ms  mean %.3f ms  p90 %.3f ms  p99 %.3f ms  "
      "first %.1f ms  (%d steps, mean Fz wheel 0 %.0f N)\n",
      name, dofs, build, 1e3 * times[times.size() / 2], 1e3 * mean, 1e3 * times[times.size() * 9 / 10],
      1e3 * times[times.size() * 99 / 100], 1e3 * first, steps, fz / (steps + 1));
  if (track.flexible() && coupling == rt::CosimCoupling::kSemiImplicit)
    std::printf("%-22s influence window %d DOFs, %.3f influence solves and %.2f Newton iterations per step\n", "",
                track.influenceWindow(), static_cast<double>(track.influenceSolves()) / steps,
                static_cast<double>(track.newtonIterations()) / steps);
  if (g_cost && track.flexible()) printClock(clock, steps);
}

int main(int argc, char** argv) {
  if (rail::tools::startTool(argc, argv, kUsage, 5)) return 0;
  const int steps = static_cast<int>(rail::tools::positionalNumber(argc, argv, 1, 500, 10, kUsage));
  const int window_steps = static_cast<int>(rail::tools::positionalNumber(argc, argv, 2, 20000, 0, kUsage));
  g_cost = rail::tools::positionalNumber(argc, argv, 3, 0, 0, kUsage) != 0;
  g_beside = rail::tools::positionalNumber(argc, argv, 4, 1, 0, kUsage) != 0;
  const int factor = static_cast<int>(rail::tools::positionalNumber(argc, argv, 5, 0, 0, kUsage));
  if (factor > 3) {
    std::fprintf(stderr, "bench_cosim_track: factor must be 0, 1, 2 or 3, got %d\n%s", factor, kUsage);
    return 2;
  }
  const rt::CholeskyLayout layouts[4] = {rt::CholeskyLayout::kSimplicial, rt::CholeskyLayout::kSupernodal,
                                         rt::CholeskyLayout::kSimplicialTwoParts, rt::CholeskyLayout::kBlockedTwoParts};
  g_layout = layouts[factor];
  std::printf("cost clock %s, next solve %s, %s factor\n", g_cost ? "on" : "off",
              g_beside ? "beside (second thread)" : "in the step", rt::choleskyLayoutName(g_layout));
  const rail::core::Scene scene =
      rail::core::loadSceneFile(rail::core::fixtures::configDir() + "/scenes/paper_demo.yaml");
  run(scene, rail::core::TrackModel::kRigidFe, rt::CosimCoupling::kExplicit, steps);
  run(scene, rail::core::TrackModel::kFlexible, rt::CosimCoupling::kSemiImplicit, steps);
  run(scene, rail::core::TrackModel::kFlexible, rt::CosimCoupling::kExplicit, steps);
  run(scene, rail::core::TrackModel::kFlexible, rt::CosimCoupling::kSemiImplicit, steps, true);
  if (window_steps > 0) {
    std::printf("track window: %.1f m behind, %.1f m ahead, shift %.1f m (scene defaults unless set)\n",
                scene.solver.track_window.behind, scene.solver.track_window.ahead, scene.solver.track_window.shift);
    runWindow(scene, scene.vehicle.start_arc_length, window_steps, "straight from 25 m");
    runWindow(scene, 260.0, window_steps, "R 500 m curve from 260 m");
  }
  return 0;
}
