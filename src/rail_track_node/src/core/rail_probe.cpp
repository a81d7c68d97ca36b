#include "rail_track_node/rail_probe.hpp"

#include <sstream>
#include <stdexcept>

#include <rail_contact/beam_shape.hpp>

#include "rail_track_node/elements.hpp"

namespace rail::track {

bool makeRailProbes(const TrackMesh& mesh, const Eigen::Matrix3d& R_track_to_world, double s, RailProbes& probes) {
  for (int r = 0; r < 2; ++r) {
    int beam = 0;
    double xi = 0.0;
    if (!mesh.locateRail(r, s, beam, xi)) return false;
    const BeamElement& b = mesh.beams[static_cast<std::size_t>(beam)];
    rail::contact::Matrix3x12 N_u, N_theta;
    rail::contact::beamShapeDisplacement(xi, b.length, N_u);
    rail::contact::beamShapeRotation(xi, b.length, N_theta);
    const Matrix12d T = beamWorldToLocal(b.R_local_to_world);
    const Eigen::Matrix3d R_local_to_track = R_track_to_world.transpose() * b.R_local_to_world;
    RailProbe& p = probes[static_cast<std::size_t>(r)];
    p.P_u = R_local_to_track * N_u * T;
    p.P_theta = R_local_to_track * N_theta * T;
    for (int d = 0; d < 6; ++d) {
      p.dofs[static_cast<std::size_t>(d)] = mesh.dofIndex(b.node_i, d);
      p.dofs[static_cast<std::size_t>(6 + d)] = mesh.dofIndex(b.node_j, d);
    }
  }
  return true;
}

void requireOnMeshRails(const TrackMesh& mesh, double s) {
  int beam = 0;
  double xi = 0.0;
  if (mesh.locateRail(0, s, beam, xi) && mesh.locateRail(1, s, beam, xi)) return;
  std::ostringstream os;
  os << "deflection section at s = " << s << " m is not on the meshed rails [" << mesh.s_start << ", "
     << mesh.railNodeS(static_cast<int>(mesh.rail_nodes[0].size()) - 1) << "] m";
  throw std::runtime_error(os.str());
}

void makeZeroRailProbes(RailProbes& probes) {
  for (RailProbe& p : probes) {
    p.dofs.fill(-1);
    p.P_u.setZero();
    p.P_theta.setZero();
  }
}

void evalRailProbes(const RailProbes& probes, const Eigen::VectorXd& d, RailSectionDeflection& out) {
  for (std::size_t r = 0; r < 2; ++r) {
    const RailProbe& p = probes[r];
    Eigen::Matrix<double, 12, 1> d_e;
    for (std::size_t k = 0; k < 12; ++k) d_e(static_cast<Eigen::Index>(k)) = p.dofs[k] >= 0 ? d(p.dofs[k]) : 0.0;
    out.displacement[r].noalias() = p.P_u * d_e;
    out.rotation[r].noalias() = p.P_theta * d_e;
  }
}

}  // namespace rail::track
