// A steady-state exchange allocates nothing, on either side, over the loopback and the shm transport.
// Every allocation of this program is counted by replacing the global operator new.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <new>
#include <thread>

#include "rail_core/coupling/loopback_transport.hpp"
#include "rail_core/coupling/protocol.hpp"
#include "rail_core/coupling/shm_transport.hpp"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new(std::size_t n, std::align_val_t a) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  const std::size_t al = static_cast<std::size_t>(a);
  if (void* p = std::aligned_alloc(al, (n + al - 1) / al * al)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n, std::align_val_t a) { return operator new(n, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

using namespace rail::core::coupling;

namespace {

constexpr int kWheels = 8;
constexpr long kWarmup = 10;  // exchanges before counting
constexpr long kCounted = 500;

CouplingConfig config() {
  CouplingConfig c;
  c.track_step = 2e-5;
  c.exchange_timeout = 10.0;
  c.scene_hash = 0xa110c;
  c.wheel_count = kWheels;
  return c;
}

// Returns the allocations made by the track during the counted steps, or -1 on a failed step.
long trackSide(FrameTransport& t, std::atomic<long>* counted_out) {
  TrackCoupling track(config(), t);
  long before = 0;
  for (long k = 0; k < kWarmup + kCounted; ++k) {
    if (k == kWarmup) before = g_allocations.load();
    if (!track.receive()) return -1;
    for (int i = 0; i < kWheels; ++i)
      track.wrenches().wheels[i].f_wheel_in_world = track.states().wheels[i].p_wheel_in_world;
    if (!track.send()) return -1;
  }
  const long n = g_allocations.load() - before;
  if (counted_out) *counted_out = n;
  return n;
}

// Allocations made by the process during the vehicle's counted exchanges, or -1 on a failed exchange.
long vehicleSide(FrameTransport& t) {
  VehicleCoupling v(config(), t);
  WrenchFrame out(kWheels);
  long before = 0;
  for (long k = 0; k < kWarmup + kCounted; ++k) {
    if (k == kWarmup) before = g_allocations.load();
    for (int i = 0; i < kWheels; ++i) v.states().wheels[i].p_wheel_in_world = Eigen::Vector3d(k, i, 0.0);
    if (!v.exchange()) return -1;
    v.extrapolate(v.nextExchangeTime(), out);
  }
  return g_allocations.load() - before;
}

}  // namespace

TEST(CouplingAllocation, CounterSeesAllocations) {  // the counter itself works
  const long before = g_allocations.load();
  auto* p = new std::vector<double>(100);
  delete p;
  EXPECT_GE(g_allocations.load() - before, 2);
}

TEST(CouplingAllocation, LoopbackSteadyStateAllocatesNothing) {
  LoopbackLink link(kWheels);
  long track_result = -2;
  std::thread track([&] { track_result = trackSide(link.trackEnd(), nullptr); });
  const long vehicle_allocations = vehicleSide(link.vehicleEnd());
  track.join();
  // Both threads count into one counter: the vehicle's figure includes the track's.
  EXPECT_EQ(vehicle_allocations, 0);
  EXPECT_EQ(track_result, 0);
}

TEST(CouplingAllocation, ShmSteadyStateAllocatesNothing) {
  ShmOptions o;
  o.scene_hash = config().scene_hash;
  o.wheel_capacity = kWheels;
  o.run_id = "alloc" + std::to_string(getpid());
  o.name_prefix = "railsimtest" + std::to_string(getpid());
  ShmOptions track_options = o;
  track_options.role = Role::kTrack;
  const pid_t child = fork();
  if (child == 0) {
    long n = -1;
    try {
      ShmTransport t(track_options);
      n = trackSide(t, nullptr);
    } catch (...) {
    }
    _exit(n == 0 ? 0 : (n < 0 ? 2 : 1));  // 1: the track allocated, 2: it failed
  }
  long vehicle_allocations = -1;
  try {
    o.role = Role::kVehicle;
    ShmTransport t(o);
    vehicle_allocations = vehicleSide(t);
  } catch (const std::exception& e) {
    ADD_FAILURE() << e.what();
  }
  int status = 0;
  if (vehicle_allocations < 0) kill(child, SIGKILL);
  waitpid(child, &status, 0);
  EXPECT_EQ(vehicle_allocations, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "track child status " << status;
}
