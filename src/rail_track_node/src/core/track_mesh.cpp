#include "rail_track_node/track_mesh.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rail {
namespace track {

namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Matrix3d rotationAboutX(double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  Eigen::Matrix3d R;
  R << 1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c;
  return R;
}

// +1 for the left rail (y > 0 in the track frame), -1 for the right rail.
double sideSign(int rail) { return rail == kLeftRail ? 1.0 : -1.0; }

// Frame of a rail: the track frame turned about the tangent so that the rail leans towards the centre line.
Eigen::Matrix3d railFrame(const TrackFrameSample& F, int rail, double inclination) {
  return F.R_track_to_world * rotationAboutX(sideSign(rail) * inclination);
}

Eigen::Vector3d railSeat(const TrackFrameSample& F, int rail, const TrackLayout& L) {
  return F.p_centre_in_world + F.R_track_to_world * Eigen::Vector3d(0.0, sideSign(rail) * L.rail_lateral_offset, 0.0);
}

// Orthonormal frame with x along x_dir and z as close as possible to z_hint.
Eigen::Matrix3d frameFromAxis(const Eigen::Vector3d& x_dir, const Eigen::Vector3d& z_hint) {
  const Eigen::Vector3d x = x_dir.normalized();
  const Eigen::Vector3d z = (z_hint - z_hint.dot(x) * x).normalized();
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = z.cross(x);
  R.col(2) = z;
  return R;
}

Vector6d springVector(const Eigen::Vector3d& translational, double roll) {
  Vector6d v = Vector6d::Zero();
  v.head<3>() = translational;
  v(3) = roll;
  return v;
}

void checkFrame(const TrackFrameSample& F, double s) {
  const double err = (F.R_track_to_world.transpose() * F.R_track_to_world - Eigen::Matrix3d::Identity()).norm();
  if (!(err < 1e-9) || !(F.R_track_to_world.determinant() > 0.0) || !F.p_centre_in_world.allFinite()) {
    std::ostringstream os;
    os << "buildTrackMesh: track frame at s = " << s << " m is not a proper rotation (|R^T R - I| = " << err << ")";
    throw std::runtime_error(os.str());
  }
}

}  // namespace

TrackFrameFunction straightTrackFrames(const Eigen::Vector3d& p_start_in_world) {
  return [p_start_in_world](double s) {
    TrackFrameSample F;
    F.p_centre_in_world = p_start_in_world + Eigen::Vector3d(s, 0.0, 0.0);
    F.R_track_to_world.setIdentity();
    return F;
  };
}

bool TrackMesh::locateRail(int rail, double s, int& beam, double& xi) const {
  const int n_beams = static_cast<int>(rail_beams[rail].size());
  const double ds = sleeper_spacing / rail_elements_between_sleepers;
  const double u = (s - s_start) / ds;
  if (!(u >= -1e-9 && u <= n_beams + 1e-9)) return false;
  int k = static_cast<int>(std::floor(u));
  if (k < 0) k = 0;
  if (k >= n_beams) k = n_beams - 1;
  beam = rail_beams[rail][k];
  xi = std::min(1.0, std::max(0.0, u - k));
  return true;
}

void foundationModuli(const TrackData& data, double& k_lateral, double& k_vertical) {
  const double share = 0.5 * static_cast<double>(data.layout.ballast_nodes.size());  // ballast elements per rail
  auto series = [](double a, double b) { return 1.0 / (1.0 / a + 1.0 / b); };
  k_lateral = series(data.pad.k(1), share * data.ballast.k(1)) / data.layout.sleeper_spacing;
  k_vertical = series(data.pad.k(2), share * data.ballast.k(2)) / data.layout.sleeper_spacing;
}

TrackMesh buildTrackMesh(const TrackData& data, const MeshOptions& options, const TrackFrameFunction& frame) {
  const TrackLayout& L = data.layout;
  const double a = L.sleeper_spacing;
  const int n_e = L.rail_elements_between_sleepers;
  if (!(options.track_length >= a)) {
    std::ostringstream os;
    os << "buildTrackMesh: track_length must cover at least one sleeper bay (" << a << " m), got "
       << options.track_length;
    throw std::runtime_error(os.str());
  }
  if (n_e < 1)
    throw std::runtime_error("buildTrackMesh: rail_elements_between_sleepers must be >= 1, got " + std::to_string(n_e));
  const int n_bays = static_cast<int>(std::floor(options.track_length / a + 1e-9));
  const int n_sleepers = n_bays + 1;

  TrackMesh mesh;
  mesh.n_sleepers = n_sleepers;
  mesh.s_start = options.s_start;
  mesh.sleeper_spacing = a;
  mesh.rail_elements_between_sleepers = n_e;

  const double y_sleeper[6] = {-0.5 * L.sleeper_length,     -L.rail_lateral_offset, -L.sleeper_inner_node_offset,
                               L.sleeper_inner_node_offset, L.rail_lateral_offset,  0.5 * L.sleeper_length};
  const int seat_node[2] = {4, 1};  // sleeper node under the left / right rail
  const double h_rail = L.railCentroidAboveSeat();

  std::vector<TrackFrameSample> sleeper_frames(n_sleepers);
  std::array<std::vector<Eigen::Vector3d>, 2> rail_up;  // rail z axis at each rail node
  std::vector<std::vector<int>> foundation_nodes(n_sleepers);
  mesh.sleeper_nodes.resize(n_sleepers);

  auto addNode = [&mesh](const Eigen::Vector3d& p, NodeKind kind, bool fixed) {
    mesh.nodes.push_back(Node{p, kind, fixed});
    return static_cast<int>(mesh.nodes.size()) - 1;
  };
  auto addRailNodes = [&](const TrackFrameSample& F) {
    for (int r = 0; r < 2; ++r) {
      const Eigen::Matrix3d R_rail = railFrame(F, r, L.rail_inclination);
      rail_up[r].push_back(R_rail.col(2));
      mesh.rail_nodes[r].push_back(addNode(railSeat(F, r, L) + h_rail * R_rail.col(2), NodeKind::Rail, false));
    }
  };

  // Nodes, plane by plane along s (keeps coupled DOFs close in the natural ordering).
  for (int k = 0; k < n_sleepers; ++k) {
    const double s = options.s_start + k * a;
    const TrackFrameSample F = frame(s);
    checkFrame(F, s);
    sleeper_frames[k] = F;
    for (int n = 0; n < 6; ++n)
      mesh.sleeper_nodes[k][n] = addNode(
          F.p_centre_in_world + F.R_track_to_world * Eigen::Vector3d(0.0, y_sleeper[n], -0.5 * L.sleeper_height),
          NodeKind::Sleeper, false);
    for (int n : L.ballast_nodes)
      foundation_nodes[k].push_back(
          addNode(F.p_centre_in_world + F.R_track_to_world * Eigen::Vector3d(0.0, y_sleeper[n], -L.sleeper_height),
                  NodeKind::Foundation, true));
    addRailNodes(F);
    if (k + 1 < n_sleepers) {
      for (int m = 1; m < n_e; ++m) {
        const double s_m = s + m * a / n_e;
        const TrackFrameSample Fm = frame(s_m);
        checkFrame(Fm, s_m);
        addRailNodes(Fm);
      }
    }
  }

  // Rail beams.
  for (int r = 0; r < 2; ++r) {
    const std::vector<int>& rn = mesh.rail_nodes[r];
    for (std::size_t q = 0; q + 1 < rn.size(); ++q) {
      const Eigen::Vector3d chord = mesh.nodes[rn[q + 1]].p_in_world - mesh.nodes[rn[q]].p_in_world;
      const Eigen::Matrix3d R = frameFromAxis(chord, rail_up[r][q] + rail_up[r][q + 1]);
      mesh.rail_beams[r].push_back(static_cast<int>(mesh.beams.size()));
      mesh.beams.push_back(BeamElement{rn[q], rn[q + 1], BeamKind::Rail, chord.norm(), R});
    }
  }

  // Sleepers: 5 beams each, local x to the left, z along the track normal.
  for (int k = 0; k < n_sleepers; ++k) {
    for (int n = 0; n < 5; ++n) {
      const int ni = mesh.sleeper_nodes[k][n], nj = mesh.sleeper_nodes[k][n + 1];
      const Eigen::Vector3d chord = mesh.nodes[nj].p_in_world - mesh.nodes[ni].p_in_world;
      const Eigen::Matrix3d R = frameFromAxis(chord, sleeper_frames[k].R_track_to_world.col(2));
      mesh.beams.push_back(BeamElement{ni, nj, BeamKind::Sleeper, chord.norm(), R});
    }
  }

  // Pads: rail node (a) to the sleeper node under it (b), acting at the rail seat, in the rail frame.
  // Each sleeper's pads and ballast carry the support factors at its arc length (all 1 without zones).
  auto factorsAt = [&](int k) { return rail::core::supportFactors(data.support_zones, options.s_start + k * a); };
  const Vector6d k_pad = springVector(data.pad.k, data.pad.k_roll);
  const Vector6d c_pad = springVector(data.pad.c, 0.0);
  for (int k = 0; k < n_sleepers; ++k) {
    const TrackFrameSample& F = sleeper_frames[k];
    const rail::core::SupportFactors f = factorsAt(k);
    for (int r = 0; r < 2; ++r) {
      mesh.springs.push_back(SpringDamperElement{
          SpringKind::Pad, mesh.rail_nodes[r][k * n_e], mesh.sleeper_nodes[k][seat_node[r]], railSeat(F, r, L),
          railFrame(F, r, L.rail_inclination), f.pad_stiffness * k_pad, f.pad_damping * c_pad});
    }
  }

  // Ballast: sleeper node (a) to its foundation node (b), acting at the sleeper bottom, with lumped mass.
  const Vector6d k_bal = springVector(data.ballast.k, 0.0);
  const Vector6d c_bal = springVector(data.ballast.c, 0.0);
  for (int k = 0; k < n_sleepers; ++k) {
    const rail::core::SupportFactors f = factorsAt(k);
    for (std::size_t q = 0; q < L.ballast_nodes.size(); ++q) {
      const int sn = mesh.sleeper_nodes[k][L.ballast_nodes[q]];
      const int fn = foundation_nodes[k][q];
      mesh.springs.push_back(SpringDamperElement{SpringKind::Ballast, sn, fn, mesh.nodes[fn].p_in_world,
                                                 sleeper_frames[k].R_track_to_world, f.ballast_stiffness * k_bal,
                                                 f.ballast_damping * c_bal, f.hanging, f.sleeper_gap});
      // The ballast under a void stays on the ground: a hanging sleeper does not carry its mass.
      if (!f.hanging) mesh.masses.push_back(PointMass{sn, data.ballast.mass});
    }
  }

  // Sleeper interaction: same supported nodes of consecutive sleepers, acting at the midpoint.
  const Vector6d k_int = springVector(data.sleeper_interaction.k, 0.0);
  const Vector6d c_int = springVector(data.sleeper_interaction.c, 0.0);
  for (int k = 0; k + 1 < n_sleepers; ++k) {
    const TrackFrameSample F_mid = frame(options.s_start + (k + 0.5) * a);
    checkFrame(F_mid, options.s_start + (k + 0.5) * a);
    for (int n : L.ballast_nodes) {
      const int na = mesh.sleeper_nodes[k][n], nb = mesh.sleeper_nodes[k + 1][n];
      const Eigen::Vector3d mid = 0.5 * (mesh.nodes[na].p_in_world + mesh.nodes[nb].p_in_world);
      mesh.springs.push_back(
          SpringDamperElement{SpringKind::SleeperInteraction, na, nb, mid, F_mid.R_track_to_world, k_int, c_int});
    }
  }

  // Absorbing ends: grounded dashpots at the first and last node of each rail, in the end beam's frame.
  if (data.absorbing_ends.enabled) {
    double k_lat = 0.0, k_vert = 0.0;
    foundationModuli(data, k_lat, k_vert);
    const Vector6d c_end =
        absorbingEndDashpots(data.rail, k_lat, k_vert, 2.0 * kPi * data.absorbing_ends.design_frequency);
    for (int r = 0; r < 2; ++r) {
      const BeamElement& first = mesh.beams[mesh.rail_beams[r].front()];
      const BeamElement& last = mesh.beams[mesh.rail_beams[r].back()];
      mesh.springs.push_back(SpringDamperElement{SpringKind::AbsorbingEnd, first.node_i, -1,
                                                 mesh.nodes[first.node_i].p_in_world, first.R_local_to_world,
                                                 Vector6d::Zero(), c_end});
      mesh.springs.push_back(SpringDamperElement{SpringKind::AbsorbingEnd, last.node_j, -1,
                                                 mesh.nodes[last.node_j].p_in_world, last.R_local_to_world,
                                                 Vector6d::Zero(), c_end});
    }
  }

  // DOF map.
  mesh.dof_index.assign(6 * mesh.nodes.size(), -1);
  int next = 0;
  for (std::size_t n = 0; n < mesh.nodes.size(); ++n) {
    if (mesh.nodes[n].fixed) continue;
    for (int d = 0; d < 6; ++d) mesh.dof_index[6 * n + d] = next++;
  }
  mesh.n_free_dofs = next;
  return mesh;
}

}  // namespace track
}  // namespace rail
