// Joint constraints: Phi_v (velocity Jacobian) and gamma against central differences along the exact flow of
// a constant velocity state (r(t) = r + t r_dot, A(t) = A exp(t omega'~), i.e. p(t) = p (x) exp(t omega'/2)).
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "rail_vehicle_node/multibody_dynamics.hpp"

namespace rail::vehicle {
namespace {

RigidBody makeBody(const std::string& name, const Vector3& r, const Vector3& rotation_vector) {
  RigidBody b;
  b.name = name;
  b.mass = 3.0;
  b.inertia_in_body = Vector3(0.4, 0.5, 0.6).asDiagonal();
  b.r_reference = r;
  b.p_reference = eulerParametersFromRotationVector(rotation_vector);
  return b;
}

// State advanced by time h along the constant-velocity flow.
Eigen::VectorXd flow(const VehicleModel& model, const Eigen::VectorXd& y, double h) {
  Eigen::VectorXd out = y;
  for (int b = 0; b < model.nBodies(); ++b) {
    out.segment<3>(VehicleModel::positionOffset(b)) += h * y.segment<3>(model.velocityOffset(b));
    out.segment<4>(VehicleModel::eulerOffset(b)) =
        quaternionProduct(y.segment<4>(VehicleModel::eulerOffset(b)),
                          eulerParametersFromRotationVector(h * y.segment<3>(model.angularVelocityOffset(b))));
  }
  return out;
}

class JointDerivatives : public ::testing::TestWithParam<int> {};

// Model with every joint type, body-body and body-ground; the state is off the constraint manifold (the
// identities Phi_dot = Phi_v v and Phi_ddot = Phi_v v_dot - gamma hold everywhere).
TEST_P(JointDerivatives, JacobianAndGammaMatchCentralDifferences) {
  VehicleModel model;
  const int a = model.addBody(makeBody("a", Vector3(0.1, 0.2, 0.3), Vector3(0.2, -0.1, 0.3)));
  const int b = model.addBody(makeBody("b", Vector3(1.0, -0.5, 0.2), Vector3(-0.4, 0.2, 0.1)));
  const int c = model.addBody(makeBody("c", Vector3(-0.7, 0.4, 1.1), Vector3(0.0, 0.5, -0.2)));
  switch (GetParam()) {
    case 0:
      model.addRevoluteJointAt("rev_ab", a, b, Vector3(0.5, -0.1, 0.25), Vector3(0.3, 0.9, -0.2).normalized());
      model.addRevoluteJointAt("rev_c_ground", c, kGround, Vector3(-0.5, 0.3, 1.0),
                               Vector3(1.0, 0.0, 0.2).normalized());
      break;
    case 1:
      model.addSphericalJointAt("sph_bc", b, c, Vector3(0.2, 0.0, 0.6));
      model.addSphericalJointAt("sph_a_ground", a, kGround, Vector3(0.0, 0.0, 0.0));
      break;
    default:
      model.addFixedJointAt("fix_ca", c, a, Vector3(-0.3, 0.3, 0.7));
      model.addFixedJointAt("fix_b_ground", b, kGround, Vector3(1.2, -0.4, 0.0));
      break;
  }
  model.finalize();
  VehicleData data(model);
  Eigen::VectorXd y = model.referenceState();
  // Move off the reference configuration and give every body a velocity.
  for (int k = 0; k < model.nBodies(); ++k) {
    y.segment<3>(VehicleModel::positionOffset(k)) += Vector3(0.01 * k, -0.02, 0.015 * (k + 1));
    y.segment<4>(VehicleModel::eulerOffset(k)) = quaternionProduct(
        y.segment<4>(VehicleModel::eulerOffset(k)), eulerParametersFromRotationVector(Vector3(0.05, -0.03 * k, 0.02)));
    y.segment<3>(model.velocityOffset(k)) = Vector3(0.7, -0.3 + 0.2 * k, 0.5);
    y.segment<3>(model.angularVelocityOffset(k)) = Vector3(1.1 - 0.4 * k, 0.6, -0.8 + 0.3 * k);
  }
  const int m = model.nConstraints();
  const auto v = y.tail(model.nVelocities());

  computeKinematics(model, y, data);
  computeConstraints(model, data);
  const Eigen::VectorXd phi_dot = data.phi_v * v;
  const Eigen::VectorXd gamma = data.gamma;

  // Central differences with h = 1e-5: truncation ~h^2 * |third derivative| ~ 1e-10 for O(1) data, round-off
  // ~1e-16 / 1e-5 = 1e-11; 1e-7 leaves a wide margin while any wrong term (O(0.1..1)) fails.
  const double h = 1e-5;
  Eigen::VectorXd phi_plus(m), phi_minus(m), phidot_plus(m), phidot_minus(m);
  computeKinematics(model, flow(model, y, h), data);
  computeConstraints(model, data);
  phi_plus = data.phi;
  phidot_plus = data.phi_v * v;
  computeKinematics(model, flow(model, y, -h), data);
  computeConstraints(model, data);
  phi_minus = data.phi;
  phidot_minus = data.phi_v * v;

  const Eigen::VectorXd phi_dot_fd = (phi_plus - phi_minus) / (2.0 * h);
  const Eigen::VectorXd phi_ddot_fd = (phidot_plus - phidot_minus) / (2.0 * h);  // = (d Phi_v/dt) v = -gamma
  for (int r = 0; r < m; ++r) {
    EXPECT_NEAR(phi_dot[r], phi_dot_fd[r], 1e-7) << "row " << r;
    EXPECT_NEAR(gamma[r], -phi_ddot_fd[r], 1e-7) << "row " << r;
  }
  EXPECT_GT(phi_dot.norm(), 1e-2);  // the check is not vacuous
  EXPECT_GT(gamma.norm(), 1e-2);
}

INSTANTIATE_TEST_SUITE_P(AllTypes, JointDerivatives, ::testing::Values(0, 1, 2));

// A revolute joint leaves exactly one relative rotation free: rotating body j about the axis keeps Phi = 0,
// rotating it about a perpendicular axis does not.
TEST(RevoluteJoint, AllowsRotationAboutItsAxisOnly) {
  VehicleModel model;
  const int a = model.addBody(makeBody("a", Vector3::Zero(), Vector3::Zero()));
  const Vector3 axis = Vector3(0.0, 1.0, 0.0);
  model.addRevoluteJointAt("hinge", a, kGround, Vector3(0.0, 0.0, 0.5), axis);
  model.finalize();
  VehicleData data(model);
  Eigen::VectorXd y = model.referenceState();
  // Rigid rotation of body a by 0.7 rad about the hinge line.
  const Matrix3 R = Eigen::AngleAxisd(0.7, axis).toRotationMatrix();
  const Vector3 hinge(0.0, 0.0, 0.5);
  y.segment<3>(0) = hinge + R * (Vector3::Zero() - hinge);
  y.segment<4>(3) = eulerParametersFromRotation(R);
  computeKinematics(model, y, data);
  computeConstraints(model, data);
  EXPECT_LT(data.phi.lpNorm<Eigen::Infinity>(), 1e-14);  // exact up to round-off
  const Matrix3 R_bad = Eigen::AngleAxisd(0.1, Vector3::UnitX()).toRotationMatrix();
  y.segment<3>(0) = hinge + R_bad * (Vector3::Zero() - hinge);
  y.segment<4>(3) = eulerParametersFromRotation(R_bad);
  computeKinematics(model, y, data);
  computeConstraints(model, data);
  EXPECT_GT(data.phi.lpNorm<Eigen::Infinity>(), 0.05);  // sin(0.1) ~ 0.0998 in an orientation row
}

}  // namespace
}  // namespace rail::vehicle
