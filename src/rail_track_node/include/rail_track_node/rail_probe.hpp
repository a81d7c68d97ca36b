// A probe of both rails at one track section: each rail's displacement and small rotation there, in the
// track frame of the section, as linear maps of the 12 DOFs of the rail beam the section lies on. Built once
// per section (the maps are the beam's shape functions at the section, rotated from the element's axes to
// the track's); evaluated without allocation. Used by the moving-load simulator, the co-simulation track and
// the track window for their deflection outputs.
#pragma once

#include <Eigen/Core>

#include <array>

#include "rail_track_node/track_mesh.hpp"

namespace rail::track {

/// Displacement (m) and small rotation (rad) of both rails at one section, components in the track frame
/// at that section (x along the track, y lateral left, z normal up). Index: RailSide (0 left, 1 right).
struct RailSectionDeflection {
  double arc_length = 0.0;  ///< s of the section, m
  std::array<Eigen::Vector3d, 2> displacement;
  std::array<Eigen::Vector3d, 2> rotation;
};

/// One rail's probe.
struct RailProbe {
  std::array<int, 12> dofs;                   ///< the element's DOFs in the displacement vector, -1 fixed
  Eigen::Matrix<double, 3, 12> P_u, P_theta;  ///< element world DOFs -> track-frame displacement / rotation
};
using RailProbes = std::array<RailProbe, 2>;  ///< index: RailSide

/// The probes of both rails of `mesh` at arc length s, whose track frame is R_track_to_world. False when s
/// is not on the mesh's rails.
bool makeRailProbes(const TrackMesh& mesh, const Eigen::Matrix3d& R_track_to_world, double s, RailProbes& probes);

/// Throws std::runtime_error "deflection section at s = ... m is not on the meshed rails [a, b] m" when s
/// is not on both rails of the mesh.
void requireOnMeshRails(const TrackMesh& mesh, double s);

/// Probes that always read zero (a rail that does not move: the rigid track).
void makeZeroRailProbes(RailProbes& probes);

/// Both rails' deflection for the displacement vector d (free DOFs of the probes' mesh); out.s is left as is.
void evalRailProbes(const RailProbes& probes, const Eigen::VectorXd& d, RailSectionDeflection& out);

}  // namespace rail::track
