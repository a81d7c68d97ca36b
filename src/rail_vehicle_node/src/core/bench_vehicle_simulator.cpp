// Benchmark of the vehicle on the rigid track (prints its figures; not a test):
//   bench_vehicle_simulator <scene.yaml> <simulated seconds> [bdf|adams|auto] [max_step] [flange 0|1] [spin 0|1]
//                           [start_arc_length] [cost 0|1]
// Prints wall time per simulated second, CVODE steps, RHS and Jacobian evaluations. cost 1 passes a cost
// clock (as the node does) so that the clock's own overhead can be measured against cost 0.
#include <rail_core/cost_profile.hpp>
#include <rail_core/scene_loader.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "rail_vehicle_node/vehicle_simulator.hpp"

int main(int argc, char** argv) {
  using namespace rail;
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s scene.yaml seconds [bdf|adams|auto] [max_step] [flange 0|1] [spin 0|1] [start_s] "
                 "[cost 0|1]\n", argv[0]);
    return 2;
  }
  core::Scene scene = core::load_scene_file(argv[1]);
  scene.effects.track_model = core::TrackModel::kRigid;
  const double duration = std::atof(argv[2]);
  if (argc > 3) {
    const std::string m = argv[3];
    scene.solver.vehicle_method = m == "bdf" ? core::VehicleMethod::kBdf
                                  : m == "adams" ? core::VehicleMethod::kAdams : core::VehicleMethod::kAuto;
  }
  if (argc > 4) scene.solver.vehicle_max_step = std::atof(argv[4]);
  if (argc > 5) scene.effects.flange_contact = std::atoi(argv[5]) != 0;
  if (argc > 6) scene.effects.spin_creepage = std::atoi(argv[6]) != 0;
  if (argc > 7) scene.vehicle.start_arc_length = std::atof(argv[7]);
  const bool with_cost = argc > 8 && std::atoi(argv[8]) != 0;
  core::CostClock clock;
  vehicle::SimulatorSettings settings;
  if (with_cost) settings.cost = &clock;
  scene.solver.end.kind = core::EndKind::kTime;
  scene.solver.end.value = duration;
  const auto t0 = std::chrono::steady_clock::now();
  vehicle::VehicleSimulator sim(scene, settings);
  const auto t1 = std::chrono::steady_clock::now();
  vehicle::RunStatus status = vehicle::RunStatus::kRunning;
  for (int i = 1; status == vehicle::RunStatus::kRunning; ++i) status = sim.AdvanceTo(std::min(duration, 1e-3 * i));
  const auto t2 = std::chrono::steady_clock::now();
  const double build = std::chrono::duration<double>(t1 - t0).count();
  const double run = std::chrono::duration<double>(t2 - t1).count();
  const vehicle::IntegratorCounters c = sim.Counters();
  std::printf("%s: %s, max_step %g, flange %d, spin %d: %.3f s simulated in %.2f s wall (%.2f s per simulated s; "
              "build %.2f s); steps %ld, RHS %ld + %ld for %ld Jacobians, error-test failures %ld, nonlinear "
              "failures %ld, projections %ld, contact evaluations %lld; cost clock %s; status %s %s\n",
              scene.name.c_str(), sim.method() == vehicle::IntegrationMethod::kBdf ? "BDF" : "Adams",
              scene.solver.vehicle_max_step, scene.effects.flange_contact, scene.effects.spin_creepage, sim.time(),
              run, run / sim.time(), build, c.steps, c.rhs_evals, c.rhs_evals_jacobian, c.jacobian_evals,
              c.error_test_failures, c.nonlinear_convergence_failures, c.projections,
              sim.contact_data().evaluations, with_cost ? "on" : "off", status == vehicle::RunStatus::kFinished ? "finished" : "stopped",
              sim.message().c_str());
  return status == vehicle::RunStatus::kFinished ? 0 : 1;
}
