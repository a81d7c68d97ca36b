// Force elements against closed-form solutions: a mass on a bushing and on a point-to-point spring-damper
// (damped oscillation), a torsional bushing (harmonic rotation), a bump stop (impact with clearance).
#include <gtest/gtest.h>

#include <cmath>

#include "rail_vehicle_node/vehicle_integrator.hpp"

namespace rail::vehicle {
namespace {

constexpr double kMass = 10.0;         // [kg]
constexpr double kStiffness = 4000.0;  // [N/m]
constexpr double kDamping = 40.0;      // [N s/m]  -> zeta = c / (2 sqrt(k m)) = 0.1
constexpr double kX0 = 0.01;           // initial displacement [m]

// Free vibration of m x'' + c x' + k x = 0 from (x0, 0), underdamped.
double dampedOscillation(double t) {
  const double wn = std::sqrt(kStiffness / kMass);
  const double zeta = kDamping / (2.0 * std::sqrt(kStiffness * kMass));
  const double wd = wn * std::sqrt(1.0 - zeta * zeta);
  return std::exp(-zeta * wn * t) * kX0 * (std::cos(wd * t) + zeta * wn / wd * std::sin(wd * t));
}

RigidBody block(const Vector3& r) {
  RigidBody b;
  b.name = "block";
  b.mass = kMass;
  b.inertia_in_body = Vector3(0.2, 0.3, 0.4).asDiagonal();
  b.r_reference = r;
  return b;
}

IntegratorSettings tight() {
  IntegratorSettings s;
  s.rtol = 1e-10;
  s.atol = 1e-13;
  return s;
}

// Tolerance for the oscillators: rtol 1e-10 gives a global error ~1e-8 of the 1e-2 m amplitude over the
// ~10 periods, i.e. ~1e-10 m; 1e-8 m (1e-6 of the amplitude) leaves margin, while a 1 % error in the
// frequency or damping rate shows up as > 1e-5 m.
constexpr double kOscillatorTolerance = 1e-8;

TEST(Bushing, MassMatchesAnalyticDampedOscillation) {
  VehicleModel model;
  const int b = model.addBody(block(Vector3(0.0, 0.0, 1.0)));
  Bushing::Parameters par;
  par.stiffness = Vector3(1e5, 1e5, kStiffness);  // x, y stiff and never excited
  par.damping = Vector3(0.0, 0.0, kDamping);
  model.addBushingAt("mount", kGround, b, Vector3(0.0, 0.0, 1.0), Matrix3::Identity(), par);
  model.setGravity(Vector3::Zero());
  model.finalize();
  VehicleData data(model);
  Eigen::VectorXd y0 = model.referenceState();
  y0[2] += kX0;
  VehicleIntegrator integrator(model, data, y0, 0.0, tight());
  double max_error = 0.0;
  for (int k = 1; k <= 300; ++k) {
    const double t = 0.01 * k;  // 3 s, about 10 periods of 0.31 s
    integrator.advanceTo(t);
    max_error = std::max(max_error, std::abs(integrator.state()[2] - 1.0 - dampedOscillation(t)));
  }
  EXPECT_LT(max_error, kOscillatorTolerance);
  EXPECT_LT(std::abs(integrator.state()[0]) + std::abs(integrator.state()[1]), 1e-14);
}

TEST(Bushing, PreloadBalancesGravityAtTheReference) {
  // Preload m g upward: the reference is the static equilibrium; an offset oscillates about it.
  VehicleModel model;
  const int b = model.addBody(block(Vector3(0.0, 0.0, 1.0)));
  Bushing::Parameters par;
  par.stiffness = Vector3(1e5, 1e5, kStiffness);
  par.damping = Vector3(0.0, 0.0, kDamping);
  par.preload = Vector3(0.0, 0.0, kMass * 9.81);
  model.addBushingAt("mount", kGround, b, Vector3(0.0, 0.0, 1.0), Matrix3::Identity(), par);
  model.finalize();
  VehicleData data(model);
  Eigen::VectorXd y0 = model.referenceState();
  Eigen::VectorXd y_dot(model.stateSize());
  computeDerivatives(model, 0.0, y0, y_dot, data);
  EXPECT_LT(y_dot.norm(), 1e-12);
  y0[2] += kX0;
  VehicleIntegrator integrator(model, data, y0, 0.0, tight());
  integrator.advanceTo(1.234);
  EXPECT_NEAR(integrator.state()[2] - 1.0, dampedOscillation(1.234), kOscillatorTolerance);
}

TEST(PointToPoint, MassMatchesAnalyticDampedOscillation) {
  // Spring along z from a ground point 1 m above the block; free length 1 m; stretched by x0.
  VehicleModel model;
  const int b = model.addBody(block(Vector3::Zero()));
  model.addPointToPointAt("spring", kGround, b, Vector3(0.0, 0.0, 1.0), Vector3::Zero(), kStiffness, kDamping, 1.0,
                          0.0);
  model.setGravity(Vector3::Zero());
  model.finalize();
  VehicleData data(model);
  Eigen::VectorXd y0 = model.referenceState();
  y0[2] -= kX0;  // stretched: pulled back up
  VehicleIntegrator integrator(model, data, y0, 0.0, tight());
  double max_error = 0.0;
  for (int k = 1; k <= 300; ++k) {
    const double t = 0.01 * k;
    integrator.advanceTo(t);
    max_error = std::max(max_error, std::abs(-integrator.state()[2] - dampedOscillation(t)));
  }
  EXPECT_LT(max_error, kOscillatorTolerance);
}

TEST(Bushing, RotationalStiffnessGivesHarmonicRoll) {
  // Single-axis rotation: the rotation vector is exactly the roll angle, so theta'' = -(k_r / J_xx) theta.
  VehicleModel model;
  const int b = model.addBody(block(Vector3::Zero()));
  Bushing::Parameters par;
  par.stiffness = Vector3(1e5, 1e5, 1e5);
  par.rotational_stiffness = Vector3(50.0, 0.0, 0.0);
  model.addBushingAt("torsion", kGround, b, Vector3::Zero(), Matrix3::Identity(), par);
  model.setGravity(Vector3::Zero());
  model.finalize();
  VehicleData data(model);
  Eigen::VectorXd y0 = model.referenceState();
  const double theta0 = 0.3;
  y0.segment<4>(3) = eulerParametersFromRotationVector(Vector3(theta0, 0.0, 0.0));
  VehicleIntegrator integrator(model, data, y0, 0.0, tight());
  const double w = std::sqrt(50.0 / 0.2);
  double max_error = 0.0;
  for (int k = 1; k <= 200; ++k) {
    const double t = 0.01 * k;
    integrator.advanceTo(t);
    const Vector3 theta = rotationVectorFromRotation(rotationFromEulerParameters(integrator.state().segment<4>(3)));
    max_error = std::max(max_error, std::abs(theta.x() - theta0 * std::cos(w * t)));
  }
  EXPECT_LT(max_error, 1e-7);  // rtol 1e-10 on a 0.3 rad amplitude over ~5 periods; margin as above
}

TEST(BumpStop, TableInterpolationAndEnergy) {
  VehicleModel model;
  const int b = model.addBody(block(Vector3::Zero()));
  model.addBumpStopAt("stop", kGround, b, Vector3::Zero(), Vector3::UnitY(), {0.025, 0.030, 0.040},
                      {0.0, 600.0, 3730.0});
  model.finalize();
  const auto* stop = dynamic_cast<const BumpStop*>(model.forceElements()[0].get());
  ASSERT_NE(stop, nullptr);
  EXPECT_DOUBLE_EQ(stop->forceAt(0.02), 0.0);
  EXPECT_DOUBLE_EQ(stop->forceAt(0.025), 0.0);
  EXPECT_NEAR(stop->forceAt(0.0275), 300.0, 1e-9);                     // halfway on the first segment
  EXPECT_NEAR(stop->forceAt(0.035), 0.5 * (600.0 + 3730.0), 1e-9);     // halfway on the second
  EXPECT_NEAR(stop->forceAt(0.045), 3730.0 + 313000.0 * 0.005, 1e-6);  // last slope extended
  VehicleData data(model);
  Eigen::VectorXd y = model.referenceState();
  y[1] = -0.035;  // deflection along -y: same magnitude, opposite force
  computeKinematics(model, y, data);
  // Integral of the piecewise-linear force from 0.025 to 0.035: trapezoids 0.005*300 + 0.005*(600+2165)/2.
  EXPECT_NEAR(stop->potentialEnergy(data), 0.005 * 300.0 + 0.005 * (600.0 + 2165.0) / 2.0, 1e-9);
  data.generalized_forces.setZero();
  stop->addForces(data, data.generalized_forces);
  EXPECT_NEAR(data.generalized_forces[1], +2165.0, 1e-9);  // pushes the block back toward the centre
}

TEST(BumpStop, ImpactWithClearanceMatchesEnergyBalance) {
  // A block sliding along y at v0 enters a linear stop (clearance c, stiffness k): the maximum deflection is
  // c + v0 sqrt(m / k) and it leaves at -v0 (elastic).
  const double c = 0.025, k = 2.0e5, v0 = 0.5;
  VehicleModel model;
  const int b = model.addBody(block(Vector3::Zero()));
  model.addBumpStopAt("stop", kGround, b, Vector3::Zero(), Vector3::UnitY(), {c, c + 1.0}, {0.0, k});
  model.setGravity(Vector3::Zero());
  model.finalize();
  VehicleData data(model);
  Eigen::VectorXd y0 = model.referenceState();
  y0[model.velocityOffset(b) + 1] = v0;
  IntegratorSettings s = tight();
  s.max_step = 1e-3;  // resolve the onset of contact (a kink in the force law)
  VehicleIntegrator integrator(model, data, y0, 0.0, s);
  double max_y = 0.0;
  const double t_contact = c / v0;                               // 0.05 s
  const double t_out = t_contact + M_PI * std::sqrt(kMass / k);  // half a period later: 0.0722 s
  const double t_end = 0.1;  // out of contact, before reaching the opposite stop at 0.05 + 0.0722 + 0.1 s
  ASSERT_GT(t_end, t_out);
  for (int step = 1; step <= 1000; ++step) {
    integrator.advanceTo(step * 1e-4);
    max_y = std::max(max_y, integrator.state()[1]);
  }
  const double expected_max = c + v0 * std::sqrt(kMass / k);
  // Sampling every 1e-4 s near the turning point (curvature v0 w) costs < v0 w (0.5e-4)^2 / 2 ~ 1e-7 m;
  // the kinks at contact are crossed with local error ~rtol: 1e-6 m bounds both.
  EXPECT_NEAR(max_y, expected_max, 1e-6);
  EXPECT_NEAR(integrator.state()[model.velocityOffset(b) + 1], -v0, 1e-5);  // elastic rebound
}

}  // namespace
}  // namespace rail::vehicle
