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

// Row `row` of a shape matrix: a linear field, a at DOF p of node i and b at p of node j.
void placeRow(Matrix3x12& N, int row, int p, double a, double b) {
  N(row, p) = a;
  N(row, kJ + p) = b;
}

// A cubic field: a, b at DOFs p (displacement) and q (slope) of node i, c, d at p, q of node j.
void placeRow(Matrix3x12& N, int row, int p, int q, double a, double b, double c, double d) {
  N(row, p) = a;
  N(row, q) = b;
  N(row, kJ + p) = c;
  N(row, kJ + q) = d;
}

}  // namespace

void beamShapeDisplacement(double xi, double L, Matrix3x12& N_u) {
  const Hermite h = hermite(xi, L);
  N_u.setZero();
  placeRow(N_u, 0, kU, 1.0 - xi, xi);                   // axial u: linear
  placeRow(N_u, 1, kV, kTz, h.H1, h.H2, h.H3, h.H4);    // v (x-y plane, slope theta_z)
  placeRow(N_u, 2, kW, kTy, h.H1, -h.H2, h.H3, -h.H4);  // w (x-z plane, slope -theta_y)
}

void beamShapeRotation(double xi, double L, Matrix3x12& N_theta) {
  const Hermite h = hermite(xi, L);
  N_theta.setZero();
  placeRow(N_theta, 0, kTx, 1.0 - xi, xi);                      // torsion theta_x: linear
  placeRow(N_theta, 1, kW, kTy, -h.dH1, h.dH2, -h.dH3, h.dH4);  // theta_y = -dw/ds
  placeRow(N_theta, 2, kV, kTz, h.dH1, h.dH2, h.dH3, h.dH4);    // theta_z = dv/ds
}

void beamShapeDisplacementDs(double xi, double L, Matrix3x12& dN_u_ds) {
  const Hermite h = hermite(xi, L);
  dN_u_ds.setZero();
  placeRow(dN_u_ds, 0, kU, -1.0 / L, 1.0 / L);
  placeRow(dN_u_ds, 1, kV, kTz, h.dH1, h.dH2, h.dH3, h.dH4);
  placeRow(dN_u_ds, 2, kW, kTy, h.dH1, -h.dH2, h.dH3, -h.dH4);
}

void beamShapeRotationDs(double xi, double L, Matrix3x12& dN_theta_ds) {
  const Hermite h = hermite(xi, L);
  dN_theta_ds.setZero();
  placeRow(dN_theta_ds, 0, kTx, -1.0 / L, 1.0 / L);
  placeRow(dN_theta_ds, 1, kW, kTy, -h.ddH1, h.ddH2, -h.ddH3, h.ddH4);
  placeRow(dN_theta_ds, 2, kV, kTz, h.ddH1, h.ddH2, h.ddH3, h.ddH4);
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
