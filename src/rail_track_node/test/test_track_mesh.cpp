// Track mesh and assembled model: topology counts, geometry, mass, gravity equilibrium and the static
// deflection under a wheel load against the beam-on-elastic-foundation (Winkler) solution.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "rail_track_node/newmark.hpp"
#include "rail_track_node/track_data.hpp"
#include "rail_track_node/track_mesh.hpp"
#include "rail_track_node/track_model.hpp"

namespace rt = rail::track;

namespace {

std::string paperTrackPath() {
#ifdef RAIL_TRACK_CONFIG_DIR
  return std::string(RAIL_TRACK_CONFIG_DIR) + "/paper_track.yaml";
#else
  const std::string here = __FILE__;
  return here.substr(0, here.rfind("/src/rail_track_node/")) + "/config/track/paper_track.yaml";
#endif
}

rt::TrackModel straightModel(double length, bool absorbing = true) {
  rt::TrackData data = rt::loadTrackData(paperTrackPath());
  data.absorbing_ends.enabled = absorbing;
  rt::MeshOptions opt;
  opt.track_length = length;
  return rt::buildTrackModel(data, opt, rt::straightTrackFrames());
}

int countKind(const rt::TrackMesh& m, rt::SpringKind kind) {
  int n = 0;
  for (const auto& s : m.springs) n += s.kind == kind;
  return n;
}

}  // namespace

// Node / element counts follow from the topology: n_s = floor(L / a) + 1 sleepers; per rail
// (n_s - 1) n_e + 1 nodes; 6 sleeper nodes and one foundation node per ballast element per sleeper;
// 5 beams per sleeper; 2 pads per sleeper; n_b ballast per sleeper; n_b interaction elements per bay;
// 4 end dashpots. Exact integers.
TEST(TrackMesh, CountsForGivenLength) {
  for (double length : {6.0, 100.0}) {
    const rt::TrackModel model = straightModel(length);
    const rt::TrackMesh& m = model.mesh;
    const int n_bays = static_cast<int>(std::floor(length / 0.6 + 1e-9));
    const int n_s = n_bays + 1, n_e = 6, n_b = 4;
    const int rail_nodes = n_bays * n_e + 1;
    EXPECT_EQ(m.n_sleepers, n_s);
    EXPECT_EQ(static_cast<int>(m.rail_nodes[0].size()), rail_nodes);
    EXPECT_EQ(static_cast<int>(m.nodes.size()), 2 * rail_nodes + 6 * n_s + n_b * n_s);
    EXPECT_EQ(static_cast<int>(m.beams.size()), 2 * n_bays * n_e + 5 * n_s);
    EXPECT_EQ(countKind(m, rt::SpringKind::Pad), 2 * n_s);
    EXPECT_EQ(countKind(m, rt::SpringKind::Ballast), n_b * n_s);
    EXPECT_EQ(countKind(m, rt::SpringKind::SleeperInteraction), n_b * n_bays);
    EXPECT_EQ(countKind(m, rt::SpringKind::AbsorbingEnd), 4);
    EXPECT_EQ(static_cast<int>(m.masses.size()), n_b * n_s);
    EXPECT_EQ(m.n_free_dofs, 6 * (2 * rail_nodes + 6 * n_s));
    EXPECT_EQ(model.system.size(), m.n_free_dofs);
  }
}

// Total mass seen by a rigid translation, u' M u, equals 2 rho A L_rail + n_s rho_s A_s L_s + n_ballast m_b
// (consistent mass preserves the element mass exactly): 1e-12 relative. Gravity load sums to the weight.
TEST(TrackMesh, TotalMassAndGravityLoad) {
  const rt::TrackModel model = straightModel(12.0);
  const rt::TrackData& d = model.data;
  const rt::TrackMesh& m = model.mesh;
  const double rail_length = 12.0;  // 20 bays of 0.6 m
  const double expected = 2.0 * d.rail.rho * d.rail.A * rail_length +
                          m.n_sleepers * d.sleeper.rho * d.sleeper.A * d.layout.sleeper_length +
                          m.n_sleepers * 4 * d.ballast.mass;
  for (int axis = 0; axis < 3; ++axis) {
    Eigen::VectorXd u = Eigen::VectorXd::Zero(m.n_free_dofs);
    for (std::size_t n = 0; n < m.nodes.size(); ++n)
      if (m.dofIndex(static_cast<int>(n), axis) >= 0) u(m.dofIndex(static_cast<int>(n), axis)) = 1.0;
    EXPECT_NEAR(u.dot(model.system.M * u), expected, 1e-12 * expected);
    if (axis == 2) {
      EXPECT_NEAR(u.dot(model.system.f_gravity), -9.81 * expected, 1e-12 * 9.81 * expected);
    }
  }
}

// Static equilibrium under gravity: the vertical ballast forces (k_v times the vertical displacement of the
// ballast point, which for a level straight track equals the sleeper node's vertical displacement) carry
// the whole weight. Limited by the solve's roundoff: 1e-8 relative.
TEST(TrackMesh, GravityEquilibriumReactionsCarryTheWeight) {
  const rt::TrackModel model = straightModel(12.0);
  const rt::TrackMesh& m = model.mesh;
  const Eigen::VectorXd d = rt::staticGravityDeflection(model.system);
  double reaction = 0.0;
  for (const auto& s : m.springs) {
    if (s.kind != rt::SpringKind::Ballast) continue;
    reaction += -s.k(2) * d(m.dofIndex(s.node_a, 2));
  }
  Eigen::VectorXd u = Eigen::VectorXd::Zero(m.n_free_dofs);
  for (std::size_t n = 0; n < m.nodes.size(); ++n)
    if (m.dofIndex(static_cast<int>(n), 2) >= 0) u(m.dofIndex(static_cast<int>(n), 2)) = 1.0;
  const double weight = -u.dot(model.system.f_gravity);
  EXPECT_NEAR(reaction, weight, 1e-8 * weight);
}

// Rail nodes on a canted circular curve lie in the plane normal to the centre line at their s, at track
// coordinates (0, +-(o - h sin i), h cos i) (o lateral offset, h centroid height above the seat, i
// inclination). Pure geometry: 1e-12 m.
TEST(TrackMesh, RailNodesOnCantedCurve) {
  const rt::TrackData data = rt::loadTrackData(paperTrackPath());
  const double radius = 500.0, cant = 0.1;
  auto frame = [=](double s) {
    const double psi = s / radius;
    rt::TrackFrameSample F;
    F.p_centre_in_world = Eigen::Vector3d(radius * std::sin(psi), radius * (1.0 - std::cos(psi)), 0.0);
    const Eigen::Vector3d t(std::cos(psi), std::sin(psi), 0.0), lat(-std::sin(psi), std::cos(psi), 0.0);
    const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
    F.R_track_to_world.col(0) = t;
    F.R_track_to_world.col(1) = std::cos(cant) * lat + std::sin(cant) * z;
    F.R_track_to_world.col(2) = -std::sin(cant) * lat + std::cos(cant) * z;
    return F;
  };
  rt::MeshOptions opt;
  opt.track_length = 6.0;
  const rt::TrackMesh m = rt::buildTrackMesh(data, opt, frame);
  const double o = data.layout.rail_lateral_offset, h = data.layout.railCentroidAboveSeat();
  const double inc = data.layout.rail_inclination;
  for (int r = 0; r < 2; ++r) {
    const double side = r == rt::kLeftRail ? 1.0 : -1.0;
    for (std::size_t k = 0; k < m.rail_nodes[r].size(); ++k) {
      const rt::TrackFrameSample F = frame(m.railNodeS(static_cast<int>(k)));
      const Eigen::Vector3d local =
          F.R_track_to_world.transpose() * (m.nodes[m.rail_nodes[r][k]].p_in_world - F.p_centre_in_world);
      EXPECT_NEAR(local(0), 0.0, 1e-12);
      EXPECT_NEAR(local(1), side * (o - h * std::sin(inc)), 1e-12);
      EXPECT_NEAR(local(2), h * std::cos(inc), 1e-12);
    }
  }
}

// Equivalent nodal loads of a rail point load sum to the applied force (static equivalence; 1e-9 N).
TEST(TrackMesh, RailPointLoadIsStaticallyEquivalent) {
  const rt::TrackModel model = straightModel(6.0);
  rt::NodalLoads loads(64);
  const Eigen::Vector3d f(1e3, -2e4, -1e5);
  ASSERT_TRUE(rt::addRailPointLoad(model.mesh, rt::kLeftRail, 2.345, f, Eigen::Vector3d::Zero(), loads));
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int k = 0; k < loads.size(); ++k) {
    // translational DOFs have index % 6 < 3 because every free node owns 6 consecutive DOFs
    if (loads.index(k) % 6 < 3) sum(loads.index(k) % 6) += loads.value(k);
  }
  EXPECT_LT((sum - f).norm(), 1e-9);
  EXPECT_FALSE(rt::addRailPointLoad(model.mesh, rt::kLeftRail, 7.0, f, Eigen::Vector3d::Zero(), loads));
}

// Static rail deflection under a 100 kN vertical wheel load on each rail (one axle of 200 kN, symmetric so
// that each rail sees its own half of every sleeper) at mid length of a 60 m straight track, against the
// Winkler beam w0 = F beta / (2 k), beta = (k / (4 E I))^(1/4), E I the rail's vertical bending stiffness.
// Equivalent foundation modulus per rail: the pad k_p in series with the sleeper-on-ballast stiffness k_sb
// seen at the rail seat, smeared over the sleeper spacing a: k = (1 / (1/k_p + 1/k_sb)) / a.
//  - rigid sleeper: k_sb = 2 k_b (the two ballast elements of the half sleeper, under the end and the seat).
//    With the paper's data: k = 1.06e8 N/m^2, beta = 1.43 1/m, w0 = 0.67 mm.
//  - flexible sleeper (E_s I_s): half sleeper from the centre (symmetry: zero slope, zero shear) to the end
//    b = L_s / 2, seat at a_s = rail offset, ballast springs k_b at a_s and b, load P at a_s. Equilibrium gives
//    equal and opposite net forces R at a_s and b; cantilever formulas from the guided centre give the end
//    rising relative to the seat: w_b = w_seat - R c_f, c_f = (b - a_s)^2 (b + 2 a_s) / (3 E_s I_s); with
//    R = k_b w_b and P = k_b (w_seat + w_b): k_sb = P / w_seat = k_b (1 + 1 / (1 + k_b c_f)).
//    Paper data: k_b c_f = 1.44, k_sb = 8.7e7 N/m (30 % softer than rigid), w0 = 0.78 mm.
// Tolerance 5 %: what remains is the discrete support (beta a = 0.86 < 1, the range where a continuous
// foundation represents discrete sleepers to within a few percent; checked both above a sleeper and
// mid-bay), the rail inclination and the weak sleeper-interaction springs. A 7 % error in any stiffness
// entering k (w0 ~ k^(-3/4)) or in E I would fail the test. The 60 m length puts the ends ~40 / beta away.
namespace {

// pad_factor: the support zone's factor on the pads at s = 30 m (k_sb carries the ballast's).
void checkWinkler(const rt::TrackData& d, double k_sb, double pad_factor = 1.0) {
  rt::MeshOptions opt;
  opt.track_length = 60.0;
  const rt::TrackModel model = rt::buildTrackModel(d, opt, rt::straightTrackFrames());
  const rt::TrackMesh& m = model.mesh;
  const double F = 1.0e5;
  const double k = 1.0 / (1.0 / (pad_factor * d.pad.k(2)) + 1.0 / k_sb) / d.layout.sleeper_spacing;
  const double EI = d.rail.E * d.rail.I_y;
  const double beta = std::pow(k / (4.0 * EI), 0.25);
  const double w0 = F * beta / (2.0 * k);
  for (double s_load : {30.0, 30.3}) {  // above sleeper 50, and mid-bay
    rt::NodalLoads loads(64);
    for (int r = 0; r < 2; ++r)
      ASSERT_TRUE(rt::addRailPointLoad(m, r, s_load, Eigen::Vector3d(0, 0, -F), Eigen::Vector3d::Zero(), loads));
    Eigen::VectorXd f = Eigen::VectorXd::Zero(m.n_free_dofs);
    for (int q = 0; q < loads.size(); ++q) f(loads.index(q)) += loads.value(q);
    const Eigen::VectorXd disp = rt::solveStatic(model.system, f);
    int beam = 0;
    double xi = 0.0;
    ASSERT_TRUE(m.locateRail(rt::kLeftRail, s_load, beam, xi));
    const int node = xi < 0.5 ? m.beams[beam].node_i : m.beams[beam].node_j;
    const double w = -disp(m.dofIndex(node, 2));
    EXPECT_NEAR(w / w0, 1.0, 0.05) << "load at s = " << s_load << ": w = " << w << " m, Winkler w0 = " << w0;
    // symmetric load: both rails deflect equally (1e-9 relative)
    ASSERT_TRUE(m.locateRail(rt::kRightRail, s_load, beam, xi));
    const int node_r = xi < 0.5 ? m.beams[beam].node_i : m.beams[beam].node_j;
    EXPECT_NEAR(-disp(m.dofIndex(node_r, 2)), w, 1e-9 * w);
  }
}

}  // namespace

TEST(TrackMesh, WinklerStaticDeflectionRigidSleeper) {
  rt::TrackData d = rt::loadTrackData(paperTrackPath());
  d.absorbing_ends.enabled = false;
  ASSERT_EQ(d.layout.ballast_nodes, (std::vector<int>{0, 1, 4, 5}));
  d.sleeper.E *= 1e4;  // sleeper 10^4 times stiffer: bending of the sleeper negligible
  checkWinkler(d, 2.0 * d.ballast.k(2));
}

TEST(TrackMesh, WinklerStaticDeflectionPaperTrack) {
  rt::TrackData d = rt::loadTrackData(paperTrackPath());
  d.absorbing_ends.enabled = false;
  ASSERT_EQ(d.layout.ballast_nodes, (std::vector<int>{0, 1, 4, 5}));
  const double a_s = d.layout.rail_lateral_offset, b = 0.5 * d.layout.sleeper_length;
  const double c_f = (b - a_s) * (b - a_s) * (b + 2.0 * a_s) / (3.0 * d.sleeper.E * d.sleeper.I_y);
  const double k_b = d.ballast.k(2);
  checkWinkler(d, k_b * (1.0 + 1.0 / (1.0 + k_b * c_f)));
}

// A support zone (s = 10 .. 50 m, 2 m ramps) with pads at 0.4 and ballast at 0.5 of their stiffness: at
// s = 30 m, 20 m (28 / beta) from either ramp, the rail deflects as the Winkler beam of the scaled
// foundation (w0 ~ k^(-3/4): 1.8 times the unscaled track's, so a zone left out fails by far); each sleeper's
// pads and ballast carry the factor of its arc length, half-way up a ramp half of the zone's change.
TEST(TrackMesh, SupportZoneScalesPadsAndBallastAndTheDeflectionFollowsWinkler) {
  rt::TrackData d = rt::loadTrackData(paperTrackPath());
  d.absorbing_ends.enabled = false;
  d.sleeper.E *= 1e4;  // rigid sleeper, as in WinklerStaticDeflectionRigidSleeper
  rail::core::SupportZone z;
  z.s_from = 10.0;
  z.s_to = 50.0;
  z.ramp = 2.0;
  z.pad_stiffness = 0.4;
  z.ballast_stiffness = 0.5;
  z.ballast_damping = 3.0;
  d.support_zones = {z};
  checkWinkler(d, 0.5 * 2.0 * d.ballast.k(2), 0.4);
  rt::MeshOptions opt;
  opt.track_length = 60.0;
  const rt::TrackMesh m = rt::buildTrackMesh(d, opt, rt::straightTrackFrames());
  int checked = 0;
  for (const rt::SpringDamperElement& e : m.springs) {
    const double s = e.p_point_in_world.x();
    const double w = s < 10.0 || s > 50.0 ? 0.0 : std::min(1.0, std::min(s - 10.0, 50.0 - s) / 2.0);
    if (e.kind == rt::SpringKind::Pad) {
      EXPECT_NEAR(e.k(2), (1.0 + w * (0.4 - 1.0)) * d.pad.k(2), 1e-9 * d.pad.k(2)) << "pad at s = " << s;
      EXPECT_NEAR(e.c(2), d.pad.c(2), 1e-9 * d.pad.c(2)) << "pad at s = " << s;
      ++checked;
    } else if (e.kind == rt::SpringKind::Ballast) {
      EXPECT_NEAR(e.k(2), (1.0 + w * (0.5 - 1.0)) * d.ballast.k(2), 1e-9 * d.ballast.k(2)) << "ballast at s = " << s;
      EXPECT_NEAR(e.c(2), (1.0 + w * (3.0 - 1.0)) * d.ballast.c(2), 1e-9 * d.ballast.c(2)) << "ballast at s = " << s;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 2 * m.n_sleepers + 4 * m.n_sleepers);
}
