// Benchmark of the standalone flexible track (a program that prints, not a test): for straight tracks
// of 100 m, 500 m and 2 km built through the scene path (paper track data, damping and absorbing ends
// on), prints the free DOF count, the memory of the matrices and of the CHOLMOD factor, the build and
// factorisation times and the median wall time of one Newmark step with two moving 100 kN wheel loads.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <rail_core/scene_loader.hpp>

#include "rail_contact/tool_args.hpp"
#include "rail_core/testing/fixtures.hpp"
#include "rail_track_node/scene_track.hpp"
#include "rail_track_node/track_simulator.hpp"

namespace rt = rail::track;
using rail::tools::secondsSince;

namespace {
const char* const kUsage =
    "usage: bench_track [steps_100m] [steps_500m] [steps_2km]\n"
    "Standalone flexible track on straights of 100 m, 500 m and 2 km: DOFs, matrix and factor memory, build\n"
    "and factorisation times, median Newmark step with two moving 100 kN loads. Defaults 2000, 500, 100.\n";

// Compressed-column storage of a sparse matrix: values (8 B) and row indices (4 B) per entry, column starts.
double sparseBytes(const Eigen::SparseMatrix<double>& A) {
  return 12.0 * static_cast<double>(A.nonZeros()) + 4.0 * (A.cols() + 1);
}

}  // namespace

int main(int argc, char** argv) {
  if (rail::tools::startTool(argc, argv, kUsage, 3)) return 0;
  const double lengths[3] = {100.0, 500.0, 2000.0};
  int steps[3] = {2000, 500, 100};
  for (int i = 0; i < 3; ++i)
    steps[i] = static_cast<int>(rail::tools::positionalNumber(argc, argv, i + 1, steps[i], 3, kUsage));
  const double dt = 2e-5;
  std::printf(
      "straight tracks, paper track data, damping and absorbing ends on, dt = %g s, 2 wheel loads of "
      "100 kN at 30 m/s\n",
      dt);
  std::printf("%8s %9s %10s %10s %12s %11s %9s %11s %11s\n", "length", "free DOFs", "nnz(K)", "nnz(L)", "factor [MB]",
              "M,C,K [MB]", "build [s]", "factor [s]", "step [ms]");
  for (int c = 0; c < 3; ++c) {
    const double L = lengths[c];
    const std::string text =
        "name: bench\ntrack:\n  gauge: 1.668\n  data: ../track/paper_track.yaml\n  segments:\n"
        "    - {type: straight, length: " +
        std::to_string(L) +
        "}\n"
        "moving_loads:\n  start_arc_length: " +
        std::to_string(0.25 * L) +
        "\n  speed: 30.0\n  loads:\n    - {offset: 0.0, rail: both, vertical: 100000.0}\n"
        "solver:\n  track_step: 2.0e-5\n  end: {time: 1.0}\n";
    const rail::core::Scene scene =
        rail::core::loadSceneText(text, "bench.yaml", rail::core::fixtures::configDir() + "/scenes");
    const auto t0 = rail::tools::BenchClock::now();
    const rt::SceneTrack track = rt::buildSceneTrack(scene);
    const auto t1 = rail::tools::BenchClock::now();
    rt::SimulatorSettings set;
    set.track_step = dt;
    set.t_end = 1.0;
    set.loads = scene.moving_loads;
    set.rail_height = track.rail_height;
    // The simulator factorises K_eff (the timed part) and, for the initial static equilibrium, K and M.
    const auto t2 = rail::tools::BenchClock::now();
    rt::NewmarkIntegrator only_factor(track.model.system, dt);
    const auto t3 = rail::tools::BenchClock::now();
    rt::TrackSimulator sim(track.model, set);
    std::vector<double> times(steps[c]);
    for (int n = 0; n < steps[c]; ++n) {
      const auto a = rail::tools::BenchClock::now();
      sim.advanceTo((n + 1) * dt);
      times[n] = secondsSince(a);
    }
    const rt::LinearSystem& sys = track.model.system;
    const double nnz_L = only_factor.factor().factorNonZeros();
    std::printf("%6.0f m %9d %10ld %10.0f %12.1f %11.1f %9.2f %11.2f %11.3f   (%s factor, %d steps)\n", L, sys.size(),
                static_cast<long>(sys.K.nonZeros()), nnz_L, 8.0 * nnz_L / 1e6,
                (sparseBytes(sys.M) + sparseBytes(sys.C) + sparseBytes(sys.K)) / 1e6, secondsSince(t0, t1),
                secondsSince(t2, t3), 1e3 * rail::tools::median(times),
                only_factor.factor().isSupernodal() ? "supernodal" : "simplicial", steps[c]);
    std::fflush(stdout);
  }
  return 0;
}
