// The time step performs no heap allocation. This file replaces the C allocation functions of the whole
// test program with counting wrappers around glibc's (malloc, calloc, realloc, free and the aligned
// variants), which also catches allocations made inside CHOLMOD, Eigen and the C++ runtime. Build it as
// its own test executable so the replacement does not affect other tests.
#include <gtest/gtest.h>

#include <cerrno>
#include <cstddef>
#include <string>

#include "rail_track_node/newmark.hpp"
#include "rail_track_node/track_data.hpp"
#include "rail_track_node/track_model.hpp"

#include "malloc_counter.hpp"

namespace rt = rail::track;

namespace {
std::string paperTrackPath() {
  const std::string here = __FILE__;
  return here.substr(0, here.rfind("/src/rail_track_node/")) + "/config/track/paper_track.yaml";
}
}  // namespace

// The counter itself works: an Eigen vector and a std::string allocation inside the counted region are seen.
TEST(NewmarkAllocation, CounterSeesAllocations) {
  g_allocations = 0;
  g_counting = true;
  Eigen::VectorXd v(1000);
  std::string s(100, 'x');
  g_counting = false;
  EXPECT_GE(g_allocations, 2);
  EXPECT_EQ(v.size() + static_cast<long>(s.size()), 1100);
}

// 200 steps of a 30 m track with a moving wheel load on both rails (load transfer by the beam shape
// functions + right-hand side assembly + CHOLMOD solve): zero allocations.
TEST(NewmarkAllocation, StepDoesNotAllocate) {
  const rt::TrackData data = rt::loadTrackData(paperTrackPath());
  rt::MeshOptions opt;
  opt.track_length = 30.0;
  const rt::TrackModel model = rt::buildTrackModel(data, opt, rt::straightTrackFrames());
  rt::NewmarkIntegrator integ(model.system, 1e-4);
  rt::NewmarkState st = integ.initialState(rt::staticGravityDeflection(model.system));
  rt::NodalLoads loads(64);
  const double speed = 30.0;  // m/s
  g_allocations = 0;
  g_counting = true;
  for (int n = 0; n < 200; ++n) {
    loads.clear();
    const double s = 10.0 + speed * (st.t + integ.dt());
    rt::addRailPointLoad(model.mesh, rt::kLeftRail, s, Eigen::Vector3d(0, 0, -1e5), Eigen::Vector3d::Zero(), loads);
    rt::addRailPointLoad(model.mesh, rt::kRightRail, s, Eigen::Vector3d(0, 0, -1e5), Eigen::Vector3d::Zero(), loads);
    integ.step(st, loads);
  }
  g_counting = false;
  EXPECT_EQ(g_allocations, 0);
  EXPECT_TRUE(st.d.allFinite());
}
