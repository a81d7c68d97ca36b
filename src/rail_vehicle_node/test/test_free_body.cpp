// A free rigid body without gravity tumbling about a non-principal axis: kinetic energy, linear and angular
// momentum are invariants of the exact solution and must be kept to the integrator tolerance.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>

#include "rail_vehicle_node/vehicle_integrator.hpp"

namespace rail::vehicle {
namespace {

class FreeBody : public ::testing::TestWithParam<IntegrationMethod> {};

TEST_P(FreeBody, ConservesEnergyAndMomentaOverManyRevolutions) {
  VehicleModel model;
  RigidBody body;
  body.name = "tumbler";
  body.mass = 5.0;
  // Full (non-diagonal) inertia in the body frame: principal moments 1, 2, 3 kg m^2 rotated by R.
  const Matrix3 R = Eigen::AngleAxisd(0.6, Vector3(1.0, 2.0, 0.5).normalized()).toRotationMatrix();
  body.inertia_in_body = R * Vector3(1.0, 2.0, 3.0).asDiagonal() * R.transpose();
  body.r_reference = Vector3(1.0, -2.0, 0.5);
  model.addBody(body);
  model.setGravity(Vector3::Zero());
  model.finalize();
  VehicleData data(model);

  Eigen::VectorXd y0 = model.referenceState();
  y0.segment<3>(model.velocityOffset(0)) = Vector3(0.3, -0.1, 0.2);
  // Mostly about the intermediate principal axis (unstable: the body flips), plus the others.
  y0.segment<3>(model.angularVelocityOffset(0)) = R * Vector3(0.05, 6.0, 0.08);

  IntegratorSettings settings;
  settings.method = GetParam();
  settings.max_order = GetParam() == IntegrationMethod::kBdf ? 5 : 12;
  settings.rtol = 1e-10;
  settings.atol = 1e-12;
  VehicleIntegrator integrator(model, data, y0, 0.0, settings);

  computeKinematics(model, y0, data);
  const double T0 = kineticEnergy(model, data);
  const Vector3 L0 = linearMomentum(model, data);
  const Vector3 H0 = angularMomentum(model, data);

  // 25 s at ~6 rad/s is about 24 revolutions.
  const double t_end = 25.0;
  double max_energy_error = 0.0, max_momentum_error = 0.0, max_linear_error = 0.0;
  for (int k = 1; k <= 250; ++k) {
    integrator.advanceTo(t_end * k / 250.0);
    computeKinematics(model, integrator.state(), data);
    max_energy_error = std::max(max_energy_error, std::abs(kineticEnergy(model, data) - T0) / T0);
    max_momentum_error = std::max(max_momentum_error, (angularMomentum(model, data) - H0).norm() / H0.norm());
    max_linear_error = std::max(max_linear_error, (linearMomentum(model, data) - L0).norm() / L0.norm());
  }
  const IntegratorCounters c = integrator.counters();
  // Local error control at rtol = 1e-10 accumulates over the ~1e3..1e4 steps to at most ~1e-6 relative; the
  // invariants are smooth functions of the state, so their drift is bounded by the same. A wrong gyroscopic
  // term or Euler-parameter kinematics drifts by O(1) within one revolution.
  EXPECT_LT(max_energy_error, 1e-6) << "steps " << c.steps;
  EXPECT_LT(max_momentum_error, 1e-6) << "steps " << c.steps;
  EXPECT_LT(max_linear_error, 1e-9);  // no force at all: r_ddot = 0 up to round-off and error control
  EXPECT_GT(c.steps, 100);
  EXPECT_EQ(c.projections, 0);
  // The body did tumble: the angular velocity in the body frame changed substantially.
  EXPECT_GT(
      (integrator.state().segment<3>(model.angularVelocityOffset(0)) - y0.segment<3>(model.angularVelocityOffset(0)))
          .norm(),
      0.1);
  RecordProperty("max_energy_error", std::to_string(max_energy_error));
  RecordProperty("max_momentum_error", std::to_string(max_momentum_error));
  std::printf("[ free body %s ] steps %ld, rhs %ld, energy drift %.2e, momentum drift %.2e\n",
              GetParam() == IntegrationMethod::kBdf ? "BDF" : "Adams", c.steps, c.rhs_evals, max_energy_error,
              max_momentum_error);
}

INSTANTIATE_TEST_SUITE_P(Methods, FreeBody, ::testing::Values(IntegrationMethod::kAdams, IntegrationMethod::kBdf));

}  // namespace
}  // namespace rail::vehicle
