// Benchmark of the track Newmark integrator (not a test): for straight tracks of 100 m and 500 m built from
// a track data file, prints the free DOF count, the assembly and factorisation times and the median wall
// time of one step (moving 100 kN wheel loads on both rails).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "rail_contact/tool_args.hpp"
#include "rail_core/testing/fixtures.hpp"
#include "rail_track_node/newmark.hpp"
#include "rail_track_node/track_data.hpp"
#include "rail_track_node/track_model.hpp"

namespace rt = rail::track;
using rail::tools::secondsSince;

namespace {
const char* const kUsage =
    "usage: bench_newmark [track.yaml] [steps]\n"
    "Track Newmark integrator on straight tracks of 100 m and 500 m: free DOFs, assembly and factorisation\n"
    "times, median step time with moving 100 kN wheel loads. Defaults: config/track/paper_track.yaml, 200.\n";
}  // namespace

int main(int argc, char** argv) {
  if (rail::tools::startTool(argc, argv, kUsage, 2)) return 0;
  std::string path = argc > 1 ? argv[1] : "";
  if (path.empty()) path = rail::core::fixtures::configDir() + "/track/paper_track.yaml";
  const int steps = static_cast<int>(rail::tools::positionalNumber(argc, argv, 2, 200, 1, kUsage));
  const double dt = 1e-4;
  rt::TrackData data;
  try {
    data = rt::loadTrackData(path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_newmark: %s\n", e.what());
    return 1;
  }
  std::printf("track data: %s, dt = %g s, %d steps per case\n", path.c_str(), dt, steps);
  for (double length : {100.0, 500.0}) {
    rt::MeshOptions opt;
    opt.track_length = length;
    const auto t0 = rail::tools::BenchClock::now();
    const rt::TrackModel model = rt::buildTrackModel(data, opt, rt::straightTrackFrames());
    const auto t1 = rail::tools::BenchClock::now();
    rt::NewmarkIntegrator integ(model.system, dt);
    const auto t2 = rail::tools::BenchClock::now();
    rt::NewmarkState st = integ.initialState(rt::staticGravityDeflection(model.system));
    rt::NodalLoads loads(64);
    std::vector<double> times(steps);
    for (int n = 0; n < steps; ++n) {
      loads.clear();
      const double s = 0.25 * length + 30.0 * (st.t + dt);
      rt::addRailPointLoad(model.mesh, rt::kLeftRail, s, Eigen::Vector3d(0, 0, -1e5), Eigen::Vector3d::Zero(), loads);
      rt::addRailPointLoad(model.mesh, rt::kRightRail, s, Eigen::Vector3d(0, 0, -1e5), Eigen::Vector3d::Zero(), loads);
      const auto a = rail::tools::BenchClock::now();
      integ.step(st, loads);
      times[n] = secondsSince(a);
    }
    std::printf(
        "%5.0f m: %d free DOFs, nnz(K) = %ld, nnz(L) = %.0f (%s), build+assembly %.3f s, "
        "factorisation of K_eff %.3f s, median step %.3f ms\n",
        length, model.system.size(), static_cast<long>(model.system.K.nonZeros()), integ.factor().factorNonZeros(),
        integ.factor().isSupernodal() ? "supernodal" : "simplicial", secondsSince(t0, t1), secondsSince(t1, t2),
        1e3 * rail::tools::median(times));
  }
  return 0;
}
