// Tests of the beam element shape functions and of the equivalent nodal loads (paper eq. 16).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "rail_contact/beam_shape.hpp"

namespace rc = rail::contact;

namespace {

Eigen::Vector3d randomVector(std::mt19937& gen, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return Eigen::Vector3d(u(gen), u(gen), u(gen));
}

// Nodal DOFs of a rigid-body motion (translation t, small rotation omega about the local origin = node i)
// of an element of length L along local x.
rc::Vector12d rigidNodalDofs(const Eigen::Vector3d& t, const Eigen::Vector3d& omega, double L) {
  rc::Vector12d d;
  const Eigen::Vector3d x_i = Eigen::Vector3d::Zero();
  const Eigen::Vector3d x_j(L, 0.0, 0.0);
  d.segment<3>(0) = t + omega.cross(x_i);
  d.segment<3>(3) = omega;
  d.segment<3>(6) = t + omega.cross(x_j);
  d.segment<3>(9) = omega;
  return d;
}

}  // namespace

// The nodal loads must be statically equivalent to the applied force and moment: same resultant and same
// moment about any point. Both sides are sums of O(1) products, so the tolerance is a few ulps of the
// largest term (1e-12 relative to |f| L + |m|).
TEST(BeamShape, NodalLoadsAreStaticallyEquivalent) {
  std::mt19937 gen(42);
  std::uniform_real_distribution<double> uxi(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const double L = 0.1 + 2.0 * uxi(gen);
    const double xi = (trial == 0) ? 0.0 : (trial == 1) ? 1.0 : uxi(gen);
    const Eigen::Vector3d f = randomVector(gen, 1e5);
    const Eigen::Vector3d m = randomVector(gen, 1e4);
    const rc::Vector12d F = rc::beamEquivalentNodalLoads(xi, L, f, m);

    const Eigen::Vector3d x_i = Eigen::Vector3d::Zero();
    const Eigen::Vector3d x_j(L, 0.0, 0.0);
    const Eigen::Vector3d x_load(xi * L, 0.0, 0.0);
    const double scale = f.norm() * (L + 10.0) + m.norm();

    const Eigen::Vector3d resultant = F.segment<3>(0) + F.segment<3>(6);
    EXPECT_LT((resultant - f).norm(), 1e-12 * scale);

    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d P = randomVector(gen, 10.0);  // arbitrary reference point
      const Eigen::Vector3d moment_nodes =
          (x_i - P).cross(F.segment<3>(0)) + F.segment<3>(3) + (x_j - P).cross(F.segment<3>(6)) + F.segment<3>(9);
      const Eigen::Vector3d moment_applied = (x_load - P).cross(f) + m;
      EXPECT_LT((moment_nodes - moment_applied).norm(), 1e-12 * scale);
    }
  }
}

// Same equivalence with the element placed in the world by an arbitrary rotation, using the world-frame API.
TEST(BeamShape, NodalLoadsWorldFrameAreStaticallyEquivalent) {
  std::mt19937 gen(7);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Matrix3d R =
        Eigen::Quaterniond(Eigen::Vector4d(randomVector(gen, 1.0).homogeneous()).normalized()).toRotationMatrix();
    const double L = 0.6;
    const double xi = 0.37;
    const Eigen::Vector3d f = randomVector(gen, 1e5), m = randomVector(gen, 1e4);
    const rc::Vector12d F = rc::beamEquivalentNodalLoadsWorld(xi, L, R, f, m);
    const Eigen::Vector3d x_i(1.0, -2.0, 0.5);  // world position of node i
    const Eigen::Vector3d x_j = x_i + R.col(0) * L;
    const Eigen::Vector3d x_load = x_i + R.col(0) * xi * L;
    const double scale = f.norm() * 10.0 + m.norm();
    EXPECT_LT((F.segment<3>(0) + F.segment<3>(6) - f).norm(), 1e-12 * scale);
    const Eigen::Vector3d moment_nodes =
        x_i.cross(F.segment<3>(0)) + F.segment<3>(3) + x_j.cross(F.segment<3>(6)) + F.segment<3>(9);
    EXPECT_LT((moment_nodes - (x_load.cross(f) + m)).norm(), 1e-12 * scale);
  }
}

// A rigid-body motion of the nodes must give the rigid motion at every xi: u(xi) = t + omega x x(xi),
// theta(xi) = omega, du/ds = omega x e_x, dtheta/ds = 0. Exact polynomial identities: 1e-12 tolerance.
TEST(BeamShape, RigidBodyMotionIsReproduced) {
  std::mt19937 gen(3);
  std::uniform_real_distribution<double> uxi(0.0, 1.0);
  rc::Matrix3x12 N_u, N_theta, dN_u, dN_theta;
  for (int trial = 0; trial < 100; ++trial) {
    const double L = 0.05 + 3.0 * uxi(gen);
    const double xi = uxi(gen);
    const Eigen::Vector3d t = randomVector(gen, 1e-3), omega = randomVector(gen, 1e-3);
    const rc::Vector12d d = rigidNodalDofs(t, omega, L);
    rc::beamShapeDisplacement(xi, L, N_u);
    rc::beamShapeRotation(xi, L, N_theta);
    rc::beamShapeDisplacementDs(xi, L, dN_u);
    rc::beamShapeRotationDs(xi, L, dN_theta);
    const Eigen::Vector3d x(xi * L, 0.0, 0.0);
    EXPECT_LT((N_u * d - (t + omega.cross(x))).norm(), 1e-12 * 1e-3 * (1.0 + L));
    EXPECT_LT((N_theta * d - omega).norm(), 1e-12 * 1e-3 * (1.0 + 1.0 / L));
    EXPECT_LT((dN_u * d - omega.cross(Eigen::Vector3d::UnitX())).norm(), 1e-12 * 1e-3 * (1.0 + 1.0 / L));
    EXPECT_LT((dN_theta * d).norm(), 1e-12 * 1e-3 * (1.0 + 1.0 / (L * L)));
  }
}

// At the nodes the interpolation returns the nodal values (interpolation property), exactly.
TEST(BeamShape, InterpolatesNodalValues) {
  const double L = 0.6;
  rc::Matrix3x12 N_u, N_theta;
  rc::beamShapeDisplacement(0.0, L, N_u);
  rc::beamShapeRotation(0.0, L, N_theta);
  rc::Matrix3x12 expect_u = rc::Matrix3x12::Zero(), expect_theta = rc::Matrix3x12::Zero();
  expect_u.block<3, 3>(0, 0).setIdentity();
  expect_theta.block<3, 3>(0, 3).setIdentity();
  EXPECT_LT((N_u - expect_u).norm(), 1e-15);
  EXPECT_LT((N_theta - expect_theta).norm(), 1e-14);
  rc::beamShapeDisplacement(1.0, L, N_u);
  rc::beamShapeRotation(1.0, L, N_theta);
  expect_u.setZero();
  expect_theta.setZero();
  expect_u.block<3, 3>(0, 6).setIdentity();
  expect_theta.block<3, 3>(0, 9).setIdentity();
  EXPECT_LT((N_u - expect_u).norm(), 1e-15);
  EXPECT_LT((N_theta - expect_theta).norm(), 1e-14);
}

// The s-derivatives agree with central finite differences (step h = 1e-6 L: truncation O(h^2) ~ 1e-12,
// roundoff ~ 1e-16 / 1e-6 = 1e-10, hence 1e-8 tolerance on O(1 / L^2) entries), and the Euler-Bernoulli
// kinematics hold: theta_z = dv/ds, theta_y = -dw/ds.
TEST(BeamShape, DerivativesMatchFiniteDifferences) {
  const double L = 0.7;
  const double h = 1e-6;
  for (double xi : {0.1, 0.33, 0.5, 0.9}) {
    rc::Matrix3x12 Np, Nm, dN, Tp, Tm, dT, N_theta;
    rc::beamShapeDisplacement(xi + h, L, Np);
    rc::beamShapeDisplacement(xi - h, L, Nm);
    rc::beamShapeDisplacementDs(xi, L, dN);
    EXPECT_LT(((Np - Nm) / (2.0 * h * L) - dN).cwiseAbs().maxCoeff(), 1e-8);
    rc::beamShapeRotation(xi + h, L, Tp);
    rc::beamShapeRotation(xi - h, L, Tm);
    rc::beamShapeRotationDs(xi, L, dT);
    EXPECT_LT(((Tp - Tm) / (2.0 * h * L) - dT).cwiseAbs().maxCoeff(), 1e-8);
    rc::beamShapeRotation(xi, L, N_theta);
    EXPECT_LT((N_theta.row(2) - dN.row(1)).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_LT((N_theta.row(1) + dN.row(2)).cwiseAbs().maxCoeff(), 1e-14);
  }
}
