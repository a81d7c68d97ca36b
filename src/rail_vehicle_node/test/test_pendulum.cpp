// A compound pendulum on a revolute joint to the ground under gravity: energy conservation (no damping),
// constraint violation under the projection threshold, and the swing angle against an independent
// fine-step solution of theta'' = -(m g L / I_O) sin(theta).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <memory>

#include "rail_vehicle_node/vehicle_integrator.hpp"

namespace rail::vehicle {
namespace {

constexpr double kMass = 2.0;    // [kg]
constexpr double kLength = 0.5;  // hinge to centre of mass [m]
constexpr double kJyy = 0.2;     // about the centre of mass, hinge direction [kg m^2]
constexpr double kGravity = 9.81;
constexpr double kTheta0 = 1.2;  // initial angle from the downward vertical [rad] (large: nonlinear)

VehicleModel makePendulum(KktSolver solver) {
  VehicleModel model;
  RigidBody body;
  body.name = "bob";
  body.mass = kMass;
  body.inertia_in_body = Vector3(0.15, kJyy, 0.1).asDiagonal();
  body.r_reference = Vector3(0.0, 0.0, -kLength);  // hanging below the hinge at the origin
  const int b = model.addBody(body);
  model.addRevoluteJointAt("hinge", b, kGround, Vector3::Zero(), Vector3::UnitY());
  model.setGravity(Vector3(0.0, 0.0, -kGravity));
  model.setKktSolver(solver);
  model.finalize();
  return model;
}

// Angle from the downward vertical, positive for a right-hand rotation about +y.
double angle(const Eigen::Ref<const Eigen::VectorXd>& y) { return std::atan2(-y[0], -y[2]); }

// Reference: RK4 with step 1e-4 s on the scalar equation (global error ~ (1e-4)^4 * T ~ 1e-15 per unit).
double referenceAngle(double t_end) {
  const double I_O = kJyy + kMass * kLength * kLength;
  const double w2 = kMass * kGravity * kLength / I_O;
  double theta = kTheta0, omega = 0.0;
  const int n = static_cast<int>(std::lround(t_end / 1e-4));
  const double h = t_end / n;
  for (int k = 0; k < n; ++k) {
    const double k1t = omega, k1w = -w2 * std::sin(theta);
    const double k2t = omega + 0.5 * h * k1w, k2w = -w2 * std::sin(theta + 0.5 * h * k1t);
    const double k3t = omega + 0.5 * h * k2w, k3w = -w2 * std::sin(theta + 0.5 * h * k2t);
    const double k4t = omega + h * k3w, k4w = -w2 * std::sin(theta + h * k3t);
    theta += h / 6.0 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t);
    omega += h / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w);
  }
  return theta;
}

class Pendulum : public ::testing::TestWithParam<KktSolver> {};

TEST_P(Pendulum, ConservesEnergyKeepsConstraintAndMatchesScalarSolution) {
  const VehicleModel model = makePendulum(GetParam());
  VehicleData data(model);
  Eigen::VectorXd y0 = model.referenceState();
  const Matrix3 R = Eigen::AngleAxisd(kTheta0, Vector3::UnitY()).toRotationMatrix();
  y0.segment<3>(0) = R * Vector3(0.0, 0.0, -kLength);
  y0.segment<4>(3) = eulerParametersFromRotation(R);

  IntegratorSettings settings;
  settings.method = IntegrationMethod::kBdf;
  settings.rtol = 1e-9;
  settings.atol = 1e-11;
  VehicleIntegrator integrator(model, data, y0, 0.0, settings);
  computeKinematics(model, y0, data);
  const double E0 = kineticEnergy(model, data) + potentialEnergy(model, data);
  const double energy_scale = kMass * kGravity * kLength;  // 9.81 J

  const double t_end = 10.0;  // ~7 periods
  double max_energy_error = 0.0, max_violation = 0.0;
  for (int k = 1; k <= 500; ++k) {
    integrator.advanceTo(t_end * k / 500.0);
    computeKinematics(model, integrator.state(), data);
    const double E = kineticEnergy(model, data) + potentialEnergy(model, data);
    max_energy_error = std::max(max_energy_error, std::abs(E - E0) / energy_scale);
    max_violation = std::max(max_violation, integrator.violation().position);
  }
  // rtol 1e-9 over ~2e3 steps: global state error ~1e-7 relative, energy is a smooth function of it.
  EXPECT_LT(max_energy_error, 1e-6);
  // Baumgarte alone keeps the drift far below the projection threshold (1e-6 m): no projection needed.
  EXPECT_LT(max_violation, settings.projection_position_threshold);
  EXPECT_EQ(integrator.counters().projections, 0);
  // Swing angle against the independent scalar solution; 1e-5 rad covers the ~1e-7 global error with margin,
  // while a wrong inertia (e.g. J_yy missing, period 20% off) misses by O(1) after 7 periods.
  EXPECT_NEAR(angle(integrator.state()), referenceAngle(t_end), 1e-5);
  std::printf("[ pendulum ] steps %ld, energy drift %.2e mgL, max |Phi| %.2e m\n", integrator.counters().steps,
              max_energy_error, max_violation);
}

INSTANTIATE_TEST_SUITE_P(Solvers, Pendulum, ::testing::Values(KktSolver::kRangeSpace, KktSolver::kAugmentedLu));

// A force element that applies nothing and counts the steps it is told were accepted.
class StepCounter : public ForceElement {
 public:
  explicit StepCounter(long* accepted) : ForceElement("step_counter", 0, kGround), accepted_(accepted) {}
  void addForces(const VehicleData&, Eigen::Ref<Eigen::VectorXd>) const override {}
  double potentialEnergy(const VehicleData&) const override { return 0.0; }
  void acceptStep() const override { ++*accepted_; }

 private:
  long* accepted_;
};

// Taking CVODE's steps one at a time (IntegratorSettings::accept_steps) tells the force elements of every
// accepted step, once, and changes nothing else: the same steps, the same interpolated outputs.
TEST(Pendulum, AcceptingStepsOneAtATimeTellsTheElementsAndChangesNoResult) {
  long accepted[2] = {0, 0};
  Eigen::VectorXd end_state[2];
  long steps[2] = {0, 0};
  for (int one_at_a_time = 0; one_at_a_time < 2; ++one_at_a_time) {
    VehicleModel model;
    RigidBody body;
    body.name = "bob";
    body.mass = kMass;
    body.inertia_in_body = Vector3(0.15, kJyy, 0.1).asDiagonal();
    body.r_reference = Vector3(0.0, 0.0, -kLength);
    const int b = model.addBody(body);
    model.addRevoluteJointAt("hinge", b, kGround, Vector3::Zero(), Vector3::UnitY());
    model.addForceElement(std::make_unique<StepCounter>(&accepted[one_at_a_time]));
    model.setGravity(Vector3(0.0, 0.0, -kGravity));
    model.finalize();
    VehicleData data(model);
    Eigen::VectorXd y0 = model.referenceState();
    const Matrix3 R = Eigen::AngleAxisd(kTheta0, Vector3::UnitY()).toRotationMatrix();
    y0.segment<3>(0) = R * Vector3(0.0, 0.0, -kLength);
    y0.segment<4>(3) = eulerParametersFromRotation(R);
    IntegratorSettings settings;
    settings.accept_steps = one_at_a_time == 1;
    VehicleIntegrator integrator(model, data, y0, 0.0, settings);
    // Output instants both finer (several per step) and coarser than the steps.
    for (int k = 1; k <= 400; ++k) integrator.advanceTo(k < 200 ? 1e-4 * k : 0.02 + 0.01 * (k - 200));
    end_state[one_at_a_time] = integrator.state();
    steps[one_at_a_time] = integrator.counters().steps;
  }
  EXPECT_EQ(accepted[0], 0);
  EXPECT_GT(steps[1], 100);
  EXPECT_EQ(accepted[1], steps[1]);
  EXPECT_EQ(steps[0], steps[1]);
  // Bit for bit: the same CVODE steps, interpolated at the same instants.
  EXPECT_EQ(end_state[0], end_state[1]);
}

// The reaction at the hinge at rest hanging straight down is the weight: lambda carries it.
TEST(Pendulum, HangingAtRestHasZeroAccelerationAndCarriesTheWeight) {
  const VehicleModel model = makePendulum(KktSolver::kAugmentedLu);
  VehicleData data(model);
  const Eigen::VectorXd y = model.referenceState();
  Eigen::VectorXd y_dot(model.stateSize());
  computeDerivatives(model, 0.0, y, y_dot, data);
  EXPECT_LT(y_dot.norm(), 1e-12);  // exact equilibrium up to round-off
  // M v_dot + Phi_v^T lambda = g, v_dot = 0  =>  Phi_v^T lambda = g: the joint force balances m g.
  const Eigen::VectorXd reaction = data.phi_v.transpose() * data.lambda;
  EXPECT_NEAR(reaction[2], -kMass * kGravity, 1e-9);
}

}  // namespace
}  // namespace rail::vehicle
