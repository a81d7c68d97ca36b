// Constraint drift control: a deliberately perturbed state is projected back onto the constraint manifold,
// and the integrator projects (and counts) whenever the violation exceeds its threshold.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>

#include "rail_vehicle_node/vehicle_integrator.hpp"

namespace rail::vehicle {
namespace {

RigidBody makeBody(const std::string& name, const Vector3& r) {
  RigidBody b;
  b.name = name;
  b.mass = 1.5;
  b.inertia_in_body = Vector3(0.05, 0.04, 0.03).asDiagonal();
  b.r_reference = r;
  return b;
}

// A chain with every joint type: link1 hinged to the ground, link2 hinged to link1, ball3 on a spherical
// joint to link2, plate4 welded to ball3.
VehicleModel makeChain(double alpha = 10.0, double beta = 10.0) {
  VehicleModel model;
  const int l1 = model.addBody(makeBody("link1", Vector3(0.0, 0.0, -0.3)));
  const int l2 = model.addBody(makeBody("link2", Vector3(0.0, 0.0, -0.9)));
  const int b3 = model.addBody(makeBody("ball3", Vector3(0.0, 0.0, -1.5)));
  const int p4 = model.addBody(makeBody("plate4", Vector3(0.2, 0.1, -1.8)));
  model.addRevoluteJointAt("hinge1", l1, kGround, Vector3::Zero(), Vector3::UnitY());
  model.addRevoluteJointAt("hinge2", l2, l1, Vector3(0.0, 0.0, -0.6), Vector3(0.0, 1.0, 0.0));
  model.addSphericalJointAt("ball", b3, l2, Vector3(0.0, 0.0, -1.2));
  model.addFixedJointAt("weld", p4, b3, Vector3(0.1, 0.05, -1.65));
  model.setBaumgarte(alpha, beta);
  model.finalize();
  return model;
}

// The reference state perturbed in positions, orientations (also off unit norm) and velocities.
Eigen::VectorXd perturbed(const VehicleModel& model) {
  Eigen::VectorXd y = model.referenceState();
  for (int b = 0; b < model.nBodies(); ++b) {
    y.segment<3>(VehicleModel::positionOffset(b)) += Vector3(2e-3 * (b + 1), -1.5e-3, 1e-3 * b);
    const Vector4 p = quaternionProduct(y.segment<4>(VehicleModel::eulerOffset(b)),
                                        eulerParametersFromRotationVector(Vector3(0.01, -0.02 * b, 0.015)));
    y.segment<4>(VehicleModel::eulerOffset(b)) = 1.02 * p;  // 2 % off the unit norm
    y.segment<3>(model.velocityOffset(b)) = Vector3(0.3 * b, -0.2, 0.1);
    y.segment<3>(model.angularVelocityOffset(b)) = Vector3(0.5, 1.0 - 0.3 * b, -0.4);
  }
  return y;
}

TEST(Projection, PerturbedStateReturnsBelow1e10) {
  const VehicleModel model = makeChain();
  VehicleData data(model);
  Eigen::VectorXd y = perturbed(model);
  const ConstraintViolation before = evaluateViolation(model, y, data);
  ASSERT_GT(before.position, 1e-3);  // the perturbation is real
  ASSERT_GT(before.velocity, 1e-2);
  ASSERT_GT(before.euler_norm, 1e-2);
  const int iterations = projectState(model, y, data, 1e-12, 20);
  const ConstraintViolation after = evaluateViolation(model, y, data);
  EXPECT_LT(after.position, 1e-10);
  EXPECT_LT(after.velocity, 1e-10);
  EXPECT_LT(after.euler_norm, 1e-14);  // normalised: round-off only
  EXPECT_GE(iterations, 1);
  EXPECT_LE(iterations, 6);  // Gauss-Newton converges quadratically from a 1e-3 violation
  // Minimum-norm correction: the projected positions stay close to the perturbed ones (the correction is of
  // the size of the violation, not of the configuration).
  const Eigen::VectorXd y_pert = perturbed(model);
  for (int b = 0; b < model.nBodies(); ++b) {
    EXPECT_LT(
        (y.segment<3>(VehicleModel::positionOffset(b)) - y_pert.segment<3>(VehicleModel::positionOffset(b))).norm(),
        0.05);
  }
}

TEST(Projection, IntegratorProjectsInitialStateAndDriftAboveThreshold) {
  // Without Baumgarte terms and with loose tolerances the drift grows; the integrator must project it back
  // each time it passes the threshold, and count it.
  const VehicleModel model = makeChain(0.0, 0.0);
  VehicleData data(model);
  IntegratorSettings settings;
  settings.rtol = 1e-4;
  settings.atol = 1e-6;
  settings.projection_position_threshold = 1e-8;
  settings.projection_velocity_threshold = 1e-7;
  VehicleIntegrator integrator(model, data, perturbed(model), 0.0, settings);
  EXPECT_EQ(integrator.counters().projections, 1);  // the perturbed initial state
  EXPECT_LT(integrator.violation().position, 1e-10);
  for (int k = 1; k <= 200; ++k) {
    integrator.advanceTo(0.01 * k);
    const ConstraintViolation v = integrator.violation();
    ASSERT_LE(v.position, settings.projection_position_threshold) << "t = " << integrator.time();
    ASSERT_LE(v.velocity, settings.projection_velocity_threshold) << "t = " << integrator.time();
  }
  EXPECT_GT(integrator.counters().projections, 1);
  std::printf("[ projection ] %ld projections in 2 s without Baumgarte\n", integrator.counters().projections);
}

TEST(Projection, InterpolationInsideTheLastStepMatchesTheState) {
  const VehicleModel model = makeChain();
  VehicleData data(model);
  IntegratorSettings settings;
  settings.rtol = 1e-8;
  settings.atol = 1e-10;
  Eigen::VectorXd y0 = model.referenceState();
  y0.segment<3>(model.angularVelocityOffset(0)) = Vector3(0.0, 2.0, 0.0);
  y0.segment<3>(model.velocityOffset(0)) = Vector3(-0.6, 0.0, 0.0);  // consistent with the hinge at the origin
  y0.segment<3>(model.velocityOffset(1)) = Vector3(-1.8, 0.0, 0.0);
  y0.segment<3>(model.angularVelocityOffset(1)) = Vector3(0.0, 2.0, 0.0);
  y0.segment<3>(model.velocityOffset(2)) = Vector3(-3.0, 0.0, 0.0);
  y0.segment<3>(model.angularVelocityOffset(2)) = Vector3(0.0, 2.0, 0.0);
  y0.segment<3>(model.velocityOffset(3)) = Vector3(-3.6, 0.0, -0.4);
  y0.segment<3>(model.angularVelocityOffset(3)) = Vector3(0.0, 2.0, 0.0);
  VehicleIntegrator integrator(model, data, y0, 0.0, settings);
  integrator.advanceTo(0.5);
  double t0 = 0.0, t1 = 0.0;
  integrator.lastStepInterval(t0, t1);
  ASSERT_LT(t0, t1);
  ASSERT_LE(t0, 0.5);
  ASSERT_GE(t1, 0.5);
  Eigen::VectorXd y_interp(model.stateSize());
  integrator.interpolateAt(0.5, y_interp);
  EXPECT_LT((y_interp - integrator.state()).lpNorm<Eigen::Infinity>(), 1e-12);  // CVODE returns the same value
  // Inside the step, the interpolant agrees with a separate run to that time within the tolerance (1e-8
  // relative, state entries O(1): global error ~1e-7; 1e-5 margin).
  const double t_mid = 0.5 * (t0 + t1);
  integrator.interpolateAt(t_mid, y_interp);
  VehicleData data2(model);
  VehicleIntegrator second(model, data2, y0, 0.0, settings);
  second.advanceTo(t_mid);
  EXPECT_LT((y_interp - second.state()).lpNorm<Eigen::Infinity>(), 1e-5);
  EXPECT_THROW(integrator.interpolateAt(t1 + 1.0, y_interp), std::runtime_error);
}

}  // namespace
}  // namespace rail::vehicle
