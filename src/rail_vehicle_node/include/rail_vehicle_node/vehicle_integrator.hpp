// Variable-step, variable-order time integration of a VehicleModel with SUNDIALS CVODE (6.x): BDF with
// Newton iterations on a coloured sparse difference-quotient Jacobian and KLU (JacobianKind below), or
// Adams-Moulton with fixed-point iteration.
//
// The caller owns the loop: advanceTo(t) integrates to t (CV_NORMAL), interpolateAt(t) gives the state
// anywhere inside the last internal step (for the co-simulation), Counters() reports the work done.
// Constraint drift: the Baumgarte terms act inside the right-hand side; when after advanceTo the position
// or velocity violation (or the Euler-parameter norm error) exceeds its threshold, the state is projected
// back onto the constraint manifold (projectState), CVODE is re-initialised there and the projection counted.
// The model and the caller's VehicleData must outlive the integrator.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include <rail_core/cost_profile.hpp>

#include "rail_vehicle_node/multibody_dynamics.hpp"
#include "rail_vehicle_node/vehicle_data.hpp"
#include "rail_vehicle_node/vehicle_model.hpp"

namespace rail::vehicle {

enum class IntegrationMethod { kBdf, kAdams };

// BDF's Newton iteration: the Jacobian and the linear solver. kColoured is the coloured sparse difference
// quotient over the model's sparsity (vehicle_jacobian.hpp; 78 right-hand sides, most of them partial, for
// the paper coach) solved by SUNDIALS' KLU (kSparseKlu) or its dense LU (kDense, same Jacobian);
// kDenseDifferenceQuotient is CVODE's own dense quotient (one right-hand side per state, 195) with the
// dense LU, kept as the reference the coloured one is tested against.
enum class JacobianKind { kColoured, kDenseDifferenceQuotient };
enum class LinearSolverKind { kSparseKlu, kDense };

struct IntegratorSettings {
  double rtol = 1e-6;         // relative tolerance
  double atol = 1e-8;         // absolute tolerance (positions m, Euler parameters, velocities m/s)
  double max_step = 0.0;      // [s]; 0 = no limit
  double initial_step = 0.0;  // [s]; 0 = CVODE's estimate
  IntegrationMethod method = IntegrationMethod::kBdf;
  JacobianKind jacobian = JacobianKind::kColoured;                // BDF only
  LinearSolverKind linear_solver = LinearSolverKind::kSparseKlu;  // BDF with kColoured only
  // With kSparseKlu: I - gamma J written straight into KLU's matrix by a linear-system function; false: a
  // Jacobian function, and CVODE zeroes, copies and scale-adds the matrix at every set-up (the same numbers).
  bool direct_linear_system = true;
  // BDF with kColoured only: bodies that turn fast about their own y axis and whose dynamics do not change
  // with that turn (the wheelsets). Between evaluations the Jacobian is carried along with their turn
  // (SpinTransport) at every linear-solver set-up, one every linear_setup_interval steps; a new one is
  // evaluated after jacobian_max_age steps or when Newton failed with the carried one. Empty: CVODE's own
  // policy (a Jacobian kept up to 51 steps, a set-up every 20).
  std::vector<int> spin_bodies;
  int jacobian_max_age = 50;      // [steps]; CVODE's own limit is 51
  int linear_setup_interval = 5;  // [steps]; 3 to 7 measured, 5 fastest on the paper scene (doc/simulator.md)
  // BDF only: when CVODE gives up within an advanceTo (repeated error-test or convergence failures, as at
  // some flange onsets with tolerances below 1e-6), Adams integrates the rest of that interval from the
  // last successful step and BDF restarts after it (counted in IntegratorCounters::adams_fallbacks).
  bool adams_fallback = true;
  double fallback_max_step = 0.0;    // the fallback's step cap [s]; 0 = max_step
  int max_order = 5;                 // BDF <= 5, Adams <= 12
  long max_steps_per_call = 100000;  // internal steps allowed within one advanceTo
  // Take CVODE's steps one at a time (CV_ONE_STEP) and tell the force elements after each accepted one
  // (ForceElement::acceptStep), so that memories of the contacts hold accepted states only; false: CV_NORMAL,
  // and no element hears of the steps.
  bool accept_steps = false;
  double projection_position_threshold = 1e-6;  // max |Phi| that triggers a projection [m]
  double projection_velocity_threshold = 1e-5;  // max |Phi_v v| that triggers a projection [m/s]
  double projection_euler_threshold = 1e-6;  // max |‖p‖ - 1| that triggers a projection (rotations use p/‖p‖)
  double projection_tolerance = 1e-12;       // max |Phi| after a projection [m]
  int projection_max_iterations = 20;
  // Optional timing: right-hand sides into kVehicleRhs, those of the difference-quotient Jacobians (BDF)
  // into kVehicleJacobian. Must outlive the integrator; null = no timing.
  core::CostClock* cost = nullptr;
};

// Work counters since construction (accumulated over re-initialisations).
struct IntegratorCounters {
  long steps = 0;               // internal steps
  long rhs_evals = 0;           // right-hand side evaluations by the integrator
  long rhs_evals_jacobian = 0;  // right-hand side evaluations for difference-quotient Jacobians (coloured:
                                // each perturbed evaluation, most of them without the contact)
  long jacobian_evals = 0;      // Jacobian evaluations
  long jacobian_carries = 0;    // Jacobians carried along with the spin instead (IntegratorSettings::spin_bodies)
  long error_test_failures = 0;
  long nonlinear_iterations = 0;
  long nonlinear_convergence_failures = 0;
  long projections = 0;      // constraint projections (each followed by a re-initialisation)
  long adams_fallbacks = 0;  // intervals that BDF gave up and Adams finished (adams_fallback)
  int last_order = 0;
  double last_step = 0.0;  // [s]
};

class VehicleIntegrator {
 public:
  // Starts at (t0, y0); y0 is projected first if it violates the thresholds.
  VehicleIntegrator(const VehicleModel& model, VehicleData& data, const Eigen::VectorXd& y0, double t0,
                    const IntegratorSettings& settings);
  ~VehicleIntegrator();
  VehicleIntegrator(const VehicleIntegrator&) = delete;
  VehicleIntegrator& operator=(const VehicleIntegrator&) = delete;

  // Integrates to t (> time()); throws std::runtime_error naming CVODE's failure.
  void advanceTo(double t);

  // State at t within the last internal step [t_n - h_u, t_n] (CVodeGetDky, order 0). Also valid at time().
  void interpolateAt(double t, Eigen::Ref<Eigen::VectorXd> y_out) const;
  // Interval over which interpolateAt is valid; after a projection it shrinks to [time(), time()].
  void lastStepInterval(double& t_begin, double& t_end) const;

  // Restarts from a state set by the caller (e.g. after changing the external wrenches abruptly).
  void reset(const Eigen::VectorXd& y, double t);

  double time() const;                              // time reached by the last advanceTo [s]
  Eigen::Map<const Eigen::VectorXd> state() const;  // state at time()
  IntegratorCounters counters() const;
  ConstraintViolation violation();  // of state()

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rail::vehicle
