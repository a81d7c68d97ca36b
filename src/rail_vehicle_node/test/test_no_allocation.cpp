// No heap allocation on the normal path: right-hand side evaluations, violation checks and projections of
// the full vehicle, and whole integrator steps, counted by interposing the C allocator.
//
// Eigen allocates dynamic storage with std::malloc (not operator new), and libstdc++'s operator new calls
// malloc, so this executable defines malloc/calloc/realloc/free and the aligned variants, forwarding to
// glibc's __libc_* entry points and counting calls while a flag is set. (glibc documents replacing the
// allocator this way.)
#include <gtest/gtest.h>

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <vector>

#include "rail_vehicle_node/vehicle_integrator.hpp"
#include "rail_vehicle_node/vehicle_loader.hpp"

#ifndef RAIL_VEHICLE_CONFIG_DIR
#define RAIL_VEHICLE_CONFIG_DIR "config/vehicle"
#endif

extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* ptr, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void __libc_free(void* ptr);
}

namespace {
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};
inline void countAllocation() {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

extern "C" {
void* malloc(std::size_t size) {
  countAllocation();
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
  countAllocation();
  return __libc_calloc(count, size);
}
void* realloc(void* ptr, std::size_t size) {
  countAllocation();
  return __libc_realloc(ptr, size);
}
void free(void* ptr) { __libc_free(ptr); }
void* memalign(std::size_t alignment, std::size_t size) {
  countAllocation();
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  countAllocation();
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  countAllocation();
  *out = __libc_memalign(alignment, size);
  return *out == nullptr ? ENOMEM : 0;
}
}

namespace rail::vehicle {
namespace {

class AllocationCounter {
 public:
  AllocationCounter() {
    g_allocations = 0;
    g_counting = true;
  }
  ~AllocationCounter() { g_counting = false; }
  long count() const { return g_allocations.load(); }
};

TEST(NoAllocation, CounterSeesAllocations) {
  // The check below is only meaningful if the interposed allocator is really in use.
  long seen = 0;
  {
    AllocationCounter counter;
    std::vector<double> v(100);
    Eigen::VectorXd x(50);
    v[0] = x.size();
    seen = counter.count();
  }
  EXPECT_GE(seen, 2);
}

class NoAllocation : public ::testing::TestWithParam<KktSolver> {};

TEST_P(NoAllocation, FullVehicleRightHandSideProjectionAndSteps) {
  VehicleModel model;
  loadVehicleInto(std::string(RAIL_VEHICLE_CONFIG_DIR) + "/paper_coach.yaml", model);
  model.setKktSolver(GetParam());
  model.finalize();
  VehicleData data(model);
  // A general state: moving bodies, carbody shifted 30 mm laterally (bump stops engaged) and rolled
  // (anti-roll bars twisted), wheel wrenches set.
  Eigen::VectorXd y = model.referenceState();
  const int carbody = model.bodyIndex("carbody");
  y[VehicleModel::positionOffset(carbody) + 1] += 0.03;
  y.segment<4>(VehicleModel::eulerOffset(carbody)) = eulerParametersFromRotationVector(Vector3(0.01, 0.0, 0.002));
  for (int b = 0; b < model.nBodies(); ++b) {
    y.segment<3>(model.velocityOffset(b)) = Vector3(30.0, 0.01 * b, -0.02);
    y.segment<3>(model.angularVelocityOffset(b)) = Vector3(0.01, 0.02 * (b % 3), 0.005);
  }
  for (auto& w : data.external) {
    w.force_in_world = Vector3(1000.0, -2000.0, 72000.0);
    w.moment_in_world = Vector3(10.0, 20.0, -30.0);
  }
  Eigen::VectorXd y_dot(model.stateSize());
  computeDerivatives(model, 0.0, y, y_dot, data);  // warm-up (function-local statics)

  long rhs_allocations = 0;
  {
    AllocationCounter counter;
    for (int k = 0; k < 1000; ++k) computeDerivatives(model, 1e-3 * k, y, y_dot, data);
    rhs_allocations = counter.count();
  }
  EXPECT_EQ(rhs_allocations, 0);

  Eigen::VectorXd y_perturbed = y;
  y_perturbed[VehicleModel::positionOffset(model.bodyIndex("ab1_left")) + 2] += 1e-4;
  long projection_allocations = 0;
  {
    AllocationCounter counter;
    evaluateViolation(model, y_perturbed, data);
    projectState(model, y_perturbed, data, 1e-12, 20);
    projection_allocations = counter.count();
  }
  EXPECT_EQ(projection_allocations, 0);
  EXPECT_LT(evaluateViolation(model, y_perturbed, data).position, 1e-10);

  // Whole integrator steps (CVODE allocates at construction only).
  IntegratorSettings settings;
  settings.rtol = 1e-6;
  settings.atol = 1e-8;
  VehicleIntegrator integrator(model, data, y_perturbed, 0.0, settings);
  integrator.advanceTo(1e-3);
  long step_allocations = 0;
  {
    AllocationCounter counter;
    for (int k = 2; k <= 20; ++k) integrator.advanceTo(1e-3 * k);
    step_allocations = counter.count();
  }
  EXPECT_EQ(step_allocations, 0);
  EXPECT_GT(integrator.counters().steps, 5);
}

INSTANTIATE_TEST_SUITE_P(Solvers, NoAllocation, ::testing::Values(KktSolver::kRangeSpace, KktSolver::kAugmentedLu));

}  // namespace
}  // namespace rail::vehicle
