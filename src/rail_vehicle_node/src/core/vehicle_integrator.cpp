#include "rail_vehicle_node/vehicle_integrator.hpp"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "rail_vehicle_node/vehicle_jacobian.hpp"

// CVODE's own dense difference-quotient Jacobian (cvode_ls.c; exported by libsundials_cvode 6.x, not in its
// installed headers). Wrapped when a cost clock is attached so that the right-hand sides it calls are
// timed as Jacobian work; the Jacobian and CVODE's counters are the same as without the wrapper.
extern "C" int cvLsDQJac(realtype t, N_Vector y, N_Vector fy, SUNMatrix Jac, void* cvode_mem, N_Vector tmp1,
                         N_Vector tmp2, N_Vector tmp3);

namespace rail::vehicle {

struct VehicleIntegrator::Impl {
  const VehicleModel& model;
  VehicleData& data;
  IntegratorSettings settings;
  SUNContext context = nullptr;
  N_Vector y = nullptr;
  N_Vector dky = nullptr;
  N_Vector error_weights = nullptr;  // coloured Jacobian: CVODE's error weights
  SUNMatrix jacobian = nullptr;
  SUNLinearSolver linear_solver = nullptr;
  SUNNonlinearSolver nonlinear_solver = nullptr;
  void* cvode = nullptr;
  double t = 0.0;
  bool stepped_since_init = false;  // false right after (re-)initialisation
  bool ls_counters_stale = false;
  bool in_jacobian = false;                  // inside the DQ Jacobian (cost clock attached): RHS timed as Jacobian
  std::unique_ptr<JacobianPattern> pattern;  // coloured Jacobian (BDF)
  std::unique_ptr<JacobianWork> jacobian_work;
  long coloured_jacobian_rhs = 0;  // evaluations of the coloured Jacobians since construction
  // Carrying the Jacobian along with the spin (IntegratorSettings::spin_bodies).
  std::unique_ptr<SpinTransport> spin;
  std::vector<double> carried_values;  // the Jacobian handed to CVODE, in the pattern's order
  bool has_reference = false;          // a Jacobian evaluated since the last (re-)initialisation
  long steps_at_evaluation = 0, steps_at_last_call = -1, failures_at_last_call = 0;
  long coloured_jacobians = 0, carried_jacobians = 0;
  const std::vector<double>* jacobian_values = nullptr;  // the last Jacobian handed to CVODE
  void* adams = nullptr;  // BDF's fallback (IntegratorSettings::adams_fallback), made at first use
  SUNNonlinearSolver adams_solver = nullptr;
  IntegratorCounters base;             // counters accumulated before the last re-initialisation
  std::array<char, 512> last_error{};  // CVODE's last message (fixed buffer: no allocation)

  Impl(const VehicleModel& m, VehicleData& d, const IntegratorSettings& s) : model(m), data(d), settings(s) {}

  ~Impl() {
    if (cvode != nullptr) CVodeFree(&cvode);
    if (adams != nullptr) CVodeFree(&adams);
    if (adams_solver != nullptr) SUNNonlinSolFree(adams_solver);
    if (nonlinear_solver != nullptr) SUNNonlinSolFree(nonlinear_solver);
    if (linear_solver != nullptr) SUNLinSolFree(linear_solver);
    if (jacobian != nullptr) SUNMatDestroy(jacobian);
    if (dky != nullptr) N_VDestroy(dky);
    if (error_weights != nullptr) N_VDestroy(error_weights);
    if (y != nullptr) N_VDestroy(y);
    if (context != nullptr) SUNContext_Free(&context);
  }

  Eigen::Map<Eigen::VectorXd> stateMap() const {
    return Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(y), model.stateSize());
  }

  [[noreturn]] void fail(const char* call, int flag) const {
    std::ostringstream os;
    os << "vehicle integrator: " << call << " failed with flag " << flag << " at t = " << t;
    if (last_error[0] != '\0') os << ": " << last_error.data();
    throw std::runtime_error(os.str());
  }

  void check(int flag, const char* call) const {
    if (flag < 0) fail(call, flag);
  }

  // CVode to t_out as CV_NORMAL does (the state at t_out interpolated in the last step), but with
  // IntegratorSettings::accept_steps one step at a time, each accepted one followed by the force elements'
  // acceptStep. On failure y and t_reached hold the last accepted step. Returns CVode's flag.
  int stepTo(void* mem, realtype t_out, N_Vector y_out, realtype* t_reached) {
    if (!settings.accept_steps) return CVode(mem, t_out, y_out, t_reached, CV_NORMAL);
    realtype t_now = 0.0;
    CVodeGetCurrentTime(mem, &t_now);
    for (long taken = 0; t_now < t_out; ++taken) {
      if (taken == settings.max_steps_per_call) {
        CVodeGetDky(mem, t_now, 0, y_out);
        *t_reached = t_now;
        std::snprintf(last_error.data(), last_error.size(), "%ld steps taken before reaching t = %.9g s", taken,
                      static_cast<double>(t_out));
        return CV_TOO_MUCH_WORK;
      }
      const int flag = CVode(mem, t_out, y_out, &t_now, CV_ONE_STEP);
      if (flag < 0) {
        *t_reached = t_now;
        return flag;
      }
      for (const auto& element : model.forceElements()) element->acceptStep();
    }
    const int flag = CVodeGetDky(mem, t_out, 0, y_out);
    *t_reached = t_out;
    return flag;
  }

  static int rhs(realtype t, N_Vector y, N_Vector y_dot, void* user_data) {
    auto* self = static_cast<Impl*>(user_data);
    const int n = self->model.stateSize();
    const Eigen::Map<const Eigen::VectorXd> y_map(N_VGetArrayPointer(y), n);
    Eigen::Map<Eigen::VectorXd> y_dot_map(N_VGetArrayPointer(y_dot), n);
    core::CostClock::Scope timing(self->settings.cost,
                                  self->in_jacobian ? core::CostClock::kVehicleJacobian : core::CostClock::kVehicleRhs);
    try {
      computeDerivatives(self->model, t, y_map, y_dot_map, self->data);
    } catch (...) {
      return -1;  // unrecoverable: CVODE stops and advanceTo reports it
    }
    return y_dot_map.allFinite() ? 0 : 1;  // non-finite: recoverable, CVODE retries with a smaller step
  }

  static int timedDqJacobian(realtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* user_data, N_Vector tmp1,
                             N_Vector tmp2, N_Vector tmp3) {
    auto* self = static_cast<Impl*>(user_data);
    self->in_jacobian = true;
    const int flag = cvLsDQJac(t, y, fy, J, self->cvode, tmp1, tmp2, tmp3);
    self->in_jacobian = false;
    return flag;
  }

  // The coloured difference quotient (vehicle_jacobian.hpp), carried along with the spin or evaluated anew
  // with CVODE's increments: max(sqrt(eps) |y_j|, 1000 |h| eps n ||f||_wrms / w_j). Returns CVODE's flag.
  int updateJacobian(realtype t, N_Vector y, N_Vector fy) {
    const int n = model.stateSize();
    if (CVodeGetErrWeights(cvode, error_weights) != CV_SUCCESS) return -1;
    realtype h = 0.0;
    CVodeGetCurrentStep(cvode, &h);
    const double f_norm = N_VWrmsNorm(fy, error_weights);
    const double uround = std::numeric_limits<double>::epsilon();
    const double min_increment = f_norm != 0.0 ? 1000.0 * std::abs(h) * uround * n * f_norm : 1.0;
    const Eigen::Map<const Eigen::VectorXd> y_map(N_VGetArrayPointer(y), n);
    const Eigen::Map<const Eigen::VectorXd> w_map(N_VGetArrayPointer(error_weights), n);
    JacobianWork& work = *jacobian_work;
    // Carry the last Jacobian along with the spin unless it is too old or Newton failed with what CVODE had
    // (a second call within one step, or a convergence failure since the last call).
    long steps = 0, failures = 0;
    CVodeGetNumSteps(cvode, &steps);
    CVodeGetNumNonlinSolvConvFails(cvode, &failures);
    const bool carry = spin != nullptr && has_reference && steps != steps_at_last_call &&
                       failures == failures_at_last_call && steps - steps_at_evaluation < settings.jacobian_max_age;
    steps_at_last_call = steps;
    failures_at_last_call = failures;
    if (carry) {
      spin->transport(y_map, work.values, carried_values);
      jacobian_values = &carried_values;
      ++carried_jacobians;
      return 0;
    }
    try {
      coloured_jacobian_rhs +=
          evaluateJacobian(model, *pattern, t, y_map, w_map, min_increment, data, work, settings.cost);
    } catch (...) {
      return -1;
    }
    jacobian_values = &work.values;
    ++coloured_jacobians;
    if (spin != nullptr) {
      spin->setReference(y_map);
      has_reference = true;
      steps_at_evaluation = steps;
    }
    return 0;
  }

  // The pattern's column pointers and row indices into the sparse matrix M.
  void writePattern(SUNMatrix M) const {
    const auto& col_start = pattern->colStart();
    const auto& row_index = pattern->rowIndex();
    sunindextype* pointers = SUNSparseMatrix_IndexPointers(M);
    sunindextype* indices = SUNSparseMatrix_IndexValues(M);
    for (std::size_t j = 0; j < col_start.size(); ++j) pointers[j] = col_start[j];
    for (std::size_t k = 0; k < row_index.size(); ++k) indices[k] = row_index[k];
  }

  // CVODE's Jacobian function: the coloured Jacobian into the dense or sparse matrix J.
  static int colouredJacobian(realtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* user_data, N_Vector /*tmp1*/,
                              N_Vector /*tmp2*/, N_Vector /*tmp3*/) {
    auto* self = static_cast<Impl*>(user_data);
    const int flag = self->updateJacobian(t, y, fy);
    if (flag != 0) return flag;
    const auto& col_start = self->pattern->colStart();
    const auto& row_index = self->pattern->rowIndex();
    const std::vector<double>& values = *self->jacobian_values;
    const int n = self->model.stateSize();
    bool finite = true;
    if (SUNMatGetID(J) == SUNMATRIX_SPARSE) {
      self->writePattern(J);  // CVODE zeroed the whole matrix before this call
      realtype* values_out = SUNSparseMatrix_Data(J);
      for (std::size_t k = 0; k < row_index.size(); ++k) {
        values_out[k] = values[k];
        finite = finite && std::isfinite(values[k]);
      }
      return finite ? 0 : 1;  // non-finite: recoverable
    }
    SUNMatZero(J);
    for (int j = 0; j < n; ++j) {
      realtype* column = SUNDenseMatrix_Column(J, j);
      for (int k = col_start[static_cast<std::size_t>(j)]; k < col_start[static_cast<std::size_t>(j + 1)]; ++k) {
        column[row_index[static_cast<std::size_t>(k)]] = values[static_cast<std::size_t>(k)];
        finite = finite && std::isfinite(values[static_cast<std::size_t>(k)]);
      }
    }
    return finite ? 0 : 1;  // non-finite: recoverable
  }

  // CVODE's linear-system function for KLU: A = I - gamma J written straight into the sparse matrix, with
  // the last Jacobian when CVODE deems it current (jok), instead of CVODE's zero, copy and scale-add passes.
  // The matrix's structure is the pattern's, written once at construction; only its values change here.
  static int colouredLinearSystem(realtype t, N_Vector y, N_Vector fy, SUNMatrix A, booleantype jok, booleantype* jcur,
                                  realtype gamma, void* user_data, N_Vector /*tmp1*/, N_Vector /*tmp2*/,
                                  N_Vector /*tmp3*/) {
    auto* self = static_cast<Impl*>(user_data);
    *jcur = SUNFALSE;
    if (!jok || self->jacobian_values == nullptr) {
      const int flag = self->updateJacobian(t, y, fy);
      if (flag != 0) return flag;
      *jcur = SUNTRUE;
    }
    const auto& col_start = self->pattern->colStart();
    const auto& row_index = self->pattern->rowIndex();
    const std::vector<double>& values = *self->jacobian_values;
    realtype* values_out = SUNSparseMatrix_Data(A);
    const int n = self->model.stateSize();
    bool finite = true;
    for (int j = 0; j < n; ++j) {
      for (int k = col_start[static_cast<std::size_t>(j)]; k < col_start[static_cast<std::size_t>(j + 1)]; ++k) {
        const double v = values[static_cast<std::size_t>(k)];
        finite = finite && std::isfinite(v);
        values_out[k] = -gamma * v;  // as SUNMatScaleAddI: (-gamma) J, then + 1 on the diagonal
        if (row_index[static_cast<std::size_t>(k)] == j) values_out[k] += 1.0;
      }
    }
    return finite ? 0 : 1;  // non-finite: recoverable
  }

  static void errorHandler(int /*error_code*/, const char* module, const char* function, char* msg, void* user) {
    auto* self = static_cast<Impl*>(user);
    std::snprintf(self->last_error.data(), self->last_error.size(), "%s %s: %s", module, function, msg);
  }

  void accumulateCounters() { addCvodeCounts(currentCounters(), base); }

  // The counts CVODE keeps (steps, evaluations, failures) of `now` added to `to`.
  static void addCvodeCounts(const IntegratorCounters& now, IntegratorCounters& to) {
    to.steps += now.steps;
    to.rhs_evals += now.rhs_evals;
    to.rhs_evals_jacobian += now.rhs_evals_jacobian;
    to.jacobian_evals += now.jacobian_evals;
    to.error_test_failures += now.error_test_failures;
    to.nonlinear_iterations += now.nonlinear_iterations;
    to.nonlinear_convergence_failures += now.nonlinear_convergence_failures;
  }

  // Counters of CVODE since the last (re-)initialisation.
  IntegratorCounters currentCounters() const {
    IntegratorCounters c;
    long v = 0;
    if (CVodeGetNumSteps(cvode, &v) == CV_SUCCESS) c.steps = v;
    if (CVodeGetNumRhsEvals(cvode, &v) == CV_SUCCESS) c.rhs_evals = v;
    if (CVodeGetNumErrTestFails(cvode, &v) == CV_SUCCESS) c.error_test_failures = v;
    if (CVodeGetNumNonlinSolvIters(cvode, &v) == CV_SUCCESS) c.nonlinear_iterations = v;
    if (CVodeGetNumNonlinSolvConvFails(cvode, &v) == CV_SUCCESS) c.nonlinear_convergence_failures = v;
    if (settings.method == IntegrationMethod::kBdf && !ls_counters_stale) {
      if (CVodeGetNumJacEvals(cvode, &v) == CV_SUCCESS) c.jacobian_evals = v;
      if (CVodeGetNumLinRhsEvals(cvode, &v) == CV_SUCCESS) c.rhs_evals_jacobian = v;
    }
    int order = 0;
    if (CVodeGetLastOrder(cvode, &order) == CV_SUCCESS) c.last_order = order;
    realtype h = 0.0;
    if (CVodeGetLastStep(cvode, &h) == CV_SUCCESS) c.last_step = h;
    return c;
  }

  // Projects the state when a threshold is exceeded; returns true if it did (CVODE then re-initialised).
  bool projectIfNeeded() {
    Eigen::Map<Eigen::VectorXd> state = stateMap();
    const ConstraintViolation v = evaluateViolation(model, state, data);
    if (v.position <= settings.projection_position_threshold && v.velocity <= settings.projection_velocity_threshold &&
        v.euler_norm <= settings.projection_euler_threshold) {
      return false;
    }
    projectState(model, state, data, settings.projection_tolerance, settings.projection_max_iterations);
    ++base.projections;
    return true;
  }

  // Integrates from (t, y) to t_out with Adams (fixed point; same tolerances, fallback_max_step) into y, adds its work
  // to the counters and re-initialises BDF at t_out. Allocates the Adams instance at its first use.
  void fallBackToAdams(double t_out) {
    if (adams == nullptr) {
      adams = CVodeCreate(CV_ADAMS, context);
      adams_solver = adams != nullptr ? SUNNonlinSol_FixedPoint(y, 0, context) : nullptr;
      if (adams_solver == nullptr) throw std::runtime_error("vehicle integrator: Adams fallback creation failed");
      check(CVodeSetErrHandlerFn(adams, &Impl::errorHandler, this), "CVodeSetErrHandlerFn");
      check(CVodeInit(adams, &Impl::rhs, t, y), "CVodeInit");
      check(CVodeSetUserData(adams, this), "CVodeSetUserData");
      check(CVodeSStolerances(adams, settings.rtol, settings.atol), "CVodeSStolerances");
      check(CVodeSetMaxOrd(adams, 12), "CVodeSetMaxOrd");
      check(CVodeSetMaxNumSteps(adams, settings.max_steps_per_call), "CVodeSetMaxNumSteps");
      const double cap = settings.fallback_max_step > 0.0 ? settings.fallback_max_step : settings.max_step;
      if (cap > 0.0) check(CVodeSetMaxStep(adams, cap), "CVodeSetMaxStep");
      check(CVodeSetNonlinearSolver(adams, adams_solver), "CVodeSetNonlinearSolver");
    } else {
      check(CVodeReInit(adams, t, y), "CVodeReInit");
    }
    last_error[0] = '\0';
    realtype t_reached = t;
    const int flag = stepTo(adams, t_out, y, &t_reached);
    long v = 0;
    if (CVodeGetNumSteps(adams, &v) == CV_SUCCESS) base.steps += v;
    if (CVodeGetNumRhsEvals(adams, &v) == CV_SUCCESS) base.rhs_evals += v;
    if (CVodeGetNumErrTestFails(adams, &v) == CV_SUCCESS) base.error_test_failures += v;
    if (CVodeGetNumNonlinSolvIters(adams, &v) == CV_SUCCESS) base.nonlinear_iterations += v;
    if (CVodeGetNumNonlinSolvConvFails(adams, &v) == CV_SUCCESS) base.nonlinear_convergence_failures += v;
    ++base.adams_fallbacks;
    t = t_reached;
    if (flag < 0) fail("CVode (Adams fallback)", flag);
    reInit();
  }

  void reInit() {
    accumulateCounters();
    check(CVodeReInit(cvode, t, y), "CVodeReInit");
    stepped_since_init = false;
    // CVODE's step count restarts: the next call evaluates.
    has_reference = false;
    steps_at_last_call = -1;
    failures_at_last_call = 0;
    ls_counters_stale = true;
  }
};

VehicleIntegrator::VehicleIntegrator(const VehicleModel& model, VehicleData& data, const Eigen::VectorXd& y0, double t0,
                                     const IntegratorSettings& settings)
    : impl_(std::make_unique<Impl>(model, data, settings)) {
  Impl& s = *impl_;
  std::ostringstream os;
  if (!model.finalized()) throw std::runtime_error("vehicle integrator: the model must be finalised first");
  if (y0.size() != model.stateSize()) {
    os << "vehicle integrator: initial state has " << y0.size() << " entries, the model needs " << model.stateSize();
    throw std::runtime_error(os.str());
  }
  if (!(settings.rtol > 0.0) || !(settings.atol > 0.0)) {
    os << "vehicle integrator: rtol and atol must be > 0, got " << settings.rtol << ", " << settings.atol;
    throw std::runtime_error(os.str());
  }
  const int max_order_limit = settings.method == IntegrationMethod::kBdf ? 5 : 12;
  if (settings.max_order < 1 || settings.max_order > max_order_limit) {
    os << "vehicle integrator: max_order must be in [1, " << max_order_limit << "], got " << settings.max_order;
    throw std::runtime_error(os.str());
  }
  if (!(settings.max_step >= 0.0) || !(settings.initial_step >= 0.0)) {
    os << "vehicle integrator: max_step and initial_step must be >= 0, got " << settings.max_step << ", "
       << settings.initial_step;
    throw std::runtime_error(os.str());
  }
  s.t = t0;
  s.check(SUNContext_Create(nullptr, &s.context), "SUNContext_Create");
  const sunindextype n = model.stateSize();
  s.y = N_VNew_Serial(n, s.context);
  s.dky = N_VNew_Serial(n, s.context);
  if (s.y == nullptr || s.dky == nullptr) throw std::runtime_error("vehicle integrator: N_VNew_Serial failed");
  s.stateMap() = y0;
  s.cvode = CVodeCreate(settings.method == IntegrationMethod::kBdf ? CV_BDF : CV_ADAMS, s.context);
  if (s.cvode == nullptr) throw std::runtime_error("vehicle integrator: CVodeCreate failed");
  s.check(CVodeSetErrHandlerFn(s.cvode, &Impl::errorHandler, &s), "CVodeSetErrHandlerFn");
  // A caller-supplied initial state may violate the constraints: project before the first step.
  s.projectIfNeeded();
  s.check(CVodeInit(s.cvode, &Impl::rhs, t0, s.y), "CVodeInit");
  s.check(CVodeSetUserData(s.cvode, &s), "CVodeSetUserData");
  s.check(CVodeSStolerances(s.cvode, settings.rtol, settings.atol), "CVodeSStolerances");
  s.check(CVodeSetMaxOrd(s.cvode, settings.max_order), "CVodeSetMaxOrd");
  s.check(CVodeSetMaxNumSteps(s.cvode, settings.max_steps_per_call), "CVodeSetMaxNumSteps");
  if (settings.max_step > 0.0) s.check(CVodeSetMaxStep(s.cvode, settings.max_step), "CVodeSetMaxStep");
  if (settings.initial_step > 0.0) s.check(CVodeSetInitStep(s.cvode, settings.initial_step), "CVodeSetInitStep");
  if (settings.method == IntegrationMethod::kBdf && settings.jacobian == JacobianKind::kColoured) {
    s.pattern = std::make_unique<JacobianPattern>(model);
    s.jacobian_work = std::make_unique<JacobianWork>(model, *s.pattern);
    s.error_weights = N_VNew_Serial(n, s.context);
    if (settings.linear_solver == LinearSolverKind::kSparseKlu) {
      s.jacobian = SUNSparseMatrix(n, n, s.pattern->nonzeros(), CSC_MAT, s.context);
      s.linear_solver = s.jacobian != nullptr ? SUNLinSol_KLU(s.y, s.jacobian, s.context) : nullptr;
      // AMD: on the paper coach's I - gamma J, 28 % fewer instructions per refactorisation than KLU's
      // default COLAMD (doc/simulator.md).
      if (s.linear_solver != nullptr && SUNLinSol_KLUSetOrdering(s.linear_solver, 0) != SUNLS_SUCCESS) {
        throw std::runtime_error("vehicle integrator: SUNLinSol_KLUSetOrdering failed");
      }
    } else {
      s.jacobian = SUNDenseMatrix(n, n, s.context);
      s.linear_solver = s.jacobian != nullptr ? SUNLinSol_Dense(s.y, s.jacobian, s.context) : nullptr;
    }
    if (s.error_weights == nullptr || s.jacobian == nullptr || s.linear_solver == nullptr) {
      throw std::runtime_error("vehicle integrator: matrix / linear solver creation failed");
    }
    s.check(CVodeSetLinearSolver(s.cvode, s.linear_solver, s.jacobian), "CVodeSetLinearSolver");
    if (settings.linear_solver == LinearSolverKind::kSparseKlu && settings.direct_linear_system) {
      s.writePattern(s.jacobian);
      s.check(CVodeSetLinSysFn(s.cvode, &Impl::colouredLinearSystem), "CVodeSetLinSysFn");
    } else {
      s.check(CVodeSetJacFn(s.cvode, &Impl::colouredJacobian), "CVodeSetJacFn");
    }
    if (!settings.spin_bodies.empty()) {
      if (settings.jacobian_max_age < 1 || settings.linear_setup_interval < 1) {
        throw std::runtime_error("vehicle integrator: jacobian_max_age and linear_setup_interval must be >= 1");
      }
      s.spin = std::make_unique<SpinTransport>(model, *s.pattern, settings.spin_bodies);
      s.carried_values.assign(static_cast<std::size_t>(s.pattern->nonzeros()), 0.0);
      // CVODE asks for a Jacobian at every set-up; updateJacobian decides between carrying and evaluating.
      s.check(CVodeSetJacEvalFrequency(s.cvode, 1), "CVodeSetJacEvalFrequency");
      s.check(CVodeSetLSetupFrequency(s.cvode, settings.linear_setup_interval), "CVodeSetLSetupFrequency");
    }
  } else if (settings.method == IntegrationMethod::kBdf) {
    s.jacobian = SUNDenseMatrix(n, n, s.context);
    s.linear_solver = SUNLinSol_Dense(s.y, s.jacobian, s.context);
    if (s.jacobian == nullptr || s.linear_solver == nullptr) {
      throw std::runtime_error("vehicle integrator: dense matrix / linear solver creation failed");
    }
    // No Jacobian function: CVODE uses its difference-quotient approximation.
    s.check(CVodeSetLinearSolver(s.cvode, s.linear_solver, s.jacobian), "CVodeSetLinearSolver");
    if (settings.cost != nullptr) s.check(CVodeSetJacFn(s.cvode, &Impl::timedDqJacobian), "CVodeSetJacFn");
  } else {
    s.nonlinear_solver = SUNNonlinSol_FixedPoint(s.y, 0, s.context);
    if (s.nonlinear_solver == nullptr)
      throw std::runtime_error("vehicle integrator: fixed-point solver creation failed");
    s.check(CVodeSetNonlinearSolver(s.cvode, s.nonlinear_solver), "CVodeSetNonlinearSolver");
  }
}

VehicleIntegrator::~VehicleIntegrator() = default;

void VehicleIntegrator::advanceTo(double t) {
  Impl& s = *impl_;
  if (!(t > s.t)) {
    std::ostringstream os;
    os << "vehicle integrator: advanceTo(" << t << ") must go beyond the current time " << s.t;
    throw std::runtime_error(os.str());
  }
  s.last_error[0] = '\0';
  realtype t_reached = s.t;
  const int flag = s.stepTo(s.cvode, t, s.y, &t_reached);
  const bool bdf_failed = flag == CV_ERR_FAILURE || flag == CV_CONV_FAILURE;
  if (bdf_failed && s.settings.method == IntegrationMethod::kBdf && s.settings.adams_fallback) {
    // y holds the last successful step at t_reached: Adams takes the rest of the interval, BDF restarts at t.
    s.t = t_reached;
    s.fallBackToAdams(t);
  } else {
    if (flag < 0) s.fail("CVode", flag);
    s.ls_counters_stale = false;
    s.t = t_reached;
    s.stepped_since_init = true;
  }
  if (s.projectIfNeeded()) s.reInit();
}

void VehicleIntegrator::interpolateAt(double t, Eigen::Ref<Eigen::VectorXd> y_out) const {
  const Impl& s = *impl_;
  if (!s.stepped_since_init) {
    if (std::abs(t - s.t) > 1e-12 * std::max(1.0, std::abs(s.t))) {
      std::ostringstream os;
      os << "vehicle integrator: interpolateAt(" << t << "): no step since (re)initialisation at " << s.t;
      throw std::runtime_error(os.str());
    }
    y_out = s.stateMap();
    return;
  }
  const int flag = CVodeGetDky(s.cvode, t, 0, s.dky);
  if (flag < 0) {
    double t0 = 0.0, t1 = 0.0;
    lastStepInterval(t0, t1);
    std::ostringstream os;
    os << "vehicle integrator: interpolateAt(" << t << ") outside the last step [" << t0 << ", " << t1 << "]";
    throw std::runtime_error(os.str());
  }
  y_out = Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(s.dky), s.model.stateSize());
}

void VehicleIntegrator::lastStepInterval(double& t_begin, double& t_end) const {
  const Impl& s = *impl_;
  if (!s.stepped_since_init) {
    t_begin = t_end = s.t;
    return;
  }
  realtype t_current = s.t, h_last = 0.0;
  CVodeGetCurrentTime(s.cvode, &t_current);
  CVodeGetLastStep(s.cvode, &h_last);
  t_end = t_current;
  t_begin = t_current - h_last;
}

void VehicleIntegrator::reset(const Eigen::VectorXd& y, double t) {
  Impl& s = *impl_;
  if (y.size() != s.model.stateSize()) {
    throw std::runtime_error("vehicle integrator: Reset with a state of " + std::to_string(y.size()) +
                             " entries, the model needs " + std::to_string(s.model.stateSize()));
  }
  s.stateMap() = y;
  s.t = t;
  s.projectIfNeeded();
  s.reInit();
}

double VehicleIntegrator::time() const { return impl_->t; }

Eigen::Map<const Eigen::VectorXd> VehicleIntegrator::state() const {
  return Eigen::Map<const Eigen::VectorXd>(N_VGetArrayPointer(impl_->y), impl_->model.stateSize());
}

IntegratorCounters VehicleIntegrator::counters() const {
  const Impl& s = *impl_;
  const IntegratorCounters now = s.currentCounters();
  IntegratorCounters c = s.base;
  Impl::addCvodeCounts(now, c);
  c.rhs_evals_jacobian += s.coloured_jacobian_rhs;
  if (s.pattern != nullptr) {
    // CVODE counts every Jacobian handed to it; the carried ones are not evaluations.
    c.jacobian_evals = s.coloured_jacobians;
    c.jacobian_carries = s.carried_jacobians;
  }
  c.adams_fallbacks = s.base.adams_fallbacks;
  c.last_order = now.last_order;
  c.last_step = now.last_step;
  return c;
}

ConstraintViolation VehicleIntegrator::violation() {
  return evaluateViolation(impl_->model, impl_->stateMap(), impl_->data);
}

}  // namespace rail::vehicle
