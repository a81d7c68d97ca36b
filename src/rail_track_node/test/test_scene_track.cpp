// Scene -> flexible track and the moving-load simulator: effects that are off build nothing, the FE rails
// run under the geometry's rails, the deflection probes interpolate the beam, and a slowly moving load
// deflects the rail as the static solution does.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <rail_core/scene_loader.hpp>
#include <rail_core/testing/fixtures.hpp>

#include "rail_track_node/pad_forces.hpp"
#include "rail_track_node/scene_track.hpp"
#include "rail_track_node/track_simulator.hpp"

namespace rt = rail::track;
namespace rc = rail::contact;
using rail::core::Scene;

namespace {

// A moving-load scene on the paper's track; SEGMENTS, LOADS and EFFECTS are filled in per test.
Scene scene(const std::string& segments, const std::string& loads, const std::string& effects,
            const std::string& solver = "  track_step: 1.0e-3\n  end: {time: 1.0}") {
  const std::string text =
      "name: t\ntrack:\n  gauge: 1.668\n  cant_reference_width: 1.733\n"
      "  data: ../track/paper_track.yaml\n  segments:\n" +
      segments + "\nmoving_loads:\n" + loads + "\neffects:\n" + effects + "\nsolver:\n" + solver + "\n";
  return rail::core::fixtures::sceneFromText(text, "t.yaml");
}

const std::string kStraight24 = "    - {type: straight, length: 24.0}";
const std::string kOneLoad =
    "  start_arc_length: 9.0\n  speed: 1.0\n  loads:\n    - {offset: 0.0, rail: both, vertical: 100000.0}";

int countKind(const rt::TrackMesh& m, rt::SpringKind kind) {
  int n = 0;
  for (const auto& s : m.springs) n += s.kind == kind;
  return n;
}

}  // namespace

// effects.track_damping off: C is assembled with no entry and no spring-damper carries damping;
// effects.absorbing_ends off: no end dashpot element exists. With both on (the default) C has entries and
// there are 4 end dashpots, so the test can fail. Exact counts.
TEST(SceneTrack, EffectsOffBuildNothing) {
  const rt::SceneTrack off =
      rt::buildSceneTrack(scene(kStraight24, kOneLoad, "  track_damping: false\n  absorbing_ends: false"));
  EXPECT_EQ(off.model.system.C.nonZeros(), 0);
  EXPECT_EQ(countKind(off.model.mesh, rt::SpringKind::AbsorbingEnd), 0);
  for (const rt::SpringDamperElement& s : off.model.mesh.springs) EXPECT_EQ(s.c.squaredNorm(), 0.0);

  const rt::SceneTrack on = rt::buildSceneTrack(scene(kStraight24, kOneLoad, "  track_damping: true"));
  EXPECT_GT(on.model.system.C.nonZeros(), 0);
  EXPECT_EQ(countKind(on.model.mesh, rt::SpringKind::AbsorbingEnd), 4);
  // Everything else is the same mesh.
  EXPECT_EQ(on.model.mesh.springs.size(), off.model.mesh.springs.size() + 4);
  EXPECT_EQ(on.model.system.K.nonZeros(), off.model.system.K.nonZeros());

  // Damping off only: dashpots present, nothing else damped (their entries alone fill C).
  const rt::SceneTrack ends_only = rt::buildSceneTrack(scene(kStraight24, kOneLoad, "  track_damping: false"));
  EXPECT_EQ(countKind(ends_only.model.mesh, rt::SpringKind::AbsorbingEnd), 4);
  EXPECT_GT(ends_only.model.system.C.nonZeros(), 0);
  EXPECT_LE(ends_only.model.system.C.nonZeros(), 4 * 36);
}

// On a canted curve the FE rail nodes lie on the geometry's rails: the rail centroid node is the
// geometry's rail profile origin moved down the inclined rail axis by (rail height - centroid height); the
// FE rail axis lies in the centre line's normal plane (the track frame turned by the inclination).
// The mesh samples the same design frames, so only the geometry table interpolation (cubic Hermite at
// 0.1 m) and round-off separate them: 1e-7 m.
TEST(SceneTrack, FeRailsRunUnderGeometryRails) {
  const std::string curve =
      "    - {type: straight, length: 6.0}\n"
      "    - {type: transition, length: 30.0, direction: left, radius_start: 0, radius_end: 250.0, cant_start: 0, "
      "cant_end: 0.12}\n"
      "    - {type: circular, length: 24.0, direction: left, radius: 250.0, cant: 0.12}";
  const rt::SceneTrack t = rt::buildSceneTrack(scene(curve, kOneLoad, "  track_damping: true"));
  const rt::TrackMesh& m = t.model.mesh;
  const double drop = t.rail_height - t.model.data.layout.rail_centroid_height;
  double worst = 0.0;
  for (int r = 0; r < 2; ++r) {
    for (std::size_t k = 0; k < m.rail_nodes[r].size(); k += 7) {
      const double s = m.railNodeS(k);
      rc::RailPoint rp;
      t.geometry.rail(r == rt::kLeftRail ? rc::RailSide::kLeft : rc::RailSide::kRight, s, rp);
      rc::TrackPoint c;
      t.geometry.centre(s, c);
      const double sg = r == rt::kLeftRail ? 1.0 : -1.0, incl = t.model.data.layout.rail_inclination;
      const Eigen::Vector3d axis =
          std::cos(incl) * c.R_track_to_world.col(2) - sg * std::sin(incl) * c.R_track_to_world.col(1);
      const Eigen::Vector3d expected = rp.p_origin_in_world - drop * axis;
      worst = std::max(worst, (m.nodes[m.rail_nodes[r][k]].p_in_world - expected).norm());
    }
  }
  EXPECT_LT(worst, 1e-7);
}

// The deflection probe reproduces the nodal values at a rail node (xi = 0 or 1: shape functions
// interpolate) and rotates them into the track frame. Exact up to round-off: 1e-15 m per unit DOF.
TEST(SceneTrack, DeflectionProbeInterpolatesNodalValues) {
  const Scene sc = scene(kStraight24, kOneLoad, "  track_damping: true");
  const rt::SceneTrack t = rt::buildSceneTrack(sc);
  rt::SimulatorSettings set;
  set.track_step = 1e-3;
  set.t_end = 0.0;
  set.loads = sc.moving_loads;
  rt::TrackSimulator sim(t.model, set);
  const rt::TrackMesh& m = t.model.mesh;
  const int k = 37;  // a rail node between sleepers
  const int i = sim.addSection(m.railNodeS(k), rt::seatPlaneFrames(t.geometry, t.seat_below_centre));
  Eigen::VectorXd d = Eigen::VectorXd::Zero(t.model.system.size());
  const int node = m.rail_nodes[rt::kRightRail][k];
  for (int q = 0; q < 6; ++q) d(m.dofIndex(node, q)) = 1e-3 * (q + 1);
  rt::RailSectionDeflection out;
  sim.sectionDeflection(i, d, out);
  // Straight level track: track frame = world frame.
  EXPECT_NEAR((out.displacement[rt::kRightRail] - Eigen::Vector3d(1e-3, 2e-3, 3e-3)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((out.rotation[rt::kRightRail] - Eigen::Vector3d(4e-3, 5e-3, 6e-3)).norm(), 0.0, 1e-15);
  EXPECT_NEAR(out.displacement[rt::kLeftRail].norm(), 0.0, 1e-15);
}

// A 100 kN load per rail moving at 1 m/s (first critical speed of such tracks: hundreds of m/s, so the
// dynamic amplification (v / v_cr)^2 is ~1e-5) deflects the rail as the static solution with the load at
// the same place does. Compared at the section s = 12 m (above a sleeper) as the load passes over
// 10.5 .. 13.5 m, at every 0.1 m: the difference stays below 1 % of the peak static deflection (what is
// left is the small vibration started at t = 0 by the load's sudden speed, damped by the track).
TEST(TrackSimulator, SlowlyMovingLoadMatchesStaticDeflection) {
  const Scene sc =
      scene(kStraight24, kOneLoad, "  track_damping: true", "  track_step: 1.0e-3\n  end: {arc_length: 14.0}");
  const rt::SceneTrack t = rt::buildSceneTrack(sc);
  rt::SimulatorSettings set;
  set.track_step = sc.solver.track_step;
  set.t_end = rt::movingLoadEndTime(sc);
  set.loads = sc.moving_loads;
  set.rail_height = t.rail_height;
  EXPECT_NEAR(set.t_end, 5.0, 1e-12);
  rt::TrackSimulator sim(t.model, set);
  const int sec = sim.addSection(12.0, rt::seatPlaneFrames(t.geometry, t.seat_below_centre));

  // Static reference: K d = f_g + f(t) for the load at the same place.
  rt::SparseCholesky K(t.model.system.K);
  rt::NodalLoads loads(64);
  Eigen::VectorXd f(t.model.system.size()), d(t.model.system.size());
  double peak = 0.0, worst = 0.0;
  int compared = 0;
  for (double t_cmp = 1.5; t_cmp <= 4.5 + 1e-9; t_cmp += 0.1) {
    sim.advanceTo(t_cmp);
    sim.loadsAt(sim.time(), loads);
    f = t.model.system.f_gravity;
    for (int k = 0; k < loads.size(); ++k) f(loads.index(k)) += loads.value(k);
    K.solve(f, d);
    rt::RailSectionDeflection dyn, stat;
    sim.sectionDeflection(sec, dyn);
    sim.sectionDeflection(sec, d, stat);
    for (int r = 0; r < 2; ++r) {
      peak = std::max(peak, std::abs(stat.displacement[r].z()));
      worst = std::max(worst, (dyn.displacement[r] - stat.displacement[r]).norm());
    }
    ++compared;
  }
  EXPECT_EQ(compared, 31);
  EXPECT_GT(peak, 5e-4);  // the paper track deflects ~0.8 mm under 100 kN
  EXPECT_LT(worst, 0.01 * peak) << "peak " << peak << " m, worst difference " << worst << " m";
}

// Loads are placed where the scene says: the sum of the nodal forces of one load per rail equals the
// applied vertical and lateral force (static equivalence of eq. 16), 1e-6 N on 1e5 N.
TEST(TrackSimulator, LoadsAreStaticallyEquivalent) {
  const Scene sc = scene(kStraight24,
                         "  start_arc_length: 9.0\n  speed: 2.0\n  loads:\n"
                         "    - {offset: 0.0, rail: left, vertical: 100000.0, lateral: 20000.0}\n"
                         "    - {offset: 2.5, rail: right, vertical: 50000.0, lateral: 10000.0}",
                         "  track_damping: true");
  const rt::SceneTrack t = rt::buildSceneTrack(sc);
  rt::SimulatorSettings set;
  set.track_step = 1e-3;
  set.t_end = 0.5;
  set.loads = sc.moving_loads;
  rt::TrackSimulator sim(t.model, set);
  rt::NodalLoads loads(64);
  sim.loadsAt(0.3, loads);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  const rt::TrackMesh& m = t.model.mesh;
  for (int k = 0; k < loads.size(); ++k) {
    for (std::size_t n = 0; n < m.nodes.size(); ++n)
      for (int q = 0; q < 3; ++q)
        if (m.dofIndex(static_cast<int>(n), q) == loads.index(k)) sum(q) += loads.value(k);
  }
  // Straight level track, inclination only tilts the rails: vertical -z, left field side +y, right -y.
  EXPECT_NEAR(sum.x(), 0.0, 1e-6);
  EXPECT_NEAR(sum.y(), 20000.0 - 10000.0, 1e-6);
  EXPECT_NEAR(sum.z(), -150000.0, 1e-6);
}

// Pad and ballast forces (PadForceProbe) in the static equilibrium under gravity and a 100 kN load on each rail: the
// rails rest on the pads alone (the end dashpots carry nothing at rest), so the pads' vertical forces on
// the sleepers add up to the load plus the rails' weight (the z part of f_g at the rail nodes), to the
// static solve's round-off (1e-6 of the total); each rail's largest pad force is at the sleeper nearest the
// load (at s = 9.0 m, a sleeper: 9.0 = 15 x 0.6) and no pad pulls on its sleeper there.
TEST(PadForceProbe, PadsCarryTheLoadAndTheRailWeightAtRest) {
  const Scene sc = scene(kStraight24, kOneLoad, "  track_damping: true");
  const rt::SceneTrack t = rt::buildSceneTrack(sc);
  rt::SimulatorSettings set;
  set.track_step = 1e-3;
  set.t_end = 0.0;
  set.loads = sc.moving_loads;
  set.rail_height = t.rail_height;
  rt::TrackSimulator sim(t.model, set);
  const rt::TrackMesh& m = t.model.mesh;
  double rail_weight = 0.0;
  for (int r = 0; r < 2; ++r) {
    for (int node : m.rail_nodes[static_cast<std::size_t>(r)]) {
      const int i = m.dofIndex(node, 2);
      if (i >= 0) rail_weight -= t.model.system.f_gravity(i);
    }
  }
  EXPECT_GT(rail_weight, 0.0);
  rt::PadForceProbe probe(m);
  ASSERT_EQ(probe.sleeperCount(), m.n_sleepers);
  std::vector<rt::PadForceSample> out(static_cast<std::size_t>(m.n_sleepers));
  const int n =
      probe.evaluate(m, t.geometry, sim.state().d, sim.state().v, nullptr, -1.0, 1e9, out.data(), m.n_sleepers);
  ASSERT_EQ(n, m.n_sleepers);
  double sum_z = 0.0;
  std::array<int, 2> k_max{-1, -1};
  std::array<double, 2> f_max{0.0, 0.0};
  for (int k = 0; k < n; ++k) {
    for (int r = 0; r < 2; ++r) {
      const double fz = out[static_cast<std::size_t>(k)].force_in_track[static_cast<std::size_t>(r)].z();
      sum_z += fz;
      if (-fz > f_max[static_cast<std::size_t>(r)])
        f_max[static_cast<std::size_t>(r)] = -fz, k_max[static_cast<std::size_t>(r)] = k;
    }
  }
  const double expected = -(2.0 * 100000.0 + rail_weight);
  EXPECT_NEAR(sum_z, expected, 1e-6 * std::abs(expected));
  for (int r = 0; r < 2; ++r) {
    EXPECT_NEAR(out[static_cast<std::size_t>(k_max[static_cast<std::size_t>(r)])].arc_length, 9.0, 1e-9)
        << "rail " << r;
    // Under the load the rail is pressed down: its displacement at that sleeper is negative.
    EXPECT_LT(out[static_cast<std::size_t>(k_max[static_cast<std::size_t>(r)])]
                  .rail_displacement_in_track[static_cast<std::size_t>(r)]
                  .z(),
              0.0);
  }
  // The ballast carries the whole track at rest: the sleepers' forces on the ballast add up to the loads
  // plus the weight of everything above the ballast elements (the z part of f_g at every free DOF: rails,
  // sleepers and the ballast masses lumped at the sleepers), to the same round-off; none lifts off.
  double track_weight = 0.0;
  for (std::size_t node = 0; node < m.nodes.size(); ++node) {
    const int i = m.dofIndex(static_cast<int>(node), 2);
    if (i >= 0) track_weight -= t.model.system.f_gravity(i);
  }
  EXPECT_GT(track_weight, rail_weight);
  double ballast_z = 0.0;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d& f = out[static_cast<std::size_t>(k)].ballast_force_in_track;
    EXPECT_LT(f.z(), 0.0) << "sleeper " << k;
    ballast_z += f.z();
  }
  const double expected_ballast = -(2.0 * 100000.0 + track_weight);
  EXPECT_NEAR(ballast_z, expected_ballast, 1e-6 * std::abs(expected_ballast));
  // A sub-range returns the sleepers inside it only, in order of s.
  const int n_sub =
      probe.evaluate(m, t.geometry, sim.state().d, sim.state().v, nullptr, 8.95, 10.25, out.data(), m.n_sleepers);
  ASSERT_EQ(n_sub, 3);  // 9.0, 9.6, 10.2
  EXPECT_NEAR(out[0].arc_length, 9.0, 1e-9);
  EXPECT_NEAR(out[2].arc_length, 10.2, 1e-9);
}
