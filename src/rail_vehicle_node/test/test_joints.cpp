// Joint constraints: Phi_v (velocity Jacobian) and gamma against central differences along the exact flow of
// a constant velocity state (r(t) = r + t r_dot, A(t) = A exp(t omega'~), i.e. p(t) = p (x) exp(t omega'/2)).
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "rail_vehicle_node/multibody_dynamics.hpp"

namespace rail::vehicle {
namespace {

RigidBody MakeBody(const std::string& name, const Vector3& r, const Vector3& rotation_vector) {
  RigidBody b;
  b.name = name;
  b.mass = 3.0;
  b.inertia_in_body = Vector3(0.4, 0.5, 0.6).asDiagonal();
  b.r_reference = r;
  b.p_reference = EulerParametersFromRotationVector(rotation_vector);
  return b;
}

// State advanced by time h along the constant-velocity flow.
Eigen::VectorXd Flow(const VehicleModel& model, const Eigen::VectorXd& y, double h) {
  Eigen::VectorXd out = y;
  for (int b = 0; b < model.n_bodies(); ++b) {
    out.segment<3>(VehicleModel::PositionOffset(b)) += h * y.segment<3>(model.VelocityOffset(b));
    out.segment<4>(VehicleModel::EulerOffset(b)) = QuaternionProduct(
        y.segment<4>(VehicleModel::EulerOffset(b)),
        EulerParametersFromRotationVector(h * y.segment<3>(model.AngularVelocityOffset(b))));
  }
  return out;
}

class JointDerivatives : public ::testing::TestWithParam<int> {};

// Model with every joint type, body-body and body-ground; the state is off the constraint manifold (the
// identities Phi_dot = Phi_v v and Phi_ddot = Phi_v v_dot - gamma hold everywhere).
TEST_P(JointDerivatives, JacobianAndGammaMatchCentralDifferences) {
  VehicleModel model;
  const int a = model.AddBody(MakeBody("a", Vector3(0.1, 0.2, 0.3), Vector3(0.2, -0.1, 0.3)));
  const int b = model.AddBody(MakeBody("b", Vector3(1.0, -0.5, 0.2), Vector3(-0.4, 0.2, 0.1)));
  const int c = model.AddBody(MakeBody("c", Vector3(-0.7, 0.4, 1.1), Vector3(0.0, 0.5, -0.2)));
  switch (GetParam()) {
    case 0:
      model.AddRevoluteJointAt("rev_ab", a, b, Vector3(0.5, -0.1, 0.25), Vector3(0.3, 0.9, -0.2).normalized());
      model.AddRevoluteJointAt("rev_c_ground", c, kGround, Vector3(-0.5, 0.3, 1.0), Vector3(1.0, 0.0, 0.2).normalized());
      break;
    case 1:
      model.AddSphericalJointAt("sph_bc", b, c, Vector3(0.2, 0.0, 0.6));
      model.AddSphericalJointAt("sph_a_ground", a, kGround, Vector3(0.0, 0.0, 0.0));
      break;
    default:
      model.AddFixedJointAt("fix_ca", c, a, Vector3(-0.3, 0.3, 0.7));
      model.AddFixedJointAt("fix_b_ground", b, kGround, Vector3(1.2, -0.4, 0.0));
      break;
  }
  model.Finalize();
  VehicleData data(model);
  Eigen::VectorXd y = model.ReferenceState();
  // Move off the reference configuration and give every body a velocity.
  for (int k = 0; k < model.n_bodies(); ++k) {
    y.segment<3>(VehicleModel::PositionOffset(k)) += Vector3(0.01 * k, -0.02, 0.015 * (k + 1));
    y.segment<4>(VehicleModel::EulerOffset(k)) = QuaternionProduct(
        y.segment<4>(VehicleModel::EulerOffset(k)), EulerParametersFromRotationVector(Vector3(0.05, -0.03 * k, 0.02)));
    y.segment<3>(model.VelocityOffset(k)) = Vector3(0.7, -0.3 + 0.2 * k, 0.5);
    y.segment<3>(model.AngularVelocityOffset(k)) = Vector3(1.1 - 0.4 * k, 0.6, -0.8 + 0.3 * k);
  }
  const int m = model.n_constraints();
  const auto v = y.tail(model.n_velocities());

  ComputeKinematics(model, y, data);
  ComputeConstraints(model, data);
  const Eigen::VectorXd phi_dot = data.phi_v * v;
  const Eigen::VectorXd gamma = data.gamma;

  // Central differences with h = 1e-5: truncation ~h^2 * |third derivative| ~ 1e-10 for O(1) data, round-off
  // ~1e-16 / 1e-5 = 1e-11; 1e-7 leaves a wide margin while any wrong term (O(0.1..1)) fails.
  const double h = 1e-5;
  Eigen::VectorXd phi_plus(m), phi_minus(m), phidot_plus(m), phidot_minus(m);
  ComputeKinematics(model, Flow(model, y, h), data);
  ComputeConstraints(model, data);
  phi_plus = data.phi;
  phidot_plus = data.phi_v * v;
  ComputeKinematics(model, Flow(model, y, -h), data);
  ComputeConstraints(model, data);
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
  const int a = model.AddBody(MakeBody("a", Vector3::Zero(), Vector3::Zero()));
  const Vector3 axis = Vector3(0.0, 1.0, 0.0);
  model.AddRevoluteJointAt("hinge", a, kGround, Vector3(0.0, 0.0, 0.5), axis);
  model.Finalize();
  VehicleData data(model);
  Eigen::VectorXd y = model.ReferenceState();
  // Rigid rotation of body a by 0.7 rad about the hinge line.
  const Matrix3 R = Eigen::AngleAxisd(0.7, axis).toRotationMatrix();
  const Vector3 hinge(0.0, 0.0, 0.5);
  y.segment<3>(0) = hinge + R * (Vector3::Zero() - hinge);
  y.segment<4>(3) = EulerParametersFromRotation(R);
  ComputeKinematics(model, y, data);
  ComputeConstraints(model, data);
  EXPECT_LT(data.phi.lpNorm<Eigen::Infinity>(), 1e-14);  // exact up to round-off
  const Matrix3 R_bad = Eigen::AngleAxisd(0.1, Vector3::UnitX()).toRotationMatrix();
  y.segment<3>(0) = hinge + R_bad * (Vector3::Zero() - hinge);
  y.segment<4>(3) = EulerParametersFromRotation(R_bad);
  ComputeKinematics(model, y, data);
  ComputeConstraints(model, data);
  EXPECT_GT(data.phi.lpNorm<Eigen::Infinity>(), 0.05);  // sin(0.1) ~ 0.0998 in an orientation row
}

}  // namespace
}  // namespace rail::vehicle
