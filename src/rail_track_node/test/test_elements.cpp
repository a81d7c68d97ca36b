// Element matrices: beam stiffness against closed-form cantilever solutions, consistent mass against the
// analytic frequencies of a simply supported beam, spring-dampers, Rayleigh damping ratio.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "rail_track_node/elements.hpp"

namespace rt = rail::track;

namespace {

constexpr double kPi = 3.14159265358979323846;

// UIC60-like rail section of the paper's Table 1 (only used as realistic magnitudes here).
rt::BeamSection railSection() {
  rt::BeamSection s;
  s.E = 2.10e11;
  s.G = 8.08e10;
  s.A = 7.67e-3;
  s.J = 3.55e-5;
  s.I_y = 3.04e-5;
  s.I_z = 5.12e-6;
  s.rho = 7860.0;
  return s;
}

// Tip displacement of a one-element cantilever (node i clamped) under a tip load (6 entries, local or world).
Eigen::Matrix<double, 6, 1> cantileverTip(const rt::Matrix12d& K, const Eigen::Matrix<double, 6, 1>& load) {
  const rt::Matrix6d Kjj = K.block<6, 6>(6, 6);
  return Kjj.ldlt().solve(load);
}

}  // namespace

// One Hermite element is exact for a tip-loaded cantilever: tip deflection P L^3 / (3 E I) and rotation
// P L^2 / (2 E I) in both planes, PL/EA axially and TL/GJ in torsion. Only roundoff remains: the solve of a
// 6x6 system with condition number ~ E A L^2 / (E I) ~ 1e3 gives ~1e-13; tolerance 1e-10 relative.
TEST(BeamElement, CantileverTipIsExactWithOneElement) {
  const rt::BeamSection s = railSection();
  const double L = 1.3;
  const rt::Matrix12d K = rt::beamStiffnessLocal(s, L);
  const double P = 1.0e5, T = 2.0e4;
  Eigen::Matrix<double, 6, 1> f;

  f << 0, P, 0, 0, 0, 0;  // lateral load: bending with I_z
  auto d = cantileverTip(K, f);
  EXPECT_NEAR(d(1), P * L * L * L / (3.0 * s.E * s.I_z), 1e-10 * std::abs(d(1)));
  EXPECT_NEAR(d(5), P * L * L / (2.0 * s.E * s.I_z), 1e-10 * std::abs(d(5)));

  f << 0, 0, P, 0, 0, 0;  // vertical load: bending with I_y, theta_y = -dw/ds
  d = cantileverTip(K, f);
  EXPECT_NEAR(d(2), P * L * L * L / (3.0 * s.E * s.I_y), 1e-10 * std::abs(d(2)));
  EXPECT_NEAR(d(4), -P * L * L / (2.0 * s.E * s.I_y), 1e-10 * std::abs(d(4)));

  f << P, 0, 0, 0, 0, 0;
  d = cantileverTip(K, f);
  EXPECT_NEAR(d(0), P * L / (s.E * s.A), 1e-10 * std::abs(d(0)));

  f << 0, 0, 0, T, 0, 0;
  d = cantileverTip(K, f);
  EXPECT_NEAR(d(3), T * L / (s.G * s.J), 1e-10 * std::abs(d(3)));
}

// Same cantilever with the element rotated arbitrarily in the world (K_world = T^T K_local T): the world
// response to a world load along the rotated local z must be the rotated local response (1e-10 relative).
TEST(BeamElement, RotatedCantileverMatchesLocalSolution) {
  const rt::BeamSection s = railSection();
  const double L = 0.6, P = 5.0e4;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, -1.0, 0.4).normalized()).toRotationMatrix();
  const rt::Matrix12d T = rt::beamWorldToLocal(R);
  const rt::Matrix12d K_world = T.transpose() * rt::beamStiffnessLocal(s, L) * T;
  Eigen::Matrix<double, 6, 1> f = Eigen::Matrix<double, 6, 1>::Zero();
  f.head<3>() = P * R.col(2);
  const auto d = cantileverTip(K_world, f);
  const Eigen::Vector3d u_local = R.transpose() * d.head<3>();
  const double w = P * L * L * L / (3.0 * s.E * s.I_y);
  EXPECT_NEAR(u_local(2), w, 1e-10 * w);
  EXPECT_NEAR(u_local(0), 0.0, 1e-10 * w);
  EXPECT_NEAR(u_local(1), 0.0, 1e-10 * w);
}

// Stiffness is symmetric and has exactly 6 zero eigenvalues (rigid-body modes); mass is symmetric positive
// definite and its translational part sums to the element mass rho A L (1e-12 relative: sums of O(1) terms).
TEST(BeamElement, StiffnessRigidModesAndMassTotal) {
  const rt::BeamSection s = railSection();
  const double L = 0.1;
  const rt::Matrix12d K = rt::beamStiffnessLocal(s, L);
  const rt::Matrix12d M = rt::beamConsistentMassLocal(s, L);
  EXPECT_LT((K - K.transpose()).norm(), 1e-12 * K.norm());
  EXPECT_LT((M - M.transpose()).norm(), 1e-12 * M.norm());
  // Rigid translation along each axis and rigid rotation about x: K u = 0; u' M u = mass (or rho Ip L).
  for (int axis = 0; axis < 3; ++axis) {
    Eigen::Matrix<double, 12, 1> u = Eigen::Matrix<double, 12, 1>::Zero();
    u(axis) = u(6 + axis) = 1.0;
    EXPECT_LT((K * u).norm(), 1e-12 * K.norm());
    EXPECT_NEAR(u.dot(M * u), s.rho * s.A * L, 1e-12 * s.rho * s.A * L);
  }
  Eigen::Matrix<double, 12, 1> rx = Eigen::Matrix<double, 12, 1>::Zero();
  rx(3) = rx(9) = 1.0;
  const double polar_mass = s.rho * (s.I_y + s.I_z) * L;
  EXPECT_NEAR(rx.dot(M * rx), polar_mass, 1e-12 * polar_mass);
  Eigen::SelfAdjointEigenSolver<rt::Matrix12d> eigK(K);
  int zero = 0;
  for (int i = 0; i < 12; ++i) zero += std::abs(eigK.eigenvalues()(i)) < 1e-9 * eigK.eigenvalues().maxCoeff();
  EXPECT_EQ(zero, 6);
  Eigen::SelfAdjointEigenSolver<rt::Matrix12d> eigM(M);
  EXPECT_GT(eigM.eigenvalues().minCoeff(), 0.0);
}

// Simply supported beam of 10 elements: bending frequencies (n pi / L)^2 sqrt(E I / (rho A)) for n = 1..4
// in both planes within 0.5 % (the required accuracy; Hermite elements with consistent mass converge as h^4,
// the actual error for n = 4 is ~1e-4). Torsion and axial (one end restrained: fixed-free) first frequency
// (pi / 2L) sqrt(G J / (rho Ip)) and (pi / 2L) sqrt(E / rho), linear elements, error ~ (pi/20)^2 / 24 ~ 1e-3,
// within 0.5 %. The torsional check exercises the polar mass term.
TEST(BeamElement, SimplySupportedFrequencies) {
  const rt::BeamSection s = railSection();
  const int n_el = 10;
  const double L = 6.0, h = L / n_el;
  const int n_dof = 6 * (n_el + 1);
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n_dof, n_dof), M = Eigen::MatrixXd::Zero(n_dof, n_dof);
  const rt::Matrix12d Ke = rt::beamStiffnessLocal(s, h), Me = rt::beamConsistentMassLocal(s, h);
  for (int e = 0; e < n_el; ++e) {
    K.block<12, 12>(6 * e, 6 * e) += Ke;
    M.block<12, 12>(6 * e, 6 * e) += Me;
  }
  // Supports: node 0 u, v, w, theta_x; last node v, w.
  std::vector<int> fixed = {0, 1, 2, 3, 6 * n_el + 1, 6 * n_el + 2};
  std::vector<int> free;
  for (int i = 0; i < n_dof; ++i)
    if (std::find(fixed.begin(), fixed.end(), i) == fixed.end()) free.push_back(i);
  const int nf = static_cast<int>(free.size());
  Eigen::MatrixXd Kf(nf, nf), Mf(nf, nf);
  for (int r = 0; r < nf; ++r)
    for (int c = 0; c < nf; ++c) {
      Kf(r, c) = K(free[r], free[c]);
      Mf(r, c) = M(free[r], free[c]);
    }
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(Kf, Mf);
  ASSERT_EQ(eig.info(), Eigen::Success);

  // Classify each mode by the DOF family carrying most of its kinetic energy: 0 axial, 1 lateral (v,
  // theta_z), 2 vertical (w, theta_y), 3 torsion.
  std::vector<std::vector<double>> omega(4);
  for (int m = 0; m < nf; ++m) {
    const Eigen::VectorXd phi = eig.eigenvectors().col(m);
    Eigen::VectorXd full = Eigen::VectorXd::Zero(n_dof);
    for (int r = 0; r < nf; ++r) full(free[r]) = phi(r);
    double energy[4] = {0, 0, 0, 0};
    const int family[6] = {0, 1, 2, 3, 2, 1};
    const Eigen::VectorXd Mfull = M * full;
    for (int i = 0; i < n_dof; ++i) energy[family[i % 6]] += full(i) * Mfull(i);
    const int best = static_cast<int>(std::max_element(energy, energy + 4) - energy);
    omega[best].push_back(std::sqrt(eig.eigenvalues()(m)));
  }
  for (auto& w : omega) std::sort(w.begin(), w.end());
  ASSERT_GE(omega[1].size(), 4u);
  ASSERT_GE(omega[2].size(), 4u);
  for (int n = 1; n <= 4; ++n) {
    const double k2 = std::pow(n * kPi / L, 2);
    const double w_lat = k2 * std::sqrt(s.E * s.I_z / (s.rho * s.A));
    const double w_vert = k2 * std::sqrt(s.E * s.I_y / (s.rho * s.A));
    EXPECT_NEAR(omega[1][n - 1] / w_lat, 1.0, 5e-3) << "lateral mode " << n;
    EXPECT_NEAR(omega[2][n - 1] / w_vert, 1.0, 5e-3) << "vertical mode " << n;
  }
  const double w_tor = kPi / (2.0 * L) * std::sqrt(s.G * s.J / (s.rho * (s.I_y + s.I_z)));
  const double w_ax = kPi / (2.0 * L) * std::sqrt(s.E / s.rho);
  ASSERT_FALSE(omega[3].empty());
  ASSERT_FALSE(omega[0].empty());
  EXPECT_NEAR(omega[3][0] / w_tor, 1.0, 5e-3);
  EXPECT_NEAR(omega[0][0] / w_ax, 1.0, 5e-3);
}

// A spring-damper with arbitrary attachment offsets does not resist a rigid-body motion of its two nodes,
// and a relative translation delta along element axis q gives the force k_q delta on node b along that
// axis. Both are exact algebraic identities: tolerance 1e-12 relative to the largest term.
TEST(SpringDamper, RigidInvarianceAndDirectionalStiffness) {
  std::mt19937 gen(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  rt::Vector6d k;
  k << 4e7, 1e7, 1.3e8, 2e5, 3e4, 5e4;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d x_a(0.1, 0.2, 0.3), x_b(0.2, -0.1, 0.0), P(0.15, 0.05, 0.2);
  const rt::Matrix12d K = rt::springDamperMatrix(k, R, P - x_a, P - x_b);
  EXPECT_LT((K - K.transpose()).norm(), 1e-12 * K.norm());
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Vector3d t(u(gen), u(gen), u(gen)), w(u(gen), u(gen), u(gen));
    Eigen::Matrix<double, 12, 1> d;
    d << t + w.cross(x_a), w, t + w.cross(x_b), w;
    EXPECT_LT((K * d).norm(), 1e-12 * K.norm() * d.norm());
  }
  for (int q = 0; q < 3; ++q) {
    Eigen::Matrix<double, 12, 1> d = Eigen::Matrix<double, 12, 1>::Zero();
    d.segment<3>(6) = 1e-3 * R.col(q);  // node b moves along element axis q
    const Eigen::Matrix<double, 12, 1> F = K * d;
    EXPECT_LT((F.segment<3>(6) - k(q) * 1e-3 * R.col(q)).norm(), 1e-12 * k.maxCoeff() * 1e-3);
    EXPECT_LT((F.segment<3>(0) + F.segment<3>(6)).norm(), 1e-12 * k.maxCoeff() * 1e-3);
  }
  // Grounded version equals the two-node one with node b removed.
  const rt::Matrix6d Kg = rt::groundSpringDamperMatrix(k, R, P - x_a);
  EXPECT_LT((Kg - K.block<6, 6>(0, 0)).norm(), 1e-12 * K.norm());
}

// Rayleigh damping ratio at 50 Hz and 1 kHz for the literal reading of the paper's Table 1
// (alpha = 3.98e-4 1/s, beta = 0.94 s) and the swapped reading (alpha = 0.94, beta = 3.98e-4). Expected
// values are the hand evaluations of alpha / (2 omega) + beta omega / 2 written in doc/fe.md, rounded to
// 5 significant digits, hence the 1e-4 relative tolerance.
TEST(Rayleigh, DampingRatioFiguresInDoc) {
  const double w50 = 2.0 * kPi * 50.0, w1k = 2.0 * kPi * 1000.0;
  EXPECT_NEAR(rt::rayleighDampingRatio(3.98e-4, 0.94, w50), 147.65, 147.65 * 1e-4);
  EXPECT_NEAR(rt::rayleighDampingRatio(3.98e-4, 0.94, w1k), 2953.1, 2953.1 * 1e-4);
  EXPECT_NEAR(rt::rayleighDampingRatio(0.94, 3.98e-4, w50), 0.064014, 0.064014 * 1e-4);
  EXPECT_NEAR(rt::rayleighDampingRatio(0.94, 3.98e-4, w1k), 1.2504, 1.2504 * 1e-4);
}

// Absorbing-end dashpots: axial A sqrt(E rho) and, for the free beam (no foundation), the flexural-wave end
// impedances rho A c_p and E I / c_p with phase speed c_p = sqrt(omega) (E I / (rho A))^(1/4)
// (closed forms; 1e-12 relative).
TEST(AbsorbingEnds, DashpotsMatchWaveImpedances) {
  const rt::BeamSection s = railSection();
  const double w0 = 2.0 * kPi * 500.0;
  const rt::Vector6d c = rt::absorbingEndDashpots(s, 0.0, 0.0, w0);
  EXPECT_NEAR(c(0), s.A * std::sqrt(s.E * s.rho), 1e-12 * c(0));
  const double cp_v = std::sqrt(w0) * std::pow(s.E * s.I_y / (s.rho * s.A), 0.25);
  EXPECT_NEAR(c(2), s.rho * s.A * cp_v, 1e-12 * c(2));
  EXPECT_NEAR(c(4), s.E * s.I_y / cp_v, 1e-12 * c(4));
  const double cp_l = std::sqrt(w0) * std::pow(s.E * s.I_z / (s.rho * s.A), 0.25);
  EXPECT_NEAR(c(1), s.rho * s.A * cp_l, 1e-12 * c(1));
  EXPECT_NEAR(c(5), s.E * s.I_z / cp_l, 1e-12 * c(5));
}
