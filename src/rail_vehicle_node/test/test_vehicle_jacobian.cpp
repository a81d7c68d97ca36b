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
  VehicleSimulator sim(timedScene("paper_demo.yaml", 300.0, 30.5556, 0.1));
  ASSERT_EQ(sim.advanceTo(0.1), RunStatus::kFinished) << sim.message();
  expectMatches(compare(sim));
}

TEST(VehicleJacobian, MatchesTheDenseQuotientInFlangeContact) {
  // R 150 m at 50 km/h: after 0.7 s the leading wheelset flanges on the outer (right) rail
  // (test_vehicle_simulator's TightCurveLeadingWheelsetsFlangeOnTheOuterRail).
  core::Scene scene =
      timedScene("tight_curve.yaml", 145.0, core::fixtures::loadConfigScene("tight_curve.yaml").vehicle.speed, 0.7);
  VehicleSimulator sim(scene);
  ASSERT_EQ(sim.advanceTo(0.7), RunStatus::kFinished) << sim.message();
  ASSERT_TRUE(sim.contacts()[1].contact[rc::kFlange].active);
  expectMatches(compare(sim));
}

TEST(VehicleJacobian, MatchesTheDenseQuotientAtStandstill) {
  VehicleSimulator sim(timedScene("straight_short.yaml", 25.0, 0.0, 0.01));
  ASSERT_EQ(sim.advanceTo(0.01), RunStatus::kFinished) << sim.message();
  expectMatches(compare(sim));
}

}  // namespace
}  // namespace rail::vehicle
