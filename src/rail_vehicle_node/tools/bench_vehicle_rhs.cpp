// Benchmark program (not part of the library): median wall time of one right-hand side evaluation of the
// full vehicle model, for both solvers of the augmented system.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "rail_contact/tool_args.hpp"
#include "rail_vehicle_node/multibody_dynamics.hpp"
#include "rail_vehicle_node/vehicle_loader.hpp"

namespace {
const char* const kUsage =
    "usage: bench_vehicle_rhs [vehicle.yaml] [evaluations]\n"
    "Median wall time of one right-hand side of the full vehicle model, for both solvers of the augmented\n"
    "system. Defaults: config/vehicle/paper_coach.yaml, 20000 evaluations.\n";
}  // namespace

#ifndef RAIL_VEHICLE_CONFIG_DIR
#define RAIL_VEHICLE_CONFIG_DIR "config/vehicle"
#endif

namespace {

double medianRhsMicroseconds(const std::string& path, rail::vehicle::KktSolver solver, int evaluations) {
  using namespace rail::vehicle;
  VehicleModel model;
  loadVehicleInto(path, model);
  model.setKktSolver(solver);
  model.finalize();
  VehicleData data(model);
  Eigen::VectorXd y = model.referenceState();
  // A generic moving state: every body translating and rotating a little.
  for (int b = 0; b < model.nBodies(); ++b) {
    y.segment<3>(model.velocityOffset(b)) = Vector3(30.0, 0.01 * b, -0.02);
    y.segment<3>(model.angularVelocityOffset(b)) = Vector3(0.01, 0.02 * (b % 3), 0.005);
  }
  Eigen::VectorXd y_dot = Eigen::VectorXd::Zero(model.stateSize());
  std::vector<double> times(static_cast<std::size_t>(evaluations));
  for (int k = 0; k < 100; ++k) computeDerivatives(model, 0.0, y, y_dot, data);  // warm-up
  for (int k = 0; k < evaluations; ++k) {
    const auto start = std::chrono::steady_clock::now();
    computeDerivatives(model, 1e-3 * k, y, y_dot, data);
    const auto stop = std::chrono::steady_clock::now();
    times[static_cast<std::size_t>(k)] = std::chrono::duration<double, std::micro>(stop - start).count();
  }
  std::nth_element(times.begin(), times.begin() + evaluations / 2, times.end());
  std::printf("  (bodies %d, constraints %d, state size %d)\n", model.nBodies(), model.nConstraints(),
              model.stateSize());
  return times[static_cast<std::size_t>(evaluations / 2)];
}

}  // namespace

int main(int argc, char** argv) {
  if (rail::tools::startTool(argc, argv, kUsage, 2)) return 0;
  const std::string path = argc > 1 ? argv[1] : std::string(RAIL_VEHICLE_CONFIG_DIR) + "/paper_coach.yaml";
  const int evaluations = static_cast<int>(rail::tools::positionalNumber(argc, argv, 2, 20000, 1, kUsage));
  try {
    const double range = medianRhsMicroseconds(path, rail::vehicle::KktSolver::kRangeSpace, evaluations);
    std::printf("median RHS evaluation, range-space solve: %.2f us over %d evaluations\n", range, evaluations);
    const double lu = medianRhsMicroseconds(path, rail::vehicle::KktSolver::kAugmentedLu, evaluations);
    std::printf("median RHS evaluation, augmented LU solve: %.2f us over %d evaluations\n", lu, evaluations);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_vehicle_rhs: %s\n", e.what());
    return 1;
  }
  return 0;
}
