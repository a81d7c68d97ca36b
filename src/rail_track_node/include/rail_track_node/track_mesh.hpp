// Finite element mesh of the track (paper section 3.2), generated from the track centre-line frames.
// Built once; constant afterwards.
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <vector>

#include "rail_track_node/elements.hpp"
#include "rail_track_node/track_data.hpp"

namespace rail {
namespace track {

/// Track frame at centre-line arc length s. p_centre_in_world: centre-line point in the plane of the rail
/// seats (top of the sleepers), m. R_track_to_world columns: tangent (forward), lateral (left), normal (up)
/// of the canted track plane.
struct TrackFrameSample {
  Eigen::Vector3d p_centre_in_world;
  Eigen::Matrix3d R_track_to_world;
};

/// Centre-line frames as a function of s (m). Used at build time only.
using TrackFrameFunction = std::function<TrackFrameSample(double s)>;

/// Straight, level track along world x starting at p_start_in_world (world z up).
TrackFrameFunction straightTrackFrames(const Eigen::Vector3d& p_start_in_world = Eigen::Vector3d::Zero());

enum class NodeKind { Rail, Sleeper, Foundation };
enum class BeamKind { Rail, Sleeper };
enum class SpringKind { Pad, Ballast, SleeperInteraction, AbsorbingEnd };

/// Rail index used throughout the mesh.
enum RailSide : int { kLeftRail = 0, kRightRail = 1 };

struct Node {
  Eigen::Vector3d p_in_world;  ///< undeformed position, m
  NodeKind kind;
  bool fixed;  ///< all 6 DOFs fixed (foundation)
};

struct BeamElement {
  int node_i, node_j;
  BeamKind kind;
  double length;                     ///< m
  Eigen::Matrix3d R_local_to_world;  ///< columns: local x (i -> j), y, z
};

/// 6-DOF spring-damper (see springDamperMatrix). node_b = -1: grounded.
struct SpringDamperElement {
  SpringKind kind;
  int node_a, node_b;
  Eigen::Vector3d p_point_in_world;  ///< point where the element acts, m
  Eigen::Matrix3d R_local_to_world;  ///< element frame (directions of k and c)
  Vector6d k, c;                     ///< N/m and N m/rad; N s/m and N m s/rad
  /// Ballast of a hanging sleeper: along local z it bears only in compression, once the void `gap` (m)
  /// between the sleeper and the ballast has closed (HangingSupports). K and C hold it as if closed.
  bool unilateral = false;
  double gap = 0.0;
};

/// Lumped mass on the translations of a node, kg.
struct PointMass {
  int node;
  double mass;
};

/// Build options not contained in TrackData.
struct MeshOptions {
  double track_length = 0.0;  ///< m; sleepers at s_start + k * spacing while within the length
  double s_start = 0.0;       ///< centre-line arc length of the first sleeper, m
};

/// The mesh and its DOF map (node, dof) -> free DOF index; fixed DOFs are eliminated (index -1).
struct TrackMesh {
  std::vector<Node> nodes;
  std::vector<BeamElement> beams;
  std::vector<SpringDamperElement> springs;
  std::vector<PointMass> masses;
  std::vector<int> dof_index;  ///< size 6 * nodes.size()
  int n_free_dofs = 0;
  int n_sleepers = 0;
  double s_start = 0.0;          ///< m
  double sleeper_spacing = 0.0;  ///< m
  int rail_elements_between_sleepers = 0;
  std::array<std::vector<int>, 2> rail_nodes;     ///< per rail (RailSide), ordered along s
  std::array<std::vector<int>, 2> rail_beams;     ///< per rail, ordered along s; beam k spans s_k .. s_k+1
  std::vector<std::array<int, 6>> sleeper_nodes;  ///< per sleeper, right (y < 0) to left

  /// Free DOF index of (node, dof) with dof in 0..5, or -1 if fixed.
  int dofIndex(int node, int dof) const { return dof_index[6 * node + dof]; }

  /// Centre-line arc length of rail node k (same for both rails), m.
  double railNodeS(int k) const { return s_start + k * sleeper_spacing / rail_elements_between_sleepers; }

  /// Rail beam containing arc length s and the element coordinate xi = (s - s_i) / (s_j - s_i) in [0, 1].
  /// Returns false if s is outside the rails. O(1).
  bool locateRail(int rail, double s, int& beam, double& xi) const;
};

/// Generates nodes in the planes normal to the centre line (2 rail nodes, 6 sleeper nodes and one
/// foundation node per ballast element at each sleeper; rail_elements_between_sleepers - 1 rail nodes per
/// rail in between), rail beams between sleepers, sleepers of 5 beams, pads, ballast (with lumped mass),
/// sleeper interaction and, if data.absorbing_ends.enabled, dashpots at the 4 rail ends.
/// Throws std::runtime_error if the options are not physical (e.g. length shorter than one bay).
TrackMesh buildTrackMesh(const TrackData& data, const MeshOptions& options, const TrackFrameFunction& frame);

/// Equivalent vertical (normal) and lateral foundation moduli under one rail, N/m^2: pad in series with the
/// rail's share of the ballast (half the ballast elements of a sleeper), divided by the sleeper spacing.
/// Used for tuning the absorbing ends.
void foundationModuli(const TrackData& data, double& k_lateral, double& k_vertical);

}  // namespace track
}  // namespace rail
