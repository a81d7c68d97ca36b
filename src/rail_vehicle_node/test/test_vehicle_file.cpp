// The paper's coach data file: contents (Table 3), static equilibrium on stand-in wheel springs, and the
// loader's error messages.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "rail_vehicle_node/vehicle_integrator.hpp"
#include "rail_vehicle_node/vehicle_loader.hpp"

#ifndef RAIL_VEHICLE_CONFIG_DIR
#define RAIL_VEHICLE_CONFIG_DIR "config/vehicle"
#endif

namespace rail::vehicle {
namespace {

const std::string kCoach = std::string(RAIL_VEHICLE_CONFIG_DIR) + "/paper_coach.yaml";

TEST(PaperCoach, MatchesTable3) {
  const VehicleModel model = loadVehicleModel(kCoach);
  EXPECT_EQ(model.nBodies(), 15);
  EXPECT_EQ(model.joints().size(), 8u);
  EXPECT_EQ(model.nConstraints(), 8 * 5);         // revolute joints
  EXPECT_NEAR(model.totalMass(), 59480.0, 1e-9);  // Table 3 sum; integers, exact in floating point
  EXPECT_EQ(model.loadPoints().size(), 8u);
  // Spot checks against Table 3.
  const RigidBody& carbody = model.bodies()[static_cast<std::size_t>(model.bodyIndex("carbody"))];
  EXPECT_DOUBLE_EQ(carbody.mass, 46200.0);
  EXPECT_DOUBLE_EQ(carbody.r_reference.z(), 1.432);
  EXPECT_DOUBLE_EQ(carbody.inertia_in_body(1, 1), 2600000.0);
  const RigidBody& ab = model.bodies()[static_cast<std::size_t>(model.bodyIndex("ab3_right"))];
  EXPECT_DOUBLE_EQ(ab.r_reference.x(), 3.35);
  EXPECT_DOUBLE_EQ(ab.r_reference.y(), -1.072);
  // Wheel centres on the axle at y = +-0.8665 m.
  const LoadPoint& wheel = model.loadPoints()[static_cast<std::size_t>(model.loadPointIndex("ws2_wheel_right"))];
  EXPECT_EQ(wheel.body, model.bodyIndex("ws2"));
  EXPECT_NEAR(wheel.s_in_body.y(), -0.8665, 1e-12);
  EXPECT_NEAR(wheel.s_in_body.x(), 0.0, 1e-12);
  EXPECT_NEAR(wheel.s_in_body.z(), 0.0, 1e-12);
}

// The wheel span the vehicle node sends in the handshake: first to last wheel centre of the data file.
TEST(PaperCoach, WheelSpanIsFirstToLastWheelCentre) {
  const VehicleModel model = loadVehicleModel(kCoach);
  EXPECT_NEAR(model.wheelSpan(), 22.35 - 0.65, 1e-12);  // load points at x = 0.65 .. 22.35 m
  VehicleModel none;
  EXPECT_EQ(none.wheelSpan(), 0.0);
}

TEST(PaperCoach, ReferenceConfigurationSatisfiesJointsAndSuspensionBalancesGravity) {
  // With the wheelsets held (their weight plus the suspension load taken by the wheel wrenches) the data
  // file's preloads make the reference configuration an equilibrium: every acceleration vanishes.
  const VehicleModel model = loadVehicleModel(kCoach);
  VehicleData data(model);
  const Eigen::VectorXd y = model.referenceState();
  const double wheel_load = 59480.0 * 9.81 / 8.0;  // 72937.35 N
  for (auto& w : data.external) w.force_in_world = Vector3(0.0, 0.0, wheel_load);
  Eigen::VectorXd y_dot(model.stateSize());
  computeDerivatives(model, 0.0, y, y_dot, data);
  EXPECT_LT(data.phi.lpNorm<Eigen::Infinity>(), 1e-15);
  // Accelerations are force residuals / mass: preloads are exact to 1e-10 N relative, so 1e-9 m/s^2.
  EXPECT_LT(y_dot.tail(model.nVelocities()).lpNorm<Eigen::Infinity>(), 1e-9);
}

// The shipped two-coach train (scripts/make_train.py from the coach): two coaches' bodies and wheels, the
// second 24.5 m behind the first, and a coupler that carries nothing at the reference configuration, so
// that the coach's preloads still balance gravity with W/8 on every wheel.
TEST(PaperTrain, TwoCoachesInEquilibriumWithTheCouplerUnloaded) {
  const VehicleModel model = loadVehicleModel(std::string(RAIL_VEHICLE_CONFIG_DIR) + "/paper_coach_x2.yaml");
  EXPECT_EQ(model.nBodies(), 30);
  EXPECT_EQ(model.nConstraints(), 16 * 5);
  EXPECT_NEAR(model.totalMass(), 2 * 59480.0, 1e-9);
  ASSERT_EQ(model.loadPoints().size(), 16u);
  EXPECT_NEAR(model.wheelSpan(), 22.35 - (0.65 - 24.5), 1e-12);
  EXPECT_DOUBLE_EQ(model.bodies()[static_cast<std::size_t>(model.bodyIndex("ws5"))].r_reference.x(), 22.35 - 24.5);
  EXPECT_GE(model.bodyIndex("carbody_c2"), 0);
  VehicleData data(model);
  const Eigen::VectorXd y = model.referenceState();
  for (auto& w : data.external) w.force_in_world = Vector3(0.0, 0.0, 59480.0 * 9.81 / 8.0);
  Eigen::VectorXd y_dot(model.stateSize());
  computeDerivatives(model, 0.0, y, y_dot, data);
  EXPECT_LT(data.phi.lpNorm<Eigen::Infinity>(), 1e-15);
  // As for the coach: residual forces of the exact preloads over the masses, 1e-9 m/s^2.
  EXPECT_LT(y_dot.tail(model.nVelocities()).lpNorm<Eigen::Infinity>(), 1e-9);
}

TEST(PaperCoach, AugmentedLuAndRangeSpaceSolvesAgree) {
  // Both solvers of [M Phi_v^T; Phi_v 0][v_dot; lambda] = [g; c] must give the same solution on a general
  // state (moving, bump stops engaged, anti-roll bars twisted, constraints slightly violated). The system is
  // well conditioned after scaling (masses 10..46200 kg): agreement to 1e-8 relative is round-off level.
  Eigen::VectorXd v_dot[2], lambda[2];
  const KktSolver solvers[2] = {KktSolver::kAugmentedLu, KktSolver::kRangeSpace};
  for (int s = 0; s < 2; ++s) {
    VehicleModel model;
    loadVehicleInto(kCoach, model);
    model.setKktSolver(solvers[s]);
    model.finalize();
    VehicleData data(model);
    Eigen::VectorXd y = model.referenceState();
    const int carbody = model.bodyIndex("carbody");
    y[VehicleModel::positionOffset(carbody) + 1] += 0.03;
    y.segment<4>(VehicleModel::eulerOffset(carbody)) = eulerParametersFromRotationVector(Vector3(0.01, 0.0, 0.002));
    y[VehicleModel::positionOffset(model.bodyIndex("ab2_right")) + 2] += 1e-5;
    for (int b = 0; b < model.nBodies(); ++b) {
      y.segment<3>(model.velocityOffset(b)) = Vector3(30.0, 0.01 * b, -0.02);
      y.segment<3>(model.angularVelocityOffset(b)) = Vector3(0.01, 0.02 * (b % 3), 0.005);
    }
    Eigen::VectorXd y_dot(model.stateSize());
    computeDerivatives(model, 0.0, y, y_dot, data);
    v_dot[s] = data.v_dot;
    lambda[s] = data.lambda;
  }
  EXPECT_LT((v_dot[0] - v_dot[1]).norm(), 1e-8 * v_dot[1].norm());
  EXPECT_LT((lambda[0] - lambda[1]).norm(), 1e-8 * lambda[1].norm());
  EXPECT_GT(lambda[1].norm(), 1e3);  // the joints carry load in this state
}

TEST(PaperCoach, StaticEquilibriumOnWheelSpringsCarriesOneEighthPerWheel) {
  // Stand-in for the contact: a spring-damper from the ground to each wheel centre, vertical 2e7 N/m with
  // 3.9e5 N s/m (about half critical for the whole vehicle bouncing on the eight springs), plus soft
  // longitudinal/lateral support. The vehicle starts at the reference configuration with the wheel springs
  // unloaded and drops onto them.
  VehicleModel model;
  loadVehicleInto(kCoach, model);
  std::vector<const Bushing*> supports;
  for (const auto& w : std::vector<std::string>{"ws1", "ws2", "ws3", "ws4"}) {
    for (const auto& side : std::vector<std::string>{"left", "right"}) {
      const int ws = model.bodyIndex(w);
      const double x = model.bodies()[static_cast<std::size_t>(ws)].r_reference.x();
      const Vector3 p(x, side == "left" ? 0.8665 : -0.8665, 0.445);
      Bushing::Parameters par;
      par.stiffness = Vector3(1e6, 1e6, 2e7);
      par.damping = Vector3(2e4, 2e4, 3.9e5);
      model.addBushingAt("wheel_support_" + w + "_" + side, kGround, ws, p, Matrix3::Identity(), par);
      supports.push_back(dynamic_cast<const Bushing*>(model.forceElements().back().get()));
    }
  }
  model.finalize();
  VehicleData data(model);
  IntegratorSettings settings;
  settings.method = IntegrationMethod::kBdf;
  settings.rtol = 1e-7;
  settings.atol = 1e-9;
  VehicleIntegrator integrator(model, data, model.referenceState(), 0.0, settings);
  const double t_end = 12.0;
  integrator.advanceTo(t_end);

  computeKinematics(model, integrator.state(), data);
  const double weight = 59480.0 * 9.81;
  double sum = 0.0, max_share_error = 0.0;
  for (const Bushing* s : supports) {
    Vector3 d, f;
    s->evaluateLocal(data, d, f);
    sum += f.z();
    max_share_error = std::max(max_share_error, std::abs(f.z() - weight / 8.0) / (weight / 8.0));
  }
  const double v_max = integrator.state().tail(model.nVelocities()).lpNorm<Eigen::Infinity>();
  const IntegratorCounters c = integrator.counters();
  std::printf(
      "[ static equilibrium ] t = %.0f s: max wheel-load error %.2e of W/8, sum/W - 1 = %.2e, max |v| %.2e, "
      "steps %ld, rhs %ld (+%ld for %ld Jacobians), error-test failures %ld, projections %ld\n",
      t_end, max_share_error, sum / weight - 1.0, v_max, c.steps, c.rhs_evals, c.rhs_evals_jacobian, c.jacobian_evals,
      c.error_test_failures, c.projections);
  // The vehicle is symmetric (Table 3: bogies at 11.5 -+ 9.5 m, wheelsets at bogie -+ 1.35 m, sides +-y), so
  // at equilibrium every wheel carries exactly W/8 = 72937 N. What remains after 12 s is the decaying
  // transient of the drop; the slowest mode (carbody bounce on the secondary, ~1 Hz, damping ratio ~0.15)
  // decays by exp(-0.15 * 6.3 * 12) ~ 1e-5 from an initial dynamic load below W/8, so 1e-4 of W/8 (7.3 N)
  // bounds it together with the integration error (rtol 1e-7).
  EXPECT_LT(max_share_error, 1e-4);
  EXPECT_NEAR(sum / weight, 1.0, 1e-4);
  EXPECT_LT(v_max, 1e-4);  // at rest
  // Each wheel spring is compressed by (W/8) / k = 3.65 mm.
  Vector3 d, f;
  supports[0]->evaluateLocal(data, d, f);
  EXPECT_NEAR(d.z(), -weight / 8.0 / 2e7, 1e-4 * weight / 8.0 / 2e7);
}

// ---------------------------------------------------------------------------------------------------------
// Loader errors: "<file>: <key.path>: <what>, got <value> (line N)".

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

std::string loadError(const std::string& path) {
  try {
    loadVehicleModel(path);
  } catch (const VehicleFileError& e) {
    return e.what();
  }
  return "no error";
}

const char* kTwoBodies = R"(bodies:
  - {name: ws, mass: 1800, centre_of_mass: [0, 0, 0.445], inertia: [900, 10, 900]}
  - {name: box, mass: 10, centre_of_mass: [0, 1.0, 0.445], inertia: [1, 1, 1]}
)";

TEST(VehicleLoader, NamesAnUndefinedBodyOfAJoint) {
  const std::string path = writeTemp("undefined_body.yaml", std::string(kTwoBodies) + R"(joints:
  - {name: bearing, type: revolute, body_i: ws, body_j: axlebox_9, position: [0, 1, 0.445], axis: [0, 1, 0]}
)");
  EXPECT_EQ(loadError(path), path + ": joints[0].body_j: no body of that name is defined, got 'axlebox_9' (line 5)");
}

// A joint and a force element name their type, their name and their bodies the same way.
TEST(VehicleLoader, NamesAnUnknownTypeASecondNameAndOneBodyTwiceForJointsAndForces) {
  const std::string joint_type = writeTemp("joint_type.yaml", std::string(kTwoBodies) + R"(joints:
  - {name: j, type: prismatic, body_i: ws, body_j: box, position: [0, 1, 0.445]}
)");
  EXPECT_EQ(loadError(joint_type), joint_type +
                                       ": joints[0].type: unknown joint type (expected revolute, spherical or fixed), "
                                       "got 'prismatic' (line 5)");
  const std::string force_type = writeTemp("force_type.yaml", std::string(kTwoBodies) + R"(forces:
  - {name: f, type: spring, body_i: ws, body_j: box}
)");
  EXPECT_EQ(loadError(force_type),
            force_type +
                ": forces[0].type: unknown force type (expected bushing, point_to_point or bump_stop), got 'spring' "
                "(line 5)");
  const std::string joint_same = writeTemp("joint_same.yaml", std::string(kTwoBodies) + R"(joints:
  - {name: j, type: fixed, body_i: box, body_j: box, position: [0, 1, 0.445]}
)");
  EXPECT_EQ(loadError(joint_same),
            joint_same + ": joints[0].body_j: a joint needs two different bodies, got 'box' (line 5)");
  const std::string force_same = writeTemp("force_same.yaml", std::string(kTwoBodies) + R"(forces:
  - {name: f, type: bushing, body_i: box, body_j: box, position: [0, 1, 0.445], stiffness: [1, 1, 1], damping: [0, 0, 0]}
)");
  EXPECT_EQ(loadError(force_same),
            force_same + ": forces[0].body_j: a force element needs two different bodies, got 'box' (line 5)");
  const std::string force_twice = writeTemp("force_twice.yaml", std::string(kTwoBodies) + R"(forces:
  - {name: f, type: bushing, body_i: ws, body_j: box, position: [0, 1, 0.445], stiffness: [1, 1, 1], damping: [0, 0, 0]}
  - {name: f, type: bushing, body_i: ws, body_j: box, position: [0, 1, 0.445], stiffness: [1, 1, 1], damping: [0, 0, 0]}
)");
  EXPECT_EQ(loadError(force_twice), force_twice + ": forces[1].name: force element defined twice, got 'f' (line 6)");
}

// yaml-cpp would keep the first of two equal keys: a key given twice is refused, naming both lines.
TEST(VehicleLoader, RefusesAKeyGivenTwice) {
  const std::string top =
      writeTemp("twice_top.yaml", std::string("gravity: [0, 0, -9.81]\n") + kTwoBodies + "gravity: [0, 0, -9.80]\n");
  EXPECT_EQ(loadError(top), top + ": gravity: given twice (lines 1 and 5): remove one");
  const std::string nested = writeTemp("twice_nested.yaml", R"(bodies:
  - name: ws
    mass: 1800
    mass: 1900
    centre_of_mass: [0, 0, 0.445]
    inertia: [900, 10, 900]
)");
  EXPECT_EQ(loadError(nested), nested + ": bodies[0].mass: given twice (lines 3 and 4): remove one");
}

TEST(VehicleLoader, RejectsNonPhysicalMass) {
  const std::string path = writeTemp("negative_mass.yaml", R"(bodies:
  - {name: ws, mass: -5, centre_of_mass: [0, 0, 0.445], inertia: [900, 10, 900]}
)");
  EXPECT_EQ(loadError(path), path + ": bodies[0].mass: must be positive, got -5 (line 2)");
}

TEST(VehicleLoader, RejectsMissingKeyUnknownKeyAndBadNumber) {
  const std::string missing = writeTemp("missing.yaml", R"(bodies:
  - {name: ws, mass: 1800, centre_of_mass: [0, 0, 0.445]}
)");
  EXPECT_EQ(loadError(missing), missing + ": bodies[0].inertia: required key missing (line 2)");
  const std::string typo = writeTemp("typo.yaml", std::string(kTwoBodies) + R"(forces:
  - {name: spring, type: bushing, body_i: ws, body_j: box, position: [0, 1, 0.445], stifness: [1, 2, 3]}
)");
  EXPECT_NE(loadError(typo).find(typo + ": forces[0].stifness: unknown key"), std::string::npos) << loadError(typo);
  const std::string not_number = writeTemp("not_number.yaml", R"(bodies:
  - {name: ws, mass: heavy, centre_of_mass: [0, 0, 0.445], inertia: [900, 10, 900]}
)");
  EXPECT_EQ(loadError(not_number), not_number + ": bodies[0].mass: must be a number, got 'heavy' (line 2)");
  const std::string short_vector = writeTemp("short_vector.yaml", R"(bodies:
  - {name: ws, mass: 1800, centre_of_mass: [0, 0.445], inertia: [900, 10, 900]}
)");
  EXPECT_EQ(loadError(short_vector),
            short_vector + ": bodies[0].centre_of_mass: must be a list of 3 numbers, got [0, 0.445] (line 2)");
}

TEST(VehicleLoader, RejectsBadBumpStopTableAndNegativeStiffness) {
  const std::string table = writeTemp("table.yaml", std::string(kTwoBodies) + R"(forces:
  - name: stop
    type: bump_stop
    body_i: ws
    body_j: box
    position: [0, 0, 0.5]
    axis: [0, 1, 0]
    table: [[0.025, 0], [0.030, 600], [0.028, 900]]
)");
  EXPECT_EQ(loadError(table),
            table + ": forces[0].table[2][0]: deflection not increasing (after 0.03), got 0.028 (line 11)");
  const std::string negative = writeTemp("negative_k.yaml", std::string(kTwoBodies) + R"(forces:
  - {name: spring, type: bushing, body_i: ws, body_j: box, position: [0, 1, 0.445], stiffness: [1, -2, 3]}
)");
  EXPECT_EQ(loadError(negative), negative + ": forces[0].stiffness[1]: must not be negative, got -2 (line 5)");
}

// Finite but absurd values are refused naming the key path and line: positions beyond 1 km, forces beyond
// 1e8 N, stiffness beyond 1e12 N/m, masses beyond 1e6 kg, inertias beyond 1e8 kg m^2.
TEST(VehicleLoader, RejectsAbsurdMagnitudes) {
  const std::string far = writeTemp("far_com.yaml", R"(bodies:
  - {name: ws, mass: 1800, centre_of_mass: [0, 0, -1e300], inertia: [900, 10, 900]}
)");
  EXPECT_EQ(loadError(far),
            far + ": bodies[0].centre_of_mass[2]: magnitude must be at most 1000 m, got -1e+300 (line 2)");
  const std::string heavy = writeTemp("heavy.yaml", R"(bodies:
  - {name: ws, mass: 2e6, centre_of_mass: [0, 0, 0.445], inertia: [900, 10, 900]}
)");
  EXPECT_EQ(loadError(heavy), heavy + ": bodies[0].mass: must be at most 1e+06 kg, got 2e+06 (line 2)");
  const std::string inertia = writeTemp("inertia.yaml", R"(bodies:
  - {name: ws, mass: 1800, centre_of_mass: [0, 0, 0.445], inertia: [900, 1e300, 900]}
)");
  EXPECT_EQ(loadError(inertia),
            inertia + ": bodies[0].inertia[1]: magnitude must be at most 1e+08 kg m^2, got 1e+300 (line 2)");
  const std::string tiny = writeTemp("tiny_inertia.yaml", R"(bodies:
  - {name: ws, mass: 1800, centre_of_mass: [0, 0, 0.445], inertia: [900, 10, 1e-300]}
)");
  EXPECT_EQ(loadError(tiny), tiny + ": bodies[0].inertia[2]: must be at least 1e-06 kg m^2, got 1e-300 (line 2)");
  const std::string preload = writeTemp("preload.yaml", std::string(kTwoBodies) + R"(forces:
  - {name: spring, type: bushing, body_i: ws, body_j: box, position: [0, 1, 0.445], preload: [-1e300, 0, 0]}
)");
  EXPECT_EQ(loadError(preload),
            preload + ": forces[0].preload[0]: magnitude must be at most 1e+08 N, got -1e+300 (line 5)");
  const std::string stiff = writeTemp("stiff.yaml", std::string(kTwoBodies) + R"(forces:
  - {name: link, type: point_to_point, body_i: ws, body_j: box, position_i: [0, 0, 0.445], position_j: [0, 1, 0.445],
     stiffness: 1e300}
)");
  EXPECT_EQ(loadError(stiff),
            stiff + ": forces[0].stiffness: magnitude must be at most 1e+12 N/m, got 1e+300 (line 6)");
}

TEST(VehicleLoader, RejectsAJointOrForceThatIsNotAMap) {
  const std::string joint = writeTemp("joint_scalar.yaml", std::string(kTwoBodies) + "joints:\n  - bearing\n");
  EXPECT_EQ(loadError(joint), joint + ": joints[0]: must be a map of keys to values, got 'bearing' (line 5)");
  const std::string force = writeTemp("force_list.yaml", std::string(kTwoBodies) + "forces:\n  - [1, 2]\n");
  EXPECT_EQ(loadError(force), force + ": forces[0]: must be a map of keys to values, got [1, 2] (line 5)");
}

TEST(VehicleLoader, ReportsSyntaxErrorsAndMissingFiles) {
  const std::string bad = writeTemp("syntax.yaml", "bodies:\n  - {name: ws, mass: [1800\n");
  EXPECT_EQ(loadError(bad).rfind(bad + ":", 0), 0u);
  EXPECT_NE(loadError(bad).find(": not valid YAML: "), std::string::npos) << loadError(bad);
  EXPECT_EQ(loadError("/nonexistent/vehicle.yaml"), "/nonexistent/vehicle.yaml: cannot open the file");
}

}  // namespace
}  // namespace rail::vehicle
