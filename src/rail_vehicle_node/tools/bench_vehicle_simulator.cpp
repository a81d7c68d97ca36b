// Benchmark of the vehicle on the rigid track (prints its figures; not a test):
//   bench_vehicle_simulator <scene.yaml> <simulated seconds> [bdf|adams|auto] [max_step] [flange 0|1] [spin 0|1]
//                           [start_arc_length] [cost 0|1] [coloured|dq] [klu|dense] [runs] [carry 0|1]
//                           [accepted|every]
// Prints, per run, wall time per simulated second, CVODE steps, RHS and Jacobian evaluations, then the
// median wall time of the runs. max_step is the vehicle-alone cap (it replaces the scene's
// solver.standalone_max_step; 0 = none); a negative start_arc_length keeps the scene's. cost 1 passes a cost clock (as
// the node does) so that the clock's own overhead can be measured against cost 0. coloured|dq: BDF's Jacobian (the
// coloured sparse quotient or CVODE's dense one), klu|dense: the linear solver with the coloured Jacobian.
#include <rail_core/cost_profile.hpp>
#include <rail_core/scene_loader.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "rail_contact/tool_args.hpp"
#include "rail_vehicle_node/vehicle_simulator.hpp"

namespace {
const char* const kUsage =
    "usage: bench_vehicle_simulator scene.yaml seconds [bdf|adams|auto] [max_step] [flange 0|1] [spin 0|1]\n"
    "                               [start_s] [cost 0|1] [coloured|dq] [klu|dense] [runs] [carry 0|1]\n"
    "                               [accepted|every]\n"
    "The vehicle alone on the rigid track: per run the wall time per simulated second, CVODE steps, RHS and\n"
    "Jacobian evaluations, then the median of the runs. max_step: the vehicle-alone cap (0 = none);\n"
    "start_s < 0 keeps the scene's; cost 1 passes a cost clock; coloured|dq: BDF's Jacobian; klu|dense: the\n"
    "linear solver with the coloured Jacobian; carry 0: no Jacobian carried with the wheelsets' spin (CVODE's\n"
    "own reuse policy); every: the contacts' impact memories and detection warm starts take every evaluation,\n"
    "trial states included, instead of the accepted steps only.\n";

int runBenchmark(int argc, char** argv) {
  using namespace rail;
  if (rail::tools::startTool(argc, argv, kUsage, 13)) return 0;
  if (argc < 3) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  using tools::positionalChoice;
  using tools::positionalNumber;
  static const char* const kMethods[] = {"bdf", "adams", "auto", nullptr};
  static const char* const kOffOn[] = {"0", "1", nullptr};
  static const char* const kJacobians[] = {"coloured", "dq", nullptr};
  static const char* const kSolvers[] = {"klu", "dense", nullptr};
  static const char* const kMemories[] = {"accepted", "every", nullptr};
  const double duration = positionalNumber(argc, argv, 2, 0.0, 1e-6, kUsage);
  const int method = positionalChoice(argc, argv, 3, kMethods, 2, kUsage);
  vehicle::SimulatorSettings settings;
  const double max_step = positionalNumber(argc, argv, 4, 0.0, 0.0, kUsage);
  const bool flange = positionalChoice(argc, argv, 5, kOffOn, 1, kUsage) == 1;
  const bool spin = positionalChoice(argc, argv, 6, kOffOn, 1, kUsage) == 1;
  const double start_s = positionalNumber(argc, argv, 7, -1.0, -HUGE_VAL, kUsage);
  const bool with_cost = positionalChoice(argc, argv, 8, kOffOn, 0, kUsage) == 1;
  if (positionalChoice(argc, argv, 9, kJacobians, 0, kUsage) == 1) {
    settings.jacobian = vehicle::JacobianKind::kDenseDifferenceQuotient;
  }
  if (positionalChoice(argc, argv, 10, kSolvers, 0, kUsage) == 1) {
    settings.linear_solver = vehicle::LinearSolverKind::kDense;
  }
  const int runs = static_cast<int>(positionalNumber(argc, argv, 11, 1.0, 1.0, kUsage));
  settings.carry_jacobian_with_spin = positionalChoice(argc, argv, 12, kOffOn, 1, kUsage) == 1;
  settings.impact_memory_at_accepted_steps = positionalChoice(argc, argv, 13, kMemories, 0, kUsage) == 0;
  settings.warm_starts_at_accepted_steps = settings.impact_memory_at_accepted_steps;
  core::Scene scene = core::loadSceneFile(argv[1]);
  scene.solver.standalone_max_step = max_step;
  scene.effects.track_model = core::TrackModel::kRigid;
  if (argc > 3) {
    scene.solver.vehicle_method = method == 0   ? core::VehicleMethod::kBdf
                                  : method == 1 ? core::VehicleMethod::kAdams
                                                : core::VehicleMethod::kAuto;
  }
  if (argc > 5) scene.effects.flange_contact = flange;
  if (argc > 6) scene.effects.spin_creepage = spin;
  if (start_s >= 0.0) scene.vehicle.start_arc_length = start_s;
  scene.solver.end.kind = core::EndKind::kTime;
  scene.solver.end.value = duration;
  std::vector<double> walls;
  bool all_finished = true;
  for (int run = 0; run < runs; ++run) {
    core::CostClock clock;
    settings.cost = with_cost ? &clock : nullptr;
    const auto t0 = std::chrono::steady_clock::now();
    vehicle::VehicleSimulator sim(vehicle::resolveVehicle(scene), settings);
    const auto t1 = std::chrono::steady_clock::now();
    vehicle::RunStatus status = vehicle::RunStatus::kRunning;
    for (int i = 1; status == vehicle::RunStatus::kRunning; ++i) status = sim.advanceTo(std::min(duration, 1e-3 * i));
    const auto t2 = std::chrono::steady_clock::now();
    const double build = std::chrono::duration<double>(t1 - t0).count();
    const double wall = std::chrono::duration<double>(t2 - t1).count();
    walls.push_back(wall / sim.time());
    all_finished = all_finished && status == vehicle::RunStatus::kFinished;
    const vehicle::IntegratorCounters c = sim.counters();
    std::printf(
        "%s: %s, max_step %g, jacobian %s, linear solver %s, flange %d, spin %d: %.3f s simulated in %.2f s "
        "wall (%.3f s per simulated s, real-time factor %.2f; build %.2f s); steps %ld, RHS %ld + %ld for %ld "
        "Jacobians (%ld carried with the spin), error-test failures %ld, nonlinear failures %ld, projections %ld, "
        "Adams fallbacks %ld, contact "
        "evaluations %lld; "
        "cost clock %s; status %s %s\n",
        scene.name.c_str(), sim.method() == vehicle::IntegrationMethod::kBdf ? "BDF" : "Adams", sim.maxStep(),
        settings.jacobian == vehicle::JacobianKind::kColoured ? "coloured" : "dense-dq",
        settings.linear_solver == vehicle::LinearSolverKind::kSparseKlu ? "klu" : "dense", scene.effects.flange_contact,
        scene.effects.spin_creepage, sim.time(), wall, wall / sim.time(), sim.time() / wall, build, c.steps,
        c.rhs_evals, c.rhs_evals_jacobian, c.jacobian_evals, c.jacobian_carries, c.error_test_failures,
        c.nonlinear_convergence_failures, c.projections, c.adams_fallbacks, sim.contactData().evaluations,
        with_cost ? "on" : "off", status == vehicle::RunStatus::kFinished ? "finished" : "stopped",
        sim.message().c_str());
    std::fflush(stdout);
  }
  std::vector<double> sorted = walls;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted.size() % 2 == 1 ? sorted[sorted.size() / 2]
                                               : 0.5 * (sorted[sorted.size() / 2 - 1] + sorted[sorted.size() / 2]);
  std::printf("median of %d runs: %.3f s wall per simulated s (real-time factor %.2f), min %.3f, max %.3f\n", runs,
              median, 1.0 / median, sorted.front(), sorted.back());
  return all_finished ? 0 : 1;
}
}  // namespace

// A scene that cannot be read or built: one line naming the file and the field, exit 1.
int main(int argc, char** argv) {
  return rail::tools::runReportingErrors("bench_vehicle_simulator", runBenchmark, argc, argv);
}
