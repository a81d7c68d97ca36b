// The coloured sparse Jacobian (vehicle_jacobian.hpp) against the dense difference quotient of the full
// right-hand side, one state column at a time, at states of the coach on the rigid track: in the paper
// scene's circular curve, flanging in a tight curve, and at standstill.
#include <gtest/gtest.h>

#include <rail_core/scene_loader.hpp>
#include <rail_core/testing/fixtures.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "rail_vehicle_node/multibody_dynamics.hpp"
#include "rail_vehicle_node/vehicle_jacobian.hpp"
#include "rail_vehicle_node/vehicle_simulator.hpp"

namespace rail::vehicle {
namespace {

namespace rc = rail::contact;

core::Scene timedScene(const std::string& file, double start_arc_length, double speed, double end_time) {
  core::Scene scene = core::fixtures::loadConfigScene(file);
  scene.effects.track_model = core::TrackModel::kRigid;
  scene.vehicle.start_arc_length = start_arc_length;
  scene.vehicle.speed = speed;
  scene.solver.end.kind = core::EndKind::kTime;
  scene.solver.end.value = end_time;
  return scene;
}

// Tolerance. Both quotients use the same increments and start the contact from the same warm starts, so
// they differ only by round-off: the coloured one sums the element forces in another order (and takes
// the unperturbed elements' share from their stored contributions). That changes f_i by a few eps of its
// largest terms (wheel loads and constraint forces over the masses and inertias: < 1e3 m/s^2 or rad/s^2,
// so < 1e-12 absolute; 1e-11 allows a factor 10), i.e. J_ij by 1e-11 / inc_j. On top of that 1e-6 of the
// column's largest entry. A missed coupling, two columns of one colour writing one row or an element kept
// at its unperturbed contribution although it depends on a perturbed body would be an error of the order
// of the entries themselves (damping over mass ~1e1, stiffness over mass ~1e3 to 1e4), far above it.
// Increments: inc_j = max(sqrt(eps) |y_j|, 1e-8), CVODE's rule with unit weights and a 1e-8 floor (with
// CVODE's own weights the velocities of a vehicle at rest would get increments of ~1e-22, where round-off
// is all the quotient sees).
constexpr double kRoundOff = 1e-11;  // [units of f]
constexpr double kRelative = 1e-6;
constexpr double kMinIncrement = 1e-8;

struct Comparison {
  double max_ratio = 0.0;     // max over entries of |J_coloured - J_dense| / tolerance
  double max_outside = 0.0;   // max |J_dense| / tolerance outside the pattern (where J_coloured = 0)
  double max_relative = 0.0;  // max |J_coloured - J_dense| / (the column's largest |J_dense|), for the record
  int evaluations = 0;
  int body_colours = 0;
  bool work_state_kept = false;  // the contact's results and hints unchanged by the Jacobian
};

// Coloured Jacobian at the simulator's state, then the dense forward quotient with the same increments:
// each column perturbed alone, the full right-hand side, the elements' work states restored before each.
Comparison compare(VehicleSimulator& sim) {
  const VehicleModel& model = sim.model();
  VehicleData& data = sim.data();
  const int n = model.stateSize();
  const Eigen::VectorXd y = sim.state();
  const double t = sim.time();
  const Eigen::VectorXd weight = Eigen::VectorXd::Ones(n);
  Eigen::VectorXd f_ref(n), f(n), y_perturbed = y, column(n);
  computeDerivatives(model, t, y, f_ref, data);

  const auto& contact = sim.contactData();
  const std::vector<rc::WheelContactResult> results_before = contact.result;
  const std::vector<double> hints_before = contact.s_hint;
  JacobianPattern pattern(model);
  JacobianWork work(model, pattern);
  Comparison c;
  c.evaluations = evaluateJacobian(model, pattern, t, y, weight, kMinIncrement, data, work);
  c.body_colours = pattern.nBodyColours();
  c.work_state_kept = contact.s_hint == hints_before;
  for (std::size_t k = 0; k < results_before.size(); ++k) {
    c.work_state_kept = c.work_state_kept &&
                        contact.result[k].wheel_centre.force_in_world == results_before[k].wheel_centre.force_in_world;
  }

  const auto& elements = model.forceElements();
  for (const auto& e : elements) e->saveWorkState();
  const auto& start = pattern.colStart();
  const auto& rows = pattern.rowIndex();
  for (int j = 0; j < n; ++j) {
    y_perturbed[j] = y[j] + work.increment[j];
    for (const auto& e : elements) e->restoreWorkState();
    computeDerivatives(model, t, y_perturbed, f, data);
    y_perturbed[j] = y[j];
    column = (f - f_ref) / work.increment[j];
    const double col_max = column.cwiseAbs().maxCoeff();
    const double tolerance = kRelative * col_max + kRoundOff / work.increment[j];
    Eigen::VectorXd coloured = Eigen::VectorXd::Zero(n), outside = column;
    for (int k = start[static_cast<std::size_t>(j)]; k < start[static_cast<std::size_t>(j + 1)]; ++k) {
      coloured[rows[static_cast<std::size_t>(k)]] = work.values[static_cast<std::size_t>(k)];
      outside[rows[static_cast<std::size_t>(k)]] = 0.0;
    }
    const double error = (coloured - column).cwiseAbs().maxCoeff();
    c.max_ratio = std::max(c.max_ratio, error / tolerance);
    c.max_outside = std::max(c.max_outside, outside.cwiseAbs().maxCoeff() / tolerance);
    if (col_max > 0.0) c.max_relative = std::max(c.max_relative, error / col_max);
  }
  for (const auto& e : elements) e->restoreWorkState();
  std::printf(
      "jacobian: %d nonzeros of %d, %d body colours, %d evaluations; max |coloured - dense| / tolerance "
      "%.2e (%.2e of the column's largest entry), max dense entry outside the pattern / tolerance %.2e\n",
      pattern.nonzeros(), n * n, c.body_colours, c.evaluations, c.max_ratio, c.max_relative, c.max_outside);
  return c;
}

void expectMatches(const Comparison& c) {
  EXPECT_LT(c.max_ratio, 1.0);
  EXPECT_LT(c.max_outside, 1.0);
  EXPECT_TRUE(c.work_state_kept);
  // The paper coach's topology: the four wheelsets with the carbody (no shared rows), the two bogies each
  // with an axlebox of the other bogie, and the remaining six axleboxes in three pairs across the bogies:
  // 6 body colours, 13 columns each, plus the unperturbed evaluation.
  EXPECT_EQ(c.body_colours, 6);
  EXPECT_EQ(c.evaluations, 1 + 13 * 6);
}

TEST(VehicleJacobian, MatchesTheDenseQuotientInTheCurve) {
  // Paper scene, 110 km/h, inside the R 500 m circular curve (s 200-380 m).
  VehicleSimulator sim(resolveVehicle(timedScene("paper_demo.yaml", 300.0, 30.5556, 0.1)));
  ASSERT_EQ(sim.advanceTo(0.1), RunStatus::kFinished) << sim.message();
  expectMatches(compare(sim));
}

TEST(VehicleJacobian, MatchesTheDenseQuotientInFlangeContact) {
  // R 150 m at 50 km/h: after 0.7 s the leading wheelset flanges on the outer (right) rail
  // (test_vehicle_simulator's TightCurveLeadingWheelsetsFlangeOnTheOuterRail).
  core::Scene scene =
      timedScene("tight_curve.yaml", 145.0, core::fixtures::loadConfigScene("tight_curve.yaml").vehicle.speed, 0.7);
  VehicleSimulator sim(resolveVehicle(scene));
  ASSERT_EQ(sim.advanceTo(0.7), RunStatus::kFinished) << sim.message();
  ASSERT_TRUE(sim.contacts()[1].contact[rc::kFlange].active);
  expectMatches(compare(sim));
}

TEST(VehicleJacobian, MatchesTheDenseQuotientAtStandstill) {
  VehicleSimulator sim(resolveVehicle(timedScene("straight_short.yaml", 25.0, 0.0, 0.01)));
  ASSERT_EQ(sim.advanceTo(0.01), RunStatus::kFinished) << sim.message();
  expectMatches(compare(sim));
}

TEST(VehicleJacobian, VelocityColumnsWithTheKeptClusterFactorsAreTheFreshlyFactoredOnes) {
  // The velocity columns keep the range-space solve's cluster factors of the unperturbed evaluation
  // (VehicleData::reuse_cluster_factors): Phi_v depends on the positions only, so each such column must be
  // the very same numbers as when the factors are formed anew. Compared bit for bit, in the paper curve.
  VehicleSimulator sim(resolveVehicle(timedScene("paper_demo.yaml", 300.0, 30.5556, 0.1)));
  ASSERT_EQ(sim.advanceTo(0.1), RunStatus::kFinished) << sim.message();
  const VehicleModel& model = sim.model();
  VehicleData& data = sim.data();
  const int n = model.stateSize();
  const Eigen::VectorXd y = sim.state();
  const double t = sim.time();
  JacobianPattern pattern(model);
  JacobianWork work(model, pattern);
  evaluateJacobian(model, pattern, t, y, Eigen::VectorXd::Ones(n), kMinIncrement, data, work);
  EXPECT_FALSE(data.reuse_cluster_factors);
  const auto& elements = model.forceElements();
  for (const auto& e : elements) e->saveWorkState();
  Eigen::VectorXd y_perturbed = y, f(n);
  int compared = 0, differing = 0;
  for (int c = 0; c < pattern.nBodyColours(); ++c) {
    for (int l = 7; l < 13; ++l) {
      for (int b : pattern.colourBodies(c)) {
        const int j = pattern.column(model, b, l);
        y_perturbed[j] = y[j] + work.increment[j];
      }
      computeDerivativesPartial(model, t, y_perturbed, f, data, pattern.liveElements(c), work.element_g);
      for (const auto& e : elements) e->restoreWorkState();
      for (int b : pattern.colourBodies(c)) {
        const int j = pattern.column(model, b, l);
        for (int k = pattern.colStart()[static_cast<std::size_t>(j)];
             k < pattern.colStart()[static_cast<std::size_t>(j + 1)]; ++k) {
          const int i = pattern.rowIndex()[static_cast<std::size_t>(k)];
          ++compared;
          if ((f[i] - work.f0[i]) * (1.0 / work.increment[j]) != work.values[static_cast<std::size_t>(k)]) ++differing;
        }
        y_perturbed[j] = y[j];
      }
    }
  }
  EXPECT_GT(compared, 1000);
  EXPECT_EQ(differing, 0) << "of " << compared;
}

// The Jacobian carried along with the wheelsets' spin (SpinTransport) against the one evaluated where the
// wheelsets have turned: each wheelset of the coach in the paper curve turned by 0.35 rad about its axle
// (five 1 ms steps at 110 km/h), everything else the same.
struct TurnedState {
  Eigen::VectorXd y, y_turned;
  std::vector<int> wheelsets;
};

TurnedState turnWheelsets(const VehicleSimulator& sim, double angle) {
  TurnedState s;
  s.y = sim.state();
  s.y_turned = s.y;
  s.wheelsets = sim.wheelsetBodies();
  const Vector4 q(std::cos(0.5 * angle), 0.0, std::sin(0.5 * angle), 0.0);
  const Matrix3 turn = rotationFromEulerParameters(q);
  for (int b : s.wheelsets) {
    const int e = VehicleModel::eulerOffset(b), w = sim.model().angularVelocityOffset(b);
    s.y_turned.segment<4>(e) = quaternionProduct(s.y.segment<4>(e), q);
    s.y_turned.segment<3>(w) = turn.transpose() * s.y.segment<3>(w);
  }
  return s;
}

TEST(VehicleJacobian, CarriedWithTheSpinMatchesTheJacobianWhereTheWheelsetsHaveTurned) {
  VehicleSimulator sim(resolveVehicle(timedScene("paper_demo.yaml", 300.0, 30.5556, 0.1)));
  ASSERT_EQ(sim.advanceTo(0.1), RunStatus::kFinished) << sim.message();
  const VehicleModel& model = sim.model();
  VehicleData& data = sim.data();
  const int n = model.stateSize();
  const double t = sim.time();
  const TurnedState s = turnWheelsets(sim, 0.35);
  const Eigen::VectorXd weight = Eigen::VectorXd::Ones(n);
  JacobianPattern pattern(model);
  JacobianWork work(model, pattern);
  SpinTransport transport(model, pattern, s.wheelsets);

  // The claim it rests on: f(T y) = T f(y). The turned wheels touch the rails at the same points, found
  // again by the detection's Newton to its 1e-10 m tolerance from other warm starts; 1e-9 of the largest
  // |f| (~1e3) bounds that (1e-10 measured). A wrong turn (sign, axis, frame) would be off by O(1).
  Eigen::VectorXd f(n), f_turned(n);
  computeDerivatives(model, t, s.y, f, data);
  computeDerivatives(model, t, s.y_turned, f_turned, data);
  Eigen::VectorXd t_f = f;
  const Vector4 q(std::cos(0.175), 0.0, std::sin(0.175), 0.0);
  for (int b : s.wheelsets) {
    const int e = VehicleModel::eulerOffset(b), w = model.angularVelocityOffset(b);
    t_f.segment<4>(e) = quaternionProduct(f.segment<4>(e), q);
    t_f.segment<3>(w) = rotationFromEulerParameters(q).transpose() * f.segment<3>(w);
  }
  const double f_error = (f_turned - t_f).cwiseAbs().maxCoeff() / f.cwiseAbs().maxCoeff();
  std::printf("max |f(T y) - T f(y)| / max |f| = %.2e\n", f_error);
  constexpr double kEquivariance = 1e-9;
  constexpr double kTruncation = 2e-5;
  EXPECT_LT(f_error, kEquivariance);
  const double f_noise = kEquivariance * f.cwiseAbs().maxCoeff();

  evaluateJacobian(model, pattern, t, s.y, weight, kMinIncrement, data, work);
  const std::vector<double> at_reference = work.values;
  transport.setReference(s.y);
  EXPECT_NEAR(transport.turn(0, s.y_turned), 0.35, 1e-12);
  std::vector<double> carried(at_reference.size());
  transport.transport(s.y_turned, at_reference, carried);
  evaluateJacobian(model, pattern, t, s.y_turned, weight, kMinIncrement, data, work);

  // Per column: the carried J mixes quotients taken along the unturned coordinates, the direct one is taken
  // along the turned ones, so their truncation errors (increment / 2 times f's second derivatives) differ.
  // Both are compared with that first-order error taken out: each forward quotient minus the second
  // difference along its column, (f(y + 2h) - 2 f(y + h) + f(y)) / (2h), a one-sided quotient of second
  // order. That matters at a shallow, near-conformal contact (the leading outer wheel's second tread
  // contact at 0.12 rad, 13 um deep, whose point slides along the profile as the wheelset rolls), where the
  // forward quotients differ by up to 2e-3 of the column's largest entry. What remains is bounded by 2e-5
  // of that entry (the Hertz law's relative curvature 1 / (2 delta) at delta ~ 1e-4 m over a 1e-8 m
  // increment is 5e-5 for one forward quotient; 3e-6 measured on the wheelsets' Euler-parameter columns
  // before the correction). Each corrected quotient also carries the detection's re-convergence in its
  // three evaluations of f, bounded above by kEquivariance max |f|, weighted 1 + 4 + 3 over 2h: 4 times
  // f_noise / h per quotient, 8 for the two. Left unturned, the reference Jacobian misses by a large
  // fraction of the entries (checked below, so that this comparison can fail).
  const auto& start = pattern.colStart();
  const auto& rows = pattern.rowIndex();
  auto secondDifferences = [&](const Eigen::VectorXd& y0, std::vector<double>& out) {
    out.assign(work.values.size(), 0.0);
    Eigen::VectorXd f0(n), f1(n), f2(n), y_step = y0;
    computeDerivatives(model, t, y0, f0, data);
    for (int j = 0; j < n; ++j) {
      const double h = work.increment[j];
      y_step[j] = y0[j] + h;
      computeDerivatives(model, t, y_step, f1, data);
      y_step[j] = y0[j] + 2.0 * h;
      computeDerivatives(model, t, y_step, f2, data);
      y_step[j] = y0[j];
      for (int k = start[static_cast<std::size_t>(j)]; k < start[static_cast<std::size_t>(j + 1)]; ++k) {
        const int i = rows[static_cast<std::size_t>(k)];
        out[static_cast<std::size_t>(k)] = (f2[i] - 2.0 * f1[i] + f0[i]) / (2.0 * h);
      }
    }
  };
  std::vector<double> second_at_reference, second_turned;
  secondDifferences(s.y, second_at_reference);
  secondDifferences(s.y_turned, second_turned);
  std::vector<double> corrected_reference(at_reference.size());
  for (std::size_t k = 0; k < at_reference.size(); ++k)
    corrected_reference[k] = at_reference[k] - second_at_reference[k];
  transport.transport(s.y_turned, corrected_reference, carried);
  double worst_carried = 0.0, worst_unturned = 0.0;
  for (int j = 0; j < n; ++j) {
    double col_max = 0.0;
    for (int k = start[static_cast<std::size_t>(j)]; k < start[static_cast<std::size_t>(j + 1)]; ++k) {
      col_max = std::max(col_max, std::abs(work.values[static_cast<std::size_t>(k)]));
    }
    const double tolerance = kTruncation * col_max + 8.0 * f_noise / work.increment[j];
    for (int k = start[static_cast<std::size_t>(j)]; k < start[static_cast<std::size_t>(j + 1)]; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      const double direct = work.values[kk] - second_turned[kk];
      worst_carried = std::max(worst_carried, std::abs(carried[kk] - direct) / tolerance);
      if (col_max > 0.0)
        worst_unturned = std::max(worst_unturned, std::abs(at_reference[kk] - work.values[kk]) / col_max);
    }
  }
  std::printf("carried: max |J_carried - J(T y)| / tolerance %.2e; unturned: max |J(y) - J(T y)| / column max %.2e\n",
              worst_carried, worst_unturned);
  EXPECT_LT(worst_carried, 1.0);
  EXPECT_GT(worst_unturned, 0.1);
}

}  // namespace
}  // namespace rail::vehicle
