#include "model/plant/plant_integrator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <vector>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "model/common/errors.hpp"
#include "model/plant/flexible_joint_dynamics.hpp"
#include "model/plant/plant_newton_solver.hpp"
#include "model/plant/plant_vector_operations.hpp"

namespace jointcomp {

// Every SUNDIALS object of one plant, each with its owner here and freed in reverse order.
struct PlantIntegrator::Solver {
  SUNContext context = nullptr;
  N_Vector y = nullptr;
  N_Vector y_now = nullptr;  // the state at the plant's time when CVODE is ahead of it (step_past_updates_s)
  // Their data, which stays where it is for the vectors' lives: now() reads it on every output, and
  // N_VGetArrayPointer is a call through the vector's operations table.
  double* y_data = nullptr;
  double* y_now_data = nullptr;
  N_Vector absolute_tolerances = nullptr;
  SUNMatrix jacobian = nullptr;
  SUNLinearSolver linear_solver = nullptr;
  void* cvode = nullptr;
  std::unique_ptr<StructuredLinearSolver> structured;  // the content of linear_solver when it is ours
  std::vector<double> saved_jacobian;                  // the structured solver's Jacobian, kept across setups
  long jacobian_evaluations = 0;                       // of saved_jacobian (CVODE counts only its own)
  std::string last_error;                              // CVODE's own message for the last failure
  std::string rhs_error;                               // why our right-hand side refused, if it did
  PlantStatistics before_restart;                      // counts of earlier integrator runs (a restart zeroes CVODE's)

  ~Solver() {
    if (cvode) CVodeFree(&cvode);
    if (linear_solver) SUNLinSolFree(linear_solver);
    if (jacobian) SUNMatDestroy(jacobian);
    if (absolute_tolerances) N_VDestroy(absolute_tolerances);
    if (y_now) N_VDestroy(y_now);
    if (y) N_VDestroy(y);
    if (context) SUNContext_Free(&context);
  }
};

namespace {

// CVODE's name of a return flag. SUNDIALS 6 allocates the name for the caller, who must free it.
std::string cvodeFlagName(long flag) {
  char* name = CVodeGetReturnFlagName(flag);
  std::string text = name ? name : "unknown flag";
  std::free(name);
  return text;
}

void captureCvodeError(int error_code, const char* module, const char* function, char* message, void* user_data) {
  auto* solver = static_cast<std::string*>(user_data);
  *solver = std::string(module ? module : "CVODE") + "/" + (function ? function : "?") + " (" +
            cvodeFlagName(error_code) + "): " + (message ? message : "");
}

StructuredLinearSolver& structuredOf(SUNLinearSolver solver) {
  return *static_cast<StructuredLinearSolver*>(solver->content);
}

// The SUNLinearSolver around a StructuredLinearSolver that `content` owns (outlives the solver).
SUNLinearSolver newStructuredSolver(StructuredLinearSolver& content, SUNContext context) {
  SUNLinearSolver solver = SUNLinSolNewEmpty(context);
  if (!solver) return nullptr;
  solver->content = &content;
  solver->ops->gettype = [](SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; };
  solver->ops->getid = [](SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; };
  solver->ops->initialize = [](SUNLinearSolver) { return SUNLS_SUCCESS; };
  // The Jacobian and gamma come from plantLinearSystem(), called by CVODE just before each setup; the
  // matrix CVODE passes is left unused.
  solver->ops->setup = [](SUNLinearSolver s, SUNMatrix) {
    StructuredLinearSolver& structured = structuredOf(s);
    return structured.setup(structured.jacobian, structured.gamma);
  };
  solver->ops->solve = [](SUNLinearSolver s, SUNMatrix, N_Vector x, N_Vector b, realtype) {
    return structuredOf(s).solve(N_VGetArrayPointer(x), N_VGetArrayPointer(b));
  };
  solver->ops->lastflag = [](SUNLinearSolver s) { return static_cast<sunindextype>(structuredOf(s).last_flag); };
  solver->ops->free = [](SUNLinearSolver s) {
    s->content = nullptr;  // owned by the plant's Solver
    SUNLinSolFreeEmpty(s);
    return SUNLS_SUCCESS;
  };
  return solver;
}

void check(int flag, const char* call) {
  if (flag < 0) throw SolverError(std::string("CVODE setup failed in ") + call + ": " + cvodeFlagName(flag));
}

int cvodeRightHandSide(realtype t, N_Vector y, N_Vector ydot, void* user_data) {
  auto* integrator = static_cast<PlantIntegrator*>(user_data);
  try {
    plantDerivative(integrator->model(), integrator->data(), t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
  } catch (const std::exception&) {
    return 1;  // recoverable: CVODE retries with a smaller step, and reports if it cannot
  }
  const double* values = N_VGetArrayPointer(ydot);
  for (int i = 0; i < integrator->model().stateSize(); ++i) {
    if (!std::isfinite(values[i])) return 1;
  }
  return 0;
}

int cvodeJacobian(realtype t, N_Vector y, N_Vector, SUNMatrix jacobian, void* user_data, N_Vector, N_Vector, N_Vector) {
  auto* integrator = static_cast<PlantIntegrator*>(user_data);
  double* values = SUNDenseMatrix_Data(jacobian);
  try {
    // throws on an entry that is not finite
    plantJacobian(integrator->model(), integrator->data(), t, N_VGetArrayPointer(y), values);
  } catch (const std::exception&) {
    return 1;  // recoverable, as for the right-hand side: CVODE retries smaller and reports if it cannot
  }
  return 0;
}

// CVODE's linear-system function for the structured solver: the plant's Jacobian when CVODE asks for a
// fresh one (jacobian_ok false), otherwise the saved one, and gamma, handed to the solver's setup.
int cvodeLinearSystem(realtype t, N_Vector y, N_Vector, SUNMatrix, booleantype jacobian_ok,
                      booleantype* jacobian_current, realtype gamma, void* user_data, N_Vector, N_Vector, N_Vector) {
  auto* integrator = static_cast<PlantIntegrator*>(user_data);
  return integrator->prepareNewtonSystem(t, N_VGetArrayPointer(y), jacobian_ok != SUNFALSE, gamma, jacobian_current);
}

}  // namespace

PlantIntegrator::PlantIntegrator(const PlantModel& model, PlantData& data)
    : model_(model), data_(data), solver_(std::make_unique<Solver>()) {
  configure();
}

PlantIntegrator::~PlantIntegrator() = default;

std::string PlantIntegrator::flagName(long flag) { return cvodeFlagName(flag); }

bool PlantIntegrator::budgetSpent(int flag) { return flag == CV_TOO_MUCH_WORK; }

const std::string& PlantIntegrator::lastError() const { return solver_->last_error; }

double* PlantIntegrator::state() { return solver_->y_data; }

const double* PlantIntegrator::state(bool ahead) const { return ahead ? solver_->y_now_data : solver_->y_data; }

bool PlantIntegrator::cvodeTime(double& time) const {
  realtype at = time;
  if (CVodeGetCurrentTime(solver_->cvode, &at) != CV_SUCCESS) return false;
  time = at;
  return true;
}

void PlantIntegrator::restart(double time, bool ahead) {
  Solver& s = *solver_;
  s.before_restart = statistics(PlantStatistics{});  // CVodeReInit zeroes CVODE's counts
  if (ahead) N_VScale(1.0, s.y_now, s.y);            // from the state at time, not from CVODE's last step ahead of it
  check(CVodeReInit(s.cvode, time, s.y), "CVodeReInit");
}

void PlantIntegrator::configure() {
  Solver& s = *solver_;
  check(SUNContext_Create(nullptr, &s.context), "SUNContext_Create");
  s.y = N_VNew_Serial(model_.stateSize(), s.context);
  s.y_now = N_VNew_Serial(model_.stateSize(), s.context);
  s.jacobian = SUNDenseMatrix(model_.stateSize(), model_.stateSize(), s.context);
  if (!s.y || !s.y_now || !s.jacobian) throw SolverError("plant: SUNDIALS could not allocate the state");
  s.y_data = N_VGetArrayPointer(s.y);
  s.y_now_data = N_VGetArrayPointer(s.y_now);
  useFastVectorOperations(s.y);  // before CVODE clones its own vectors from it
  // CVodeGetDky interpolates into y_now at every update that CVODE stepped past: without these, SUNDIALS'
  // unoptimised serial sums were a tenth of a 1 ms FMU step.
  useFastVectorOperations(s.y_now);
  if (model_.analytic_slope && model_.options.analytic_jacobian && model_.options.structured_linear_solver) {
    s.structured = std::make_unique<StructuredLinearSolver>(model_.n);
    s.linear_solver = newStructuredSolver(*s.structured, s.context);
  } else {
    s.linear_solver = SUNLinSol_Dense(s.y, s.jacobian, s.context);
  }
  s.cvode = CVodeCreate(CV_BDF, s.context);
  if (!s.linear_solver || !s.cvode) throw SolverError("plant: SUNDIALS could not create the solver");
  check(CVodeSetErrHandlerFn(s.cvode, captureCvodeError, &s.last_error), "CVodeSetErrHandlerFn");
  N_VConst(0.0, s.y);
  check(CVodeInit(s.cvode, cvodeRightHandSide, 0.0, s.y), "CVodeInit");
  check(CVodeSetUserData(s.cvode, this), "CVodeSetUserData");
  s.absolute_tolerances = N_VNew_Serial(model_.stateSize(), s.context);
  if (!s.absolute_tolerances) throw SolverError("plant: SUNDIALS could not allocate the tolerances");
  useFastVectorOperations(s.absolute_tolerances);
  double* tolerances = N_VGetArrayPointer(s.absolute_tolerances);
  for (int i = 0; i < model_.stateSize(); ++i) {
    const bool velocity = (i >= model_.n && i < 2 * model_.n) || (i >= 3 * model_.n && i < 4 * model_.n);
    tolerances[i] = model_.options.absolute_tolerance * (velocity ? model_.options.velocity_tolerance_factor : 1.0);
  }
  check(CVodeSVtolerances(s.cvode, model_.options.relative_tolerance, s.absolute_tolerances), "CVodeSVtolerances");
  check(CVodeSetLinearSolver(s.cvode, s.linear_solver, s.jacobian), "CVodeSetLinearSolver");
  if (s.structured) {
    s.saved_jacobian.assign(static_cast<std::size_t>(model_.stateSize()) * model_.stateSize(), 0.0);
    check(CVodeSetLinSysFn(s.cvode, cvodeLinearSystem), "CVodeSetLinSysFn");
  } else if (model_.analytic_slope && model_.options.analytic_jacobian) {
    check(CVodeSetJacFn(s.cvode, cvodeJacobian), "CVodeSetJacFn");
  }
  check(CVodeSetMaxNumSteps(s.cvode, model_.options.max_steps_per_advance), "CVodeSetMaxNumSteps");
  check(CVodeSetMaxOrd(s.cvode, model_.options.max_order), "CVodeSetMaxOrd");
  if (model_.options.max_step > 0.0) check(CVodeSetMaxStep(s.cvode, model_.options.max_step), "CVodeSetMaxStep");
  check(CVodeSetJacEvalFrequency(s.cvode, model_.options.jacobian_reuse_steps), "CVodeSetJacEvalFrequency");
  check(CVodeSetLSetupFrequency(s.cvode, model_.options.newton_setup_steps), "CVodeSetLSetupFrequency");
  check(CVodeSetDeltaGammaMaxLSetup(s.cvode, model_.options.newton_setup_gamma_change), "CVodeSetDeltaGammaMaxLSetup");
}

// Stepping past the end pays only for advances shorter than CVODE's step, and not for those of half the
// horizon or more (CVODE's step would span at most about two). Those end on their time (from where CVODE is,
// if it is ahead), as without the option: updates of exactly half the horizon too, however their times round
// (CVODE's own time roundoff, 100 eps (|t| + h), is allowed for). CVODE reports a step it cut to end on the
// last advance's end as (end - t)(1 - 4 eps) (SUNDIALS 6), so an advance as long counts as shorter than the
// step, or updates a binary fraction of a second apart (1/1024 s) would never be stepped past
// (docs/performance.md has the measurements behind this).
bool PlantIntegrator::stepsPast(double time, double end_time, double& cvode_time) const {
  cvode_time = time;
  if (!(model_.options.step_past_updates_s > 0.0)) return false;
  const Solver& s = *solver_;
  realtype planned = 0.0;  // 0 before the first step after a (re)start
  realtype at = time;
  if (CVodeGetCurrentTime(s.cvode, &at) == CV_SUCCESS) cvode_time = at;
  if (CVodeGetCurrentStep(s.cvode, &planned) != CV_SUCCESS) planned = 0.0;
  const double length = end_time - time;
  const double horizon = model_.options.step_past_updates_s;
  const double roundoff = 100.0 * std::numeric_limits<double>::epsilon() * (std::fabs(end_time) + horizon);
  return cvode_time >= end_time || (length < 0.5 * horizon - roundoff &&
                                    length <= planned * (1.0 + 16.0 * std::numeric_limits<double>::epsilon()));
}

int PlantIntegrator::advance(double time, double end_time, bool ahead, long budget, bool& past, double& reached) {
  Solver& s = *solver_;
  double cvode_time = time;
  past = stepsPast(time, end_time, cvode_time);
  if (!past) check(CVodeSetStopTime(s.cvode, end_time), "CVodeSetStopTime");
  s.last_error.clear();
  reached = time;
  if (past) return integratePast(end_time, cvode_time, budget, reached);
  if (model_.options.even_steps) return integrateEvenly(time, end_time, ahead, budget, reached);
  check(CVodeSetMaxNumSteps(s.cvode, budget), "CVodeSetMaxNumSteps");
  realtype at = time;
  const int flag = CVode(s.cvode, end_time, s.y, &at, CV_NORMAL);
  reached = at;
  return flag;
}

int PlantIntegrator::prepareNewtonSystem(double t, const double* y, bool jacobian_ok, double gamma,
                                         int* jacobian_current) {
  Solver& s = *solver_;
  *jacobian_current = SUNFALSE;
  if (!jacobian_ok || s.jacobian_evaluations == 0) {
    try {
      plantJacobian(model_, data_, t, y, s.saved_jacobian.data());  // throws on an entry that is not finite
    } catch (const std::exception&) {
      return 1;  // recoverable, as for the right-hand side: CVODE retries smaller and reports if it cannot
    }
    ++s.jacobian_evaluations;
    *jacobian_current = SUNTRUE;
    s.structured->layout_checked = false;
  }
  s.structured->jacobian = s.saved_jacobian.data();
  s.structured->gamma = gamma;
  return 0;
}

PlantStatistics PlantIntegrator::statistics(const PlantStatistics& own) const {
  const Solver& s = *solver_;
  long steps = 0, rhs = 0, jacobians = 0, error_failures = 0, convergence_failures = 0, rhs_for_jacobians = 0;
  long newton_iterations = 0, setups = 0;
  CVodeGetNumNonlinSolvIters(s.cvode, &newton_iterations);
  CVodeGetNumLinSolvSetups(s.cvode, &setups);
  CVodeGetNumSteps(s.cvode, &steps);
  CVodeGetNumRhsEvals(s.cvode, &rhs);
  CVodeGetNumJacEvals(s.cvode, &jacobians);
  CVodeGetNumLinRhsEvals(s.cvode, &rhs_for_jacobians);
  CVodeGetNumErrTestFails(s.cvode, &error_failures);
  CVodeGetNumNonlinSolvConvFails(s.cvode, &convergence_failures);
  PlantStatistics counts = own;
  counts.steps = s.before_restart.steps + steps;
  counts.rhs_evaluations = s.before_restart.rhs_evaluations + rhs + rhs_for_jacobians;
  counts.jacobian_rhs_evaluations = s.before_restart.jacobian_rhs_evaluations + rhs_for_jacobians;
  counts.jacobian_evaluations =
      s.structured ? s.jacobian_evaluations : s.before_restart.jacobian_evaluations + jacobians;
  counts.nonlinear_iterations = s.before_restart.nonlinear_iterations + newton_iterations;
  counts.linear_solver_setups = s.before_restart.linear_solver_setups + setups;
  counts.error_test_failures = s.before_restart.error_test_failures + error_failures;
  counts.nonlinear_convergence_failures = s.before_restart.nonlinear_convergence_failures + convergence_failures;
  return counts;
}

// PlantOptions::step_past_updates_s: CVODE's own steps until one ends at or beyond end_time, in one CV_NORMAL
// call; the stop time only bounds how far past end_time they may go. Steps already beyond end_time (an
// earlier advance's) are not taken again. The next advance steps past its end again only if CVODE's report
// of the step it plans (CVodeGetCurrentStep) is longer than the advance. After a CV_ONE_STEP call CVODE
// reports, and takes, its next step cut to what is left before the stop time (SUNDIALS 6, cvode.c): here at
// most step_past_updates_s past this advance's end and often much less, so the plant fell back to stopping
// at updates that CVODE could have stepped over. After a CV_NORMAL call it reports the step it plans.
// cvode_time: CVODE's time, as advance read it. The work budget is CVODE's count of steps in the call.
int PlantIntegrator::integratePast(double end_time, double cvode_time, long budget, double& reached) {
  Solver& s = *solver_;
  reached = cvode_time;
  // CVODE's last step ends at or beyond end_time and began before it: its interpolant covers end_time.
  if (cvode_time >= end_time) {
    check(CVodeGetDky(s.cvode, end_time, 0, s.y_now), "CVodeGetDky");
    return CV_SUCCESS;
  }
  check(CVodeSetStopTime(s.cvode, end_time + model_.options.step_past_updates_s), "CVodeSetStopTime");
  check(CVodeSetMaxNumSteps(s.cvode, budget), "CVodeSetMaxNumSteps");
  realtype output_time = end_time;
  // The output at end_time is that interpolant's value there, written straight into y_now.
  const int flag = CVode(s.cvode, end_time, s.y_now, &output_time, CV_NORMAL);
  realtype at = reached;
  if (CVodeGetCurrentTime(s.cvode, &at) == CV_SUCCESS) reached = at;
  if (flag < 0) N_VScale(1.0, s.y_now, s.y);  // CVODE's state at its last good step, where advance restarts
  return flag;
}

// PlantOptions::even_steps: one CVODE step per call. When what is left of the advance is more than CVODE's
// planned step but less than two, the stop time is set at its middle, so that the advance ends in two equal
// steps instead of the planned one and a sliver (a cut step in front of the end would make CVODE keep its
// size and hold back its growth, so the stop time is moved only there). The count of calls keeps the
// advance's work budget.
int PlantIntegrator::integrateEvenly(double time, double end_time, bool ahead, long budget, double& reached) {
  Solver& s = *solver_;
  realtype at = time;
  if (ahead && CVodeGetCurrentTime(s.cvode, &at) != CV_SUCCESS) at = time;  // CVODE stepped past time_ before
  for (long step = 0; step < budget; ++step) {
    realtype planned = 0.0;  // 0 before CVODE's first step after a (re)start: it chooses that one itself
    if (CVodeGetCurrentStep(s.cvode, &planned) != CV_SUCCESS) planned = 0.0;
    const double left = end_time - at;
    // CVODE takes a stop time as reached within 100 roundoffs (its FUZZ_FACTOR): a rest within that of the
    // planned step is one step, and a rest of two planned steps is left to CVODE (a cut by a roundoff would
    // still count as a change of step).
    const double fuzz = 100.0 * std::numeric_limits<double>::epsilon() * (std::fabs(at) + planned);
    double stop = end_time;
    if (planned > 0.0 && left - fuzz > planned && 0.5 * left < planned - fuzz) stop = at + 0.5 * left;
    check(CVodeSetStopTime(s.cvode, stop), "CVodeSetStopTime");
    const int flag = CVode(s.cvode, end_time, s.y, &at, CV_ONE_STEP);
    reached = at;
    if (flag < 0) return flag;
    if (stop == end_time && flag == CV_TSTOP_RETURN) return flag;
  }
  return CV_TOO_MUCH_WORK;
}

}  // namespace jointcomp
