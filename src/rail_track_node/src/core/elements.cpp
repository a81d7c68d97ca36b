#include "rail_track_node/elements.hpp"

#include <cmath>

namespace rail {
namespace track {

namespace {

// Places the 4x4 planar Hermite matrix m (DOFs: w_i, slope_i, w_j, slope_j with slope = dw/ds) into the
// 12x12 matrix at the given DOF indices; slope_sign = -1 when the nodal rotation is minus the slope.
void placeBending(Matrix12d& out, const Eigen::Matrix4d& m, const int idx[4], double slope_sign) {
  const double sign[4] = {1.0, slope_sign, 1.0, slope_sign};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out(idx[r], idx[c]) += sign[r] * sign[c] * m(r, c);
}

void placeBar(Matrix12d& out, double diag, double off, int i, int j) {
  out(i, i) += diag;
  out(j, j) += diag;
  out(i, j) += off;
  out(j, i) += off;
}

Eigen::Matrix4d hermiteStiffness(double EI, double L) {
  const double L2 = L * L, L3 = L2 * L;
  Eigen::Matrix4d k;
  k << 12.0 / L3, 6.0 / L2, -12.0 / L3, 6.0 / L2,   //
      6.0 / L2, 4.0 / L, -6.0 / L2, 2.0 / L,        //
      -12.0 / L3, -6.0 / L2, 12.0 / L3, -6.0 / L2,  //
      6.0 / L2, 2.0 / L, -6.0 / L2, 4.0 / L;
  return EI * k;
}

Eigen::Matrix4d hermiteMass(double rhoA, double L) {
  const double L2 = L * L;
  Eigen::Matrix4d m;
  m << 156.0, 22.0 * L, 54.0, -13.0 * L,        //
      22.0 * L, 4.0 * L2, 13.0 * L, -3.0 * L2,  //
      54.0, 13.0 * L, 156.0, -22.0 * L,         //
      -13.0 * L, -3.0 * L2, -22.0 * L, 4.0 * L2;
  return (rhoA * L / 420.0) * m;
}

// DOF indices of the two bending planes: x-y plane (v, theta_z = dv/ds) and x-z plane (w, theta_y = -dw/ds).
constexpr int kPlaneXY[4] = {1, 5, 7, 11};
constexpr int kPlaneXZ[4] = {2, 4, 8, 10};

Eigen::Matrix3d skew(const Eigen::Vector3d& r) {
  Eigen::Matrix3d S;
  S << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
  return S;
}

// 6x6 map from one node's world DOFs to the motion of point P (node + r) in the element frame.
Matrix6d pointMotionInElementFrame(const Eigen::Matrix3d& R_local_to_world, const Eigen::Vector3d& r_node_to_P) {
  const Eigen::Matrix3d Rt = R_local_to_world.transpose();
  Matrix6d B = Matrix6d::Zero();
  B.block<3, 3>(0, 0) = Rt;
  B.block<3, 3>(0, 3) = -Rt * skew(r_node_to_P);  // theta x r = -skew(r) theta
  B.block<3, 3>(3, 3) = Rt;
  return B;
}

}  // namespace

Matrix12d beamStiffnessLocal(const BeamSection& s, double L) {
  Matrix12d K = Matrix12d::Zero();
  placeBar(K, s.E * s.A / L, -s.E * s.A / L, 0, 6);
  placeBar(K, s.G * s.J / L, -s.G * s.J / L, 3, 9);
  placeBending(K, hermiteStiffness(s.E * s.I_z, L), kPlaneXY, 1.0);
  placeBending(K, hermiteStiffness(s.E * s.I_y, L), kPlaneXZ, -1.0);
  return K;
}

Matrix12d beamConsistentMassLocal(const BeamSection& s, double L) {
  Matrix12d M = Matrix12d::Zero();
  const double rhoA = s.rho * s.A;
  const double rhoIp = s.rho * (s.I_y + s.I_z);  // polar mass moment per unit length, kg m
  placeBar(M, rhoA * L / 3.0, rhoA * L / 6.0, 0, 6);
  placeBar(M, rhoIp * L / 3.0, rhoIp * L / 6.0, 3, 9);
  placeBending(M, hermiteMass(rhoA, L), kPlaneXY, 1.0);
  placeBending(M, hermiteMass(rhoA, L), kPlaneXZ, -1.0);
  return M;
}

Matrix12d beamWorldToLocal(const Eigen::Matrix3d& R_local_to_world) {
  Matrix12d T = Matrix12d::Zero();
  for (int b = 0; b < 4; ++b) T.block<3, 3>(3 * b, 3 * b) = R_local_to_world.transpose();
  return T;
}

double rayleighDampingRatio(double alpha, double beta, double omega) {
  return alpha / (2.0 * omega) + beta * omega / 2.0;
}

Matrix12d springDamperMatrix(const Vector6d& diag, const Eigen::Matrix3d& R_local_to_world,
                             const Eigen::Vector3d& r_a_to_P, const Eigen::Vector3d& r_b_to_P) {
  Eigen::Matrix<double, 6, 12> B;
  B.leftCols<6>() = -pointMotionInElementFrame(R_local_to_world, r_a_to_P);
  B.rightCols<6>() = pointMotionInElementFrame(R_local_to_world, r_b_to_P);
  return B.transpose() * diag.asDiagonal() * B;
}

Matrix6d groundSpringDamperMatrix(const Vector6d& diag, const Eigen::Matrix3d& R_local_to_world,
                                  const Eigen::Vector3d& r_a_to_P) {
  const Matrix6d B = pointMotionInElementFrame(R_local_to_world, r_a_to_P);
  return B.transpose() * diag.asDiagonal() * B;
}

Vector6d absorbingEndDashpots(const BeamSection& rail, double k_foundation_lateral, double k_foundation_vertical,
                              double omega0) {
  const double rhoA = rail.rho * rail.A;
  auto bending = [&](double EI, double k_f, double& c_force, double& c_moment) {
    double stiff = rhoA * omega0 * omega0 - k_f;
    if (stiff <= 0.0) stiff = rhoA * omega0 * omega0;  // below cut-off: free-beam wave
    const double kappa = std::pow(stiff / EI, 0.25);
    c_force = EI * kappa * kappa * kappa / omega0;
    c_moment = EI * kappa / omega0;
  };
  Vector6d c;
  c(0) = rail.A * std::sqrt(rail.E * rail.rho);
  c(3) = std::sqrt(rail.G * rail.J * rail.rho * (rail.I_y + rail.I_z));
  double cf = 0.0, cm = 0.0;
  bending(rail.E * rail.I_z, k_foundation_lateral, cf, cm);  // lateral: v and theta_z
  c(1) = cf;
  c(5) = cm;
  bending(rail.E * rail.I_y, k_foundation_vertical, cf, cm);  // vertical: w and theta_y
  c(2) = cf;
  c(4) = cm;
  return c;
}

}  // namespace track
}  // namespace rail
