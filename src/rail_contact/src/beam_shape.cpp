#include "rail_contact/beam_shape.hpp"

namespace rail {
namespace contact {

namespace {

// Hermite cubics and their derivatives with respect to s = xi L.
// H1, H3: unit end displacement at i, j; H2, H4: unit end slope at i, j (carry a factor L).
struct Hermite {
  double H1, H2, H3, H4;          // values
  double dH1, dH2, dH3, dH4;      // first derivatives in s
  double ddH1, ddH2, ddH3, ddH4;  // second derivatives in s
};

Hermite hermite(double xi, double L) {
  const double xi2 = xi * xi;
  const double xi3 = xi2 * xi;
  Hermite h;
  h.H1 = 1.0 - 3.0 * xi2 + 2.0 * xi3;
  h.H2 = L * (xi - 2.0 * xi2 + xi3);
  h.H3 = 3.0 * xi2 - 2.0 * xi3;
  h.H4 = L * (-xi2 + xi3);
  h.dH1 = (-6.0 * xi + 6.0 * xi2) / L;
  h.dH2 = 1.0 - 4.0 * xi + 3.0 * xi2;
  h.dH3 = (6.0 * xi - 6.0 * xi2) / L;
  h.dH4 = -2.0 * xi + 3.0 * xi2;
  h.ddH1 = (-6.0 + 12.0 * xi) / (L * L);
  h.ddH2 = (-4.0 + 6.0 * xi) / L;
  h.ddH3 = (6.0 - 12.0 * xi) / (L * L);
  h.ddH4 = (-2.0 + 6.0 * xi) / L;
  return h;
}

// DOF columns inside the 12-vector.
constexpr int kU = 0, kV = 1, kW = 2, kTx = 3, kTy = 4, kTz = 5, kJ = 6;

}  // namespace

void beamShapeDisplacement(double xi, double L, Matrix3x12& N_u) {
  const Hermite h = hermite(xi, L);
  N_u.setZero();
  // axial u: linear
  N_u(0, kU) = 1.0 - xi;
  N_u(0, kJ + kU) = xi;
  // v (bending in the x-y plane, slope theta_z)
  N_u(1, kV) = h.H1;
  N_u(1, kTz) = h.H2;
  N_u(1, kJ + kV) = h.H3;
  N_u(1, kJ + kTz) = h.H4;
  // w (bending in the x-z plane, slope -theta_y)
  N_u(2, kW) = h.H1;
  N_u(2, kTy) = -h.H2;
  N_u(2, kJ + kW) = h.H3;
  N_u(2, kJ + kTy) = -h.H4;
}

void beamShapeRotation(double xi, double L, Matrix3x12& N_theta) {
  const Hermite h = hermite(xi, L);
  N_theta.setZero();
  // torsion theta_x: linear
  N_theta(0, kTx) = 1.0 - xi;
  N_theta(0, kJ + kTx) = xi;
  // theta_y = -dw/ds
  N_theta(1, kW) = -h.dH1;
  N_theta(1, kTy) = h.dH2;
  N_theta(1, kJ + kW) = -h.dH3;
  N_theta(1, kJ + kTy) = h.dH4;
  // theta_z = dv/ds
  N_theta(2, kV) = h.dH1;
  N_theta(2, kTz) = h.dH2;
  N_theta(2, kJ + kV) = h.dH3;
  N_theta(2, kJ + kTz) = h.dH4;
}

void beamShapeDisplacementDs(double xi, double L, Matrix3x12& dN_u_ds) {
  const Hermite h = hermite(xi, L);
  dN_u_ds.setZero();
  dN_u_ds(0, kU) = -1.0 / L;
  dN_u_ds(0, kJ + kU) = 1.0 / L;
  dN_u_ds(1, kV) = h.dH1;
  dN_u_ds(1, kTz) = h.dH2;
  dN_u_ds(1, kJ + kV) = h.dH3;
  dN_u_ds(1, kJ + kTz) = h.dH4;
  dN_u_ds(2, kW) = h.dH1;
  dN_u_ds(2, kTy) = -h.dH2;
  dN_u_ds(2, kJ + kW) = h.dH3;
  dN_u_ds(2, kJ + kTy) = -h.dH4;
}

void beamShapeRotationDs(double xi, double L, Matrix3x12& dN_theta_ds) {
  const Hermite h = hermite(xi, L);
  dN_theta_ds.setZero();
  dN_theta_ds(0, kTx) = -1.0 / L;
  dN_theta_ds(0, kJ + kTx) = 1.0 / L;
  dN_theta_ds(1, kW) = -h.ddH1;
  dN_theta_ds(1, kTy) = h.ddH2;
  dN_theta_ds(1, kJ + kW) = -h.ddH3;
  dN_theta_ds(1, kJ + kTy) = h.ddH4;
  dN_theta_ds(2, kV) = h.ddH1;
  dN_theta_ds(2, kTz) = h.ddH2;
  dN_theta_ds(2, kJ + kV) = h.ddH3;
  dN_theta_ds(2, kJ + kTz) = h.ddH4;
}

Vector12d beamEquivalentNodalLoads(double xi, double L, const Eigen::Vector3d& f, const Eigen::Vector3d& m) {
  Matrix3x12 N_u, N_theta;
  beamShapeDisplacement(xi, L, N_u);
  beamShapeRotation(xi, L, N_theta);
  return N_u.transpose() * f + N_theta.transpose() * m;
}

Vector12d beamEquivalentNodalLoadsWorld(double xi, double L, const Eigen::Matrix3d& R_local_to_world,
                                        const Eigen::Vector3d& f_world, const Eigen::Vector3d& m_world) {
  const Eigen::Matrix3d R_world_to_local = R_local_to_world.transpose();
  const Vector12d F_local = beamEquivalentNodalLoads(xi, L, R_world_to_local * f_world, R_world_to_local * m_world);
  Vector12d F_world;
  for (int b = 0; b < 4; ++b) F_world.segment<3>(3 * b) = R_local_to_world * F_local.segment<3>(3 * b);
  return F_world;
}

}  // namespace contact
}  // namespace rail
