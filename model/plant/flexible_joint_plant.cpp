#include "model/plant/flexible_joint_plant.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "model/common/errors.hpp"
#include "model/effects/compliance.hpp"
#include "model/effects/spring_balancer.hpp"
#include "model/effects/transmission_error.hpp"
#include "model/plant/plant_vector_operations.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {

// Solves CVODE's Newton systems (I - gamma J) x = b for the plant's layout y = [q, qd, p, pd, z]: the rows
// of q and p are the identity and -gamma on their own velocity, those of z are diagonal in p, pd and z, so
// q, p and z are eliminated and a 2n x 2n system in (qd, pd) remains, one 12 x 12 LU for the RX170 instead
// of 30 x 30 (the Schur complement further onto 6 would save little more). It reads I - gamma J from the
// Jacobian and gamma (CVODE's linear-system function hands them over) with the arithmetic of SUNDIALS'
// SUNMatScaleAddI, so it never forms the dense 30 x 30 matrix (Debian's SUNDIALS copies and scales it
// unoptimised). Setup checks the layout and fails unrecoverably on a matrix without it.
struct StructuredLinearSolver {
  using Reduced =
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 2 * kMaxJoints, 2 * kMaxJoints>;
  using ReducedVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 2 * kMaxJoints, 1>;

  int n = 0;
  Reduced reduced;
  // The rows of qd and pd in I - gamma J, in the columns of q, p and z, read once per setup: every Newton
  // iteration's solve needs them.
  using Coupling = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 2 * kMaxJoints, kMaxJoints>;
  Coupling by_position, by_motor, by_integral;
  // `reduced` holds its own LU factors after a setup (unit-lower L below the diagonal, U on and above), with
  // the row taken as pivot at each column: a 12x12 by plain loops, a fifth of what Eigen's blocked
  // PartialPivLU of a dynamic matrix costs at this size (it showed in the profile of the FMU's step).
  std::array<int, 2 * kMaxJoints> pivot_row{};
  ReducedVector rhs, solution;
  const double* jacobian = nullptr;  // of the last setup, column-major, 5n x 5n; CVODE keeps it unchanged
  double gamma = 0.0;                // until the next setup
  bool layout_checked = false;       // for this Jacobian (the layout does not depend on gamma)
  // Per joint: q = b_q + position_gain qd, p = b_p + motor_gain pd, and the integral row
  // integral_by_p p + integral_by_pd pd + integral_self z = b_z, so z = (b_z - integral_by_p b_p) / integral_self
  // + integral_by_pd_reduced pd.
  JointVector position_gain, motor_gain, integral_by_p, integral_by_pd, integral_self, integral_by_pd_reduced;
  JointVector integral_offset;
  long last_flag = 0;

  explicit StructuredLinearSolver(int dof)
      : n(dof),
        reduced(2 * dof, 2 * dof),
        by_position(2 * dof, dof),
        by_motor(2 * dof, dof),
        by_integral(2 * dof, dof),
        rhs(2 * dof),
        solution(2 * dof),
        position_gain(dof),
        motor_gain(dof),
        integral_by_p(dof),
        integral_by_pd(dof),
        integral_self(dof),
        integral_by_pd_reduced(dof),
        integral_offset(dof) {}

  // The entry (row, column) of I - gamma J: -gamma J, plus one on the diagonal, as SUNMatScaleAddI forms it.
  double at(int row, int column) const {
    const double scaled = -gamma * jacobian[static_cast<std::size_t>(column) * (5 * n) + row];
    return row == column ? scaled + 1.0 : scaled;
  }

  int setup(const double* jacobian_values, double newton_gamma) {
    jacobian = jacobian_values;
    gamma = newton_gamma;
    const int size = 5 * n;
    for (int k = 0; k < n; ++k) {
      const int q = k, qd = n + k, p = 2 * n + k, pd = 3 * n + k, z = 4 * n + k;
      for (int c = 0; c < size && !layout_checked; ++c) {
        const bool q_row_ok = c == qd || at(q, c) == (c == q ? 1.0 : 0.0);
        const bool p_row_ok = c == pd || at(p, c) == (c == p ? 1.0 : 0.0);
        const bool z_row_ok = c == p || c == pd || c == z || at(z, c) == 0.0;
        if (!q_row_ok || !p_row_ok || !z_row_ok) return last_flag = SUNLS_PACKAGE_FAIL_UNREC;
      }
      position_gain[k] = -at(q, qd);
      motor_gain[k] = -at(p, pd);
      integral_by_p[k] = at(z, p);
      integral_by_pd[k] = at(z, pd);
      integral_self[k] = at(z, z);
      if (integral_self[k] == 0.0) return last_flag = SUNLS_LUFACT_FAIL;
      integral_by_pd_reduced[k] = -(integral_by_p[k] * motor_gain[k] + integral_by_pd[k]) / integral_self[k];
    }
    layout_checked = true;
    for (int i = 0; i < 2 * n; ++i) {
      const int row = i < n ? n + i : 2 * n + i;  // the rows of qd, then those of pd
      for (int k = 0; k < n; ++k) {
        by_position(i, k) = at(row, k);
        by_motor(i, k) = at(row, 2 * n + k);
        by_integral(i, k) = at(row, 4 * n + k);
        reduced(i, k) = at(row, n + k) + by_position(i, k) * position_gain[k];
        reduced(i, n + k) =
            at(row, 3 * n + k) + by_motor(i, k) * motor_gain[k] + by_integral(i, k) * integral_by_pd_reduced[k];
      }
    }
    if (!factorReduced()) return last_flag = SUNLS_LUFACT_FAIL;  // recoverable
    return last_flag = SUNLS_SUCCESS;
  }

  // Gaussian elimination with partial pivoting (the largest magnitude in the column, the first of equals, as
  // LAPACK and Eigen choose) in place; false at a pivot that is zero or not finite.
  bool factorReduced() {
    const int m = 2 * n;
    double* a = reduced.data();  // column-major, m x m: entry (i, j) at a[j * m + i]
    for (int k = 0; k < m; ++k) {
      double* column = a + static_cast<std::ptrdiff_t>(k) * m;
      int pivot = k;
      double largest = std::abs(column[k]);
      for (int i = k + 1; i < m; ++i) {
        const double magnitude = std::abs(column[i]);
        if (magnitude > largest) {
          largest = magnitude;
          pivot = i;
        }
      }
      pivot_row[k] = pivot;
      if (pivot != k) {
        for (int j = 0; j < m; ++j) std::swap(a[j * m + k], a[j * m + pivot]);
      }
      const double diagonal = column[k];
      if (!(diagonal != 0.0) || !std::isfinite(diagonal)) return false;
      for (int i = k + 1; i < m; ++i) column[i] /= diagonal;
      for (int j = k + 1; j < m; ++j) {
        double* target = a + static_cast<std::ptrdiff_t>(j) * m;
        const double above = target[k];
        if (above == 0.0) continue;  // the motor block is mostly zeros; the entries are finite (checked Jacobian)
        for (int i = k + 1; i < m; ++i) target[i] -= column[i] * above;
      }
    }
    return true;
  }

  // solution = reduced^-1 rhs by the factors of the last setup; rhs is overwritten. kJoints: n when known
  // at compile time, 0 otherwise (see solve).
  template <int kJoints>
  void solveReduced() {
    const int m = 2 * (kJoints > 0 ? kJoints : n);
    const double* a = reduced.data();
    double* x = rhs.data();
    for (int k = 0; k < m; ++k) std::swap(x[k], x[pivot_row[k]]);
    for (int k = 0; k < m; ++k) {
      const double value = x[k];
      if (value == 0.0) continue;
      const double* column = a + static_cast<std::ptrdiff_t>(k) * m;
      for (int i = k + 1; i < m; ++i) x[i] -= column[i] * value;
    }
    for (int k = m - 1; k >= 0; --k) {
      const double* column = a + static_cast<std::ptrdiff_t>(k) * m;
      x[k] /= column[k];
      const double value = x[k];
      for (int i = 0; i < k; ++i) x[i] -= column[i] * value;
    }
    solution = rhs;
  }

  // x and b may be the same vector: every value of b is read before x is written where it was.
  int solve(double* x, const double* b) {
    // Six joints, the arms the project models, with the sizes known at compile time: the loops unrolled and
    // paired, a third fewer instructions per Newton iteration; the same operations on each value in the same
    // order, so the same bits as for any other n.
    return n == 6 ? solveWith<6>(x, b) : solveWith<0>(x, b);
  }

  template <int kJoints>
  int solveWith(double* x, const double* b) {
    const int dof = kJoints > 0 ? kJoints : n;
    for (int k = 0; k < dof; ++k)
      integral_offset[k] = (b[4 * dof + k] - integral_by_p[k] * b[2 * dof + k]) / integral_self[k];
    // Column by column (contiguous, so the compiler vectorises it over the rows), each row's sum in the
    // order of k as before: the same bits as row by row.
    for (int i = 0; i < 2 * dof; ++i) rhs[i] = b[i < dof ? dof + i : 2 * dof + i];
    double* value = rhs.data();
    for (int k = 0; k < dof; ++k) {
      const double b_q = b[k], b_p = b[2 * dof + k], b_z = integral_offset[k];
      const double* position = by_position.data() + static_cast<std::ptrdiff_t>(k) * 2 * dof;
      const double* motor = by_motor.data() + static_cast<std::ptrdiff_t>(k) * 2 * dof;
      const double* integral = by_integral.data() + static_cast<std::ptrdiff_t>(k) * 2 * dof;
      for (int i = 0; i < 2 * dof; ++i) value[i] -= position[i] * b_q + motor[i] * b_p + integral[i] * b_z;
    }
    solveReduced<kJoints>();
    for (int k = 0; k < dof; ++k) {
      const double link_rate = solution[k], motor_rate = solution[dof + k];
      x[k] = b[k] + position_gain[k] * link_rate;
      x[dof + k] = link_rate;
      x[2 * dof + k] = b[2 * dof + k] + motor_gain[k] * motor_rate;
      x[3 * dof + k] = motor_rate;
      x[4 * dof + k] = integral_offset[k] + integral_by_pd_reduced[k] * motor_rate;
    }
    return last_flag = SUNLS_SUCCESS;
  }
};

// Every SUNDIALS object of one plant, each with its owner here and freed in reverse order.
struct FlexibleJointPlant::Solver {
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

int plantRightHandSide(realtype t, N_Vector y, N_Vector ydot, void* user_data);
int plantJacobian(realtype t, N_Vector y, N_Vector fy, SUNMatrix jacobian, void* user_data, N_Vector, N_Vector,
                  N_Vector);
int plantLinearSystem(realtype t, N_Vector y, N_Vector fy, SUNMatrix matrix, booleantype jacobian_ok,
                      booleantype* jacobian_current, realtype gamma, void* user_data, N_Vector, N_Vector, N_Vector);

// CVODE's name of a return flag. SUNDIALS 6 allocates the name for the caller, who must free it.
std::string flagName(long flag) {
  char* name = CVodeGetReturnFlagName(flag);
  std::string text = name ? name : "unknown flag";
  std::free(name);
  return text;
}

void captureCvodeError(int error_code, const char* module, const char* function, char* message, void* user_data) {
  auto* solver = static_cast<std::string*>(user_data);
  *solver = std::string(module ? module : "CVODE") + "/" + (function ? function : "?") + " (" + flagName(error_code) +
            "): " + (message ? message : "");
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
  if (flag < 0) throw SolverError(std::string("CVODE setup failed in ") + call + ": " + flagName(flag));
}

}  // namespace

FlexibleJointPlant::FlexibleJointPlant(const JointErrorModel& truth, std::vector<DriveParameters> drives,
                                       PlantOptions options)
    : truth_(truth),
      drives_(std::move(drives)),
      options_(options),
      n_(truth.robot().dof()),
      ctx_(truth.robot().dof()),
      ws_(truth.robot()),
      solver_(std::make_unique<Solver>()) {
  const Robot& robot = truth_.robot();
  if (!robot.hasInertials()) {
    throw InvalidArgument("plant: link '" + robot.link_without_inertial +
                          "' has no inertial; the plant needs every mass");
  }
  if (static_cast<int>(drives_.size()) != n_) {
    throw InvalidArgument("plant: " + std::to_string(drives_.size()) + " drives for " + std::to_string(n_) + " joints");
  }
  for (int j = 0; j < n_; ++j) {
    const DriveParameters& d = drives_[j];
    const std::string where = "plant: drive of " + robot.joints[j].name + ": ";
    const double values[] = {d.motor_inertia_kgm2,
                             d.viscous_friction_nms_per_rad,
                             d.coulomb_friction_nm,
                             d.coulomb_velocity_scale_rad_per_s,
                             d.transmission_damping_nms_per_rad,
                             d.kp_nm_per_rad,
                             d.ki_nm_per_rad_s,
                             d.kd_nms_per_rad};
    for (double v : values) {
      if (!std::isfinite(v) || v < 0.0) throw InvalidArgument(where + "every value must be finite and non-negative");
    }
    if (!(d.motor_inertia_kgm2 > 0.0)) throw InvalidArgument(where + "motor_inertia_kgm2 must be positive");
    if (!(d.coulomb_velocity_scale_rad_per_s > 0.0)) {
      throw InvalidArgument(where + "coulomb_velocity_scale_rad_per_s must be positive");
    }
    // Gains no drive can have would make the integration crawl at micro-second steps (kp 1e12 ran for
    // minutes): the position loop's frequency sqrt(kp / J), its damping rate kd / J and the integral's
    // ki / J (a frequency cubed) are bounded well above any real servo.
    const double inertia = d.motor_inertia_kgm2;
    char text[320];
    auto refuse = [&](const char* name, double value, double rate, double limit, const char* unit) {
      std::snprintf(text, sizeof text,
                    "%s = %.6g with motor_inertia_kgm2 = %.6g gives %.3g %s, beyond the %.3g %s of any real drive "
                    "(the plant would need micro-second steps)",
                    name, value, inertia, rate, unit, limit, unit);
      throw InvalidArgument(where + text);
    };
    const double position_loop = std::sqrt(d.kp_nm_per_rad / inertia);
    if (position_loop > kMaxLoopFrequency)
      refuse("kp_nm_per_rad", d.kp_nm_per_rad, position_loop, kMaxLoopFrequency, "rad/s");
    if (d.kd_nms_per_rad / inertia > kMaxLoopFrequency)
      refuse("kd_nms_per_rad", d.kd_nms_per_rad, d.kd_nms_per_rad / inertia, kMaxLoopFrequency, "1/s");
    const double integral_limit = kMaxLoopFrequency * kMaxLoopFrequency * kMaxLoopFrequency;
    if (d.ki_nm_per_rad_s / inertia > integral_limit)
      refuse("ki_nm_per_rad_s", d.ki_nm_per_rad_s, d.ki_nm_per_rad_s / inertia, integral_limit, "rad/s^3");
  }
  compliance_index_ = truth_.findEffect(ComplianceEffect::kType);
  if (compliance_index_ < 0)
    throw InvalidArgument("plant: the joint-error model has no compliance effect (the joint springs)");
  const auto& compliance = static_cast<const ComplianceEffect&>(truth_.effect(compliance_index_));
  stiffness_.resize(n_);
  for (int j = 0; j < n_; ++j) {
    stiffness_[j] = compliance.stiffness(j);
    if (!std::isfinite(stiffness_[j])) {
      throw InvalidArgument("plant: " + robot.joints[j].name +
                            " is rigid in the compliance effect; the plant needs a "
                            "finite joint stiffness for every joint");
    }
  }
  load_mask_ = 0;
  error_mask_ = 0;
  JointVector probe = JointVector::Zero(n_);
  for (int i = 0; i < truth_.effectCount(); ++i) {
    const Effect& effect = truth_.effect(i);
    if (effect.role() == EffectRole::Load) load_mask_ |= EffectMask(1) << i;
    if (effect.role() == EffectRole::JointError && i != compliance_index_) {
      error_mask_ |= EffectMask(1) << i;
      if (effect.dependsOnCommand() && !effect.addMotorSlope(robot, ctx_, probe)) analytic_slope_ = false;
    }
    transmission_effects_.push_back(dynamic_cast<const TransmissionErrorEffect*>(&effect));
  }
  loads_read_kinematics_ = loadsReadKinematics(truth_, load_mask_);
  if (!(options_.relative_tolerance > 0.0) || !(options_.absolute_tolerance > 0.0) ||
      !(options_.velocity_tolerance_factor > 0.0) || options_.max_step < 0.0 || options_.max_steps_per_advance < 1) {
    throw InvalidArgument("plant: tolerances must be positive, max_step non-negative, max_steps_per_advance >= 1");
  }
  setWatchdog(options_.tracking_envelope_rad, options_.joint_limit_margin_rad);
  // Anti-windup by back-calculation: while a drive's torque is clamped, its integral is pulled back by
  // the clamped excess over ki Tt, with the tracking time Tt = sqrt(Ti Td) = sqrt(kd / ki) (Astrom and
  // Hagglund), Ti = kp / ki for a drive without kd, and the integral's own time scale cbrt(J / ki) for a
  // pure integral drive.
  windup_gain_.resize(n_);
  for (int j = 0; j < n_; ++j) {
    const DriveParameters& d = drives_[j];
    double tracking_time = 0.0;
    if (d.ki_nm_per_rad_s > 0.0) {
      if (d.kd_nms_per_rad > 0.0) {
        tracking_time = std::sqrt(d.kd_nms_per_rad / d.ki_nm_per_rad_s);
      } else if (d.kp_nm_per_rad > 0.0) {
        tracking_time = d.kp_nm_per_rad / d.ki_nm_per_rad_s;
      } else {
        tracking_time = std::cbrt(d.motor_inertia_kgm2 / d.ki_nm_per_rad_s);
      }
    }
    windup_gain_[j] = tracking_time > 0.0 ? 1.0 / (d.ki_nm_per_rad_s * tracking_time) : 0.0;
  }

  Solver& s = *solver_;
  check(SUNContext_Create(nullptr, &s.context), "SUNContext_Create");
  s.y = N_VNew_Serial(stateSize(), s.context);
  s.y_now = N_VNew_Serial(stateSize(), s.context);
  s.jacobian = SUNDenseMatrix(stateSize(), stateSize(), s.context);
  if (!s.y || !s.y_now || !s.jacobian) throw SolverError("plant: SUNDIALS could not allocate the state");
  s.y_data = N_VGetArrayPointer(s.y);
  s.y_now_data = N_VGetArrayPointer(s.y_now);
  useFastVectorOperations(s.y);  // before CVODE clones its own vectors from it
  // CVodeGetDky interpolates into y_now at every update that CVODE stepped past: without these, SUNDIALS'
  // unoptimised serial sums were a tenth of a 1 ms FMU step.
  useFastVectorOperations(s.y_now);
  if (analytic_slope_ && options_.analytic_jacobian && options_.structured_linear_solver) {
    s.structured = std::make_unique<StructuredLinearSolver>(n_);
    s.linear_solver = newStructuredSolver(*s.structured, s.context);
  } else {
    s.linear_solver = SUNLinSol_Dense(s.y, s.jacobian, s.context);
  }
  s.cvode = CVodeCreate(CV_BDF, s.context);
  if (!s.linear_solver || !s.cvode) throw SolverError("plant: SUNDIALS could not create the solver");
  check(CVodeSetErrHandlerFn(s.cvode, captureCvodeError, &s.last_error), "CVodeSetErrHandlerFn");
  N_VConst(0.0, s.y);
  check(CVodeInit(s.cvode, plantRightHandSide, 0.0, s.y), "CVodeInit");
  check(CVodeSetUserData(s.cvode, this), "CVodeSetUserData");
  s.absolute_tolerances = N_VNew_Serial(stateSize(), s.context);
  if (!s.absolute_tolerances) throw SolverError("plant: SUNDIALS could not allocate the tolerances");
  useFastVectorOperations(s.absolute_tolerances);
  double* tolerances = N_VGetArrayPointer(s.absolute_tolerances);
  for (int i = 0; i < stateSize(); ++i) {
    const bool velocity = (i >= n_ && i < 2 * n_) || (i >= 3 * n_ && i < 4 * n_);
    tolerances[i] = options_.absolute_tolerance * (velocity ? options_.velocity_tolerance_factor : 1.0);
  }
  check(CVodeSVtolerances(s.cvode, options_.relative_tolerance, s.absolute_tolerances), "CVodeSVtolerances");
  check(CVodeSetLinearSolver(s.cvode, s.linear_solver, s.jacobian), "CVodeSetLinearSolver");
  if (s.structured) {
    s.saved_jacobian.assign(static_cast<std::size_t>(stateSize()) * stateSize(), 0.0);
    check(CVodeSetLinSysFn(s.cvode, plantLinearSystem), "CVodeSetLinSysFn");
  } else if (analytic_slope_ && options_.analytic_jacobian) {
    check(CVodeSetJacFn(s.cvode, plantJacobian), "CVodeSetJacFn");
  }
  check(CVodeSetMaxNumSteps(s.cvode, options_.max_steps_per_advance), "CVodeSetMaxNumSteps");
  if (options_.max_order < 1 || options_.max_order > 5) throw InvalidArgument("plant: max_order must be 1 to 5");
  check(CVodeSetMaxOrd(s.cvode, options_.max_order), "CVodeSetMaxOrd");
  if (options_.max_step > 0.0) check(CVodeSetMaxStep(s.cvode, options_.max_step), "CVodeSetMaxStep");
  if (!(options_.jacobian_reuse_steps >= 1 && options_.jacobian_reuse_steps <= 100000)) {
    throw InvalidArgument("plant: jacobian_reuse_steps must be 1 to 100000 steps, not " +
                          std::to_string(options_.jacobian_reuse_steps));
  }
  if (!(options_.newton_setup_steps >= 1 && options_.newton_setup_steps <= 100000)) {
    throw InvalidArgument("plant: newton_setup_steps must be 1 to 100000 steps, not " +
                          std::to_string(options_.newton_setup_steps));
  }
  if (!(options_.newton_setup_gamma_change > 0.0 && options_.newton_setup_gamma_change <= 10.0)) {
    throw InvalidArgument("plant: newton_setup_gamma_change must be in (0, 10], not " +
                          std::to_string(options_.newton_setup_gamma_change));
  }
  check(CVodeSetJacEvalFrequency(s.cvode, options_.jacobian_reuse_steps), "CVodeSetJacEvalFrequency");
  check(CVodeSetLSetupFrequency(s.cvode, options_.newton_setup_steps), "CVodeSetLSetupFrequency");
  check(CVodeSetDeltaGammaMaxLSetup(s.cvode, options_.newton_setup_gamma_change), "CVodeSetDeltaGammaMaxLSetup");
  if (!(std::isfinite(options_.step_past_tolerance_rad) && options_.step_past_tolerance_rad >= 0.0 &&
        options_.step_past_tolerance_rad <= 10.0)) {
    throw InvalidArgument("plant: step_past_tolerance_rad must be in [0, 10] rad, not " +
                          std::to_string(options_.step_past_tolerance_rad));
  }
  if (!(std::isfinite(options_.step_past_updates_s) && options_.step_past_updates_s >= 0.0 &&
        options_.step_past_updates_s <= 1.0)) {
    throw InvalidArgument("plant: step_past_updates_s must be in [0, 1] s, not " +
                          std::to_string(options_.step_past_updates_s));
  }
  reference_ = JointVector::Zero(n_);
  reference_velocity_ = JointVector::Zero(n_);
  reference_acceleration_ = JointVector::Zero(n_);
  feedforward_ = JointVector::Zero(n_);
  feedforward_rate_ = JointVector::Zero(n_);
  reset(JointVector::Zero(n_));
}

FlexibleJointPlant::~FlexibleJointPlant() = default;

void FlexibleJointPlant::staticFeedforward(const JointVector& position, JointVector& torque) {
  ctx_.q = position;
  if (loadsWithoutKinematics(loads_read_kinematics_, ctx_)) {
    double sines[kMaxJoints], cosines[kMaxJoints];
    sinCosBatch(position.data(), n_, sines, cosines);
    loadTorqueInJointFrames(truth_, load_mask_, ws_, ctx_, cosines, sines);
  } else {
    computeLoadTorque(truth_, load_mask_, ws_, ctx_);
  }
  torque = ctx_.load_torque;
}

void FlexibleJointPlant::reset(const JointVector& command, double start_time) {
  checkJointVector(truth_.robot(), command, "command");
  if (!std::isfinite(start_time)) throw InvalidArgument("plant: start time is not finite");
  ctx_.command = command;
  const FixedPointReport settled = settleStatically(truth_, truth_.allEffects(), ws_, ctx_);
  if (!settled.converged) throw SolverError("plant: no static equilibrium found at the initial command");
  const JointVector q = ctx_.q;
  const JointVector rest = JointVector::Zero(n_);
  JointVector spring_torque, motor_reaction;
  transmissionTorques(command, rest, q, rest, spring_torque, motor_reaction);
  time_ = start_time;
  reference_ = command;
  reference_velocity_.setZero(n_);
  reference_acceleration_.setZero(n_);
  reference_time_ = start_time;
  staticFeedforward(command, feedforward_);
  feedforward_rate_.setZero(n_);
  feedforward_pending_ = false;
  blend_offset_.setZero(n_);
  blend_offset_velocity_.setZero(n_);
  blend_offset_acceleration_.setZero(n_);
  feedforward_offset_.setZero(n_);
  feedforward_offset_rate_.setZero(n_);
  blend_duration_ = 0.0;
  ahead_ = false;
  double* y = N_VGetArrayPointer(solver_->y);
  for (int j = 0; j < n_; ++j) {
    y[j] = q[j];
    y[n_ + j] = 0.0;
    y[2 * n_ + j] = command[j];
    y[3 * n_ + j] = 0.0;
    const double ki = drives_[j].ki_nm_per_rad_s;
    // The integral holds exactly what the motor must push against at rest, so the plant starts still.
    y[4 * n_ + j] = ki > 0.0 ? (motor_reaction[j] - feedforward_[j]) / ki : 0.0;
  }
  restart_ = true;
  tripped_.clear();
}

void FlexibleJointPlant::setReference(const JointVector& position, const JointVector& velocity) {
  checkJointVector(truth_.robot(), position, "reference position");
  checkJointVector(truth_.robot(), velocity, "reference velocity");
  // The interpolator extrapolates with the acceleration seen between the last two updates, and the
  // static-load feed-forward with its rate along the motion, so that the controller's output is nearly
  // continuous across updates and the integrator is not knocked back to small steps at each one.
  const double since_last = time_ - reference_time_;
  if (options_.smooth_reference) ensureFeedforward();  // the blend starts from the running feed-forward
  // Stepping past updates, CVODE may have integrated the old reference beyond time_ already: the new one
  // takes over from CVODE's next step only if it stays within step_past_tolerance_rad of the old one there.
  realtype ahead_time = time_;
  if (ahead_ && !restart_ && CVodeGetCurrentTime(solver_->cvode, &ahead_time) != CV_SUCCESS) ahead_time = time_;
  // (CVODE ending a step on time_ within its roundoff, as it takes a stop time, is not ahead of it.)
  const bool check_departure =
      ahead_time - time_ > 100.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::fabs(time_));
  const double departure_times[3] = {time_, 0.5 * (time_ + ahead_time), ahead_time};
  double old_reference[3][kMaxJoints];
  for (int k = 0; k < 3 && check_departure; ++k) {
    for (int j = 0; j < n_; ++j) old_reference[k][j] = referenceAt(j, departure_times[k]);
  }
  // The reference as it runs now, before the update: the blend starts from it.
  JointVector before_value(n_), before_velocity(n_), before_acceleration(n_), before_feedforward(n_),
      before_feedforward_rate(n_);
  for (int j = 0; j < n_ && options_.smooth_reference; ++j) {
    const ReferencePoint before = referencePoint(j, time_);
    before_value[j] = before.value;
    before_velocity[j] = before.velocity;
    before_acceleration[j] = before.acceleration;
    before_feedforward[j] = before.feedforward;
    before_feedforward_rate[j] = before.feedforward_rate;
  }
  if (since_last > 0.0) {
    reference_acceleration_ = (velocity - reference_velocity_) / since_last;
  } else {
    reference_acceleration_.setZero(n_);
  }
  reference_ = position;
  reference_velocity_ = velocity;
  reference_time_ = time_;
  feedforward_pending_ = true;
  if (options_.smooth_reference) ensureFeedforward();
  // The new extrapolation takes over from the old one over the interval the last update took (the next
  // one is expected as long); a second update at the same time keeps the blend's duration.
  const bool blended_before = blend_duration_ > 0.0;
  if (!options_.smooth_reference) {
    blend_duration_ = 0.0;
  } else if (since_last > 0.0) {
    blend_duration_ = since_last;
  }
  if (blend_duration_ > 0.0) {
    blend_offset_ = before_value - reference_;
    blend_offset_velocity_ = before_velocity - reference_velocity_;
    blend_offset_acceleration_ = before_acceleration - reference_acceleration_;
    feedforward_offset_ = before_feedforward - feedforward_;
    feedforward_offset_rate_ = before_feedforward_rate - feedforward_rate_;
  } else if (blended_before) {  // without a blend the offsets are zero already (reset, restoreState)
    blend_offset_.setZero(n_);
    blend_offset_velocity_.setZero(n_);
    blend_offset_acceleration_.setZero(n_);
    feedforward_offset_.setZero(n_);
    feedforward_offset_rate_.setZero(n_);
  }
  if (check_departure) {
    ++statistics_.updates_stepped_past;
    double departure = 0.0;
    for (int k = 0; k < 3; ++k) {
      for (int j = 0; j < n_; ++j) {
        departure = std::max(departure, std::fabs(referenceAt(j, departure_times[k]) - old_reference[k][j]));
      }
    }
    if (!(departure <= options_.step_past_tolerance_rad)) {
      ++statistics_.updates_restarted;
      restart_ = true;  // from the state at time_ (advance takes it from y_now), with the new reference
    }
  }
}

// The static-load feed-forward at the last update's reference, and its rate along the update's velocity in
// closed form at the same pose; a difference quotient only when a load effect does not know its rate.
void FlexibleJointPlant::ensureFeedforward() {
  if (!feedforward_pending_) return;
  feedforward_pending_ = false;
  bool rate_known;
  if (loadsWithoutKinematics(loads_read_kinematics_, ctx_)) {
    // Gravity and its rate from the sines alone: about 35 % fewer instructions per update than the forward
    // kinematics, the world-frame sum and the chain's rates.
    ctx_.q = reference_;
    double sines[kMaxJoints], cosines[kMaxJoints];
    sinCosBatch(reference_.data(), n_, sines, cosines);
    rate_known = loadTorqueAndRateInJointFrames(truth_, load_mask_, ws_, ctx_, cosines, sines, reference_velocity_,
                                                feedforward_rate_);
    feedforward_ = ctx_.load_torque;
  } else {
    staticFeedforward(reference_, feedforward_);
    rate_known = loadTorqueRateAtCurrentPose(truth_, load_mask_, ws_, ctx_, reference_velocity_, feedforward_rate_);
  }
  if (!rate_known) {
    constexpr double kRateStep = 1e-4;  // s
    JointVector ahead;
    staticFeedforward(reference_ + reference_velocity_ * kRateStep, ahead);
    feedforward_rate_ = (ahead - feedforward_) / kRateStep;
  }
}

void FlexibleJointPlant::setToolWrench(const Vector6& wrench) {
  if (!wrench.allFinite()) throw InvalidArgument("plant: tool wrench is not finite");
  ensureFeedforward();  // at the loads of its update
  ctx_.tool_wrench = wrench;
  restart_ = true;  // a step in the load: start the integrator afresh
}

void FlexibleJointPlant::setPayload(double mass, const Eigen::Vector3d& com_in_tool) {
  if (!std::isfinite(mass) || mass < 0.0 || !com_in_tool.allFinite()) {
    throw InvalidArgument("plant: payload mass must be finite and non-negative, its centre finite");
  }
  ensureFeedforward();  // at the loads of its update
  ctx_.payload_mass = mass;
  ctx_.payload_com = com_in_tool;
  restart_ = true;
}

void FlexibleJointPlant::referenceAt(double t, JointVector& position, JointVector& velocity,
                                     JointVector& acceleration) const {
  position.resize(n_);
  velocity.resize(n_);
  acceleration.resize(n_);
  for (int j = 0; j < n_; ++j) {
    const ReferencePoint point = referencePoint(j, t);
    position[j] = point.value;
    velocity[j] = point.velocity;
    acceleration[j] = point.acceleration;
  }
}

// The new extrapolation plus (1 - s) times the old one's offset from it, with s = 10 u^3 - 15 u^4 + 6 u^5 of
// u = (t - t_update) / duration: s, s' and s'' vanish at the update (where the offset's Taylor polynomial
// equals the old reference to second order) and s = 1, s' = s'' = 0 from u = 1 on.
FlexibleJointPlant::ReferencePoint FlexibleJointPlant::referencePoint(int j, double t) const {
  const double dt = t - reference_time_;
  ReferencePoint point;
  point.value = reference_[j] + reference_velocity_[j] * dt + 0.5 * reference_acceleration_[j] * dt * dt;
  point.velocity = reference_velocity_[j] + reference_acceleration_[j] * dt;
  point.acceleration = reference_acceleration_[j];
  point.feedforward = feedforward_[j] + feedforward_rate_[j] * dt;
  point.feedforward_rate = feedforward_rate_[j];
  point.feedforward_blend = 0.0;
  if (blend_duration_ > 0.0 && dt < blend_duration_) {
    const double u = std::max(0.0, dt / blend_duration_);
    const double per_duration = 1.0 / blend_duration_;
    const double weight = 1.0 - u * u * u * (10.0 + u * (-15.0 + 6.0 * u));
    const double weight_rate = -30.0 * u * u * (1.0 - u) * (1.0 - u) * per_duration;
    const double weight_acceleration = -60.0 * u * (1.0 - u) * (1.0 - 2.0 * u) * per_duration * per_duration;
    const double offset =
        blend_offset_[j] + blend_offset_velocity_[j] * dt + 0.5 * blend_offset_acceleration_[j] * dt * dt;
    const double offset_rate = blend_offset_velocity_[j] + blend_offset_acceleration_[j] * dt;
    const double feedforward_offset = feedforward_offset_[j] + feedforward_offset_rate_[j] * dt;
    point.value += weight * offset;
    point.velocity += weight_rate * offset + weight * offset_rate;
    point.acceleration +=
        weight_acceleration * offset + 2.0 * weight_rate * offset_rate + weight * blend_offset_acceleration_[j];
    point.feedforward_blend = weight * feedforward_offset;
    point.feedforward += point.feedforward_blend;
    point.feedforward_rate += weight_rate * feedforward_offset + weight * feedforward_offset_rate_[j];
  }
  return point;
}

void FlexibleJointPlant::computeMotorTorques(double t, const JointVector& p, const JointVector& pd,
                                             const JointVector& integral, JointVector& torque,
                                             JointVector* clamped_excess) const {
  torque.resize(n_);
  if (clamped_excess) clamped_excess->setZero(n_);
  for (int j = 0; j < n_; ++j) {
    if (!options_.control) {
      torque[j] = 0.0;
      continue;
    }
    const DriveParameters& d = drives_[j];
    const double dt = t - reference_time_;
    // Outside a blend (always without smooth_reference) the extrapolation alone, spelled out: this is
    // every right-hand side's path, and referencePoint() computes much more.
    double wanted, wanted_velocity, feedforward_blend = 0.0;
    if (blend_duration_ > 0.0 && dt < blend_duration_) {
      const ReferencePoint reference = referencePoint(j, t);
      wanted = reference.value;
      wanted_velocity = reference.velocity;
      feedforward_blend = reference.feedforward_blend;
    } else {
      wanted = reference_[j] + reference_velocity_[j] * dt + 0.5 * reference_acceleration_[j] * dt * dt;
      wanted_velocity = reference_velocity_[j] + reference_acceleration_[j] * dt;
    }
    // Feed-forward of the static load at the reference and of the friction at the reference velocity,
    // as industrial drives do: the feedback then only corrects what the drive does not know.
    const double friction = d.viscous_friction_nms_per_rad * wanted_velocity +
                            d.coulomb_friction_nm * std::tanh(wanted_velocity / d.coulomb_velocity_scale_rad_per_s);
    // The feed-forward as the new extrapolation plus the blend's part (zero without one), in this order so
    // that a plant without smooth_reference computes what it did before issue 17, bit for bit.
    const double value = d.kp_nm_per_rad * (wanted - p[j]) + d.kd_nms_per_rad * (wanted_velocity - pd[j]) +
                         d.ki_nm_per_rad_s * integral[j] + feedforward_[j] + feedforward_rate_[j] * dt +
                         feedforward_blend + friction;
    const double limit = truth_.robot().joints[j].effort_limit;
    const double clamped = limit > 0.0 ? std::max(-limit, std::min(limit, value)) : value;
    torque[j] = clamped;
    if (clamped_excess) (*clamped_excess)[j] = clamped - value;
  }
}

void FlexibleJointPlant::transmissionError(const JointVector& p, const JointVector& q, JointVector& error) {
  ctx_.q = q;
  ctx_.command = p;
  updateMotorAngles(truth_, ctx_);
  error.setZero(n_);
  addSelectedJointErrors(truth_, error_mask_, ctx_, error);
}

void FlexibleJointPlant::transmissionTorques(const JointVector& p, const JointVector& pd, const JointVector& q,
                                             const JointVector& qd, JointVector& link_torque,
                                             JointVector& motor_reaction) {
  // The gear output turns by p + e(p): the spring stretches by p + e - q and the damper by its rate
  // (I + E) pd - qd with E = de/dp. The motors feel (I + E)^T times the transmitted torque, which keeps
  // the spring conservative and the damper dissipative. E = diag(de_j/dm_j) G from the effects' own
  // slopes (the error of joint j depends on its motor angle m = G p), or by central differences when an
  // effect does not give its slope.
  JointVector error;
  if (error_mask_ != 0 && analytic_slope_) {
    // E = diag(s) G applied without forming it (the rhs's path; the same bits as the matrix form below).
    JointVector motor_slope, output_rate;
    transmissionErrorAndMotorSlopes(p, q, error, motor_slope);  // leaves ctx_ at command p, its motor angles set
    const JointMatrix& gears = truth_.gears().motorFromJoint();
    transmissionOutputRate(motor_slope, gears, pd, output_rate);
    link_torque = stiffness_.cwiseProduct(p + error - q);
    for (int j = 0; j < n_; ++j)
      link_torque[j] += drives_[j].transmission_damping_nms_per_rad * (output_rate[j] - qd[j]);
    transmissionReaction(motor_slope, gears, link_torque, motor_reaction);
    return;
  }
  JointMatrix slope = JointMatrix::Zero(n_, n_);
  if (error_mask_ != 0) {
    transmissionError(p, q, error);
    JointVector shifted = p;
    JointVector ahead, behind;
    constexpr double kStep = 1e-6;  // rad of joint-side motor angle
    for (int k = 0; k < n_; ++k) {
      shifted[k] = p[k] + kStep;
      transmissionError(shifted, q, ahead);
      shifted[k] = p[k] - kStep;
      transmissionError(shifted, q, behind);
      shifted[k] = p[k];
      slope.col(k) = (ahead - behind) / (2.0 * kStep);
    }
  } else {
    transmissionError(p, q, error);
  }
  const JointVector output_rate = pd + slope * pd;
  link_torque = stiffness_.cwiseProduct(p + error - q);
  for (int j = 0; j < n_; ++j) link_torque[j] += drives_[j].transmission_damping_nms_per_rad * (output_rate[j] - qd[j]);
  motor_reaction = link_torque + slope.transpose() * link_torque;
}

void FlexibleJointPlant::transmissionErrorAndMotorSlopes(const JointVector& p, const JointVector& q, JointVector& error,
                                                         JointVector& motor_slope) {
  ctx_.q = q;
  ctx_.command = p;
  updateMotorAngles(truth_, ctx_);
  error.setZero(n_);
  motor_slope.setZero(n_);
  // Effect by effect in index order, as addSelectedJointErrors and addMotorSlopes sum them: the same bits.
  const Robot& robot = truth_.robot();
  for (int i = 0; i < truth_.effectCount(); ++i) {
    if ((error_mask_ >> i & 1) == 0) continue;
    if (const TransmissionErrorEffect* transmission = transmission_effects_[static_cast<std::size_t>(i)]) {
      transmission->addJointErrorAndMotorSlope(ctx_, error, motor_slope);
      continue;
    }
    const Effect& effect = truth_.effect(i);
    effect.addJointError(robot, ctx_, error);
    if (effect.dependsOnCommand()) effect.addMotorSlope(robot, ctx_, motor_slope);
  }
}

// Eigen's column-major matrix-vector kernel sums each row over the columns in order, from zero, and adds
// the sum to the vector it is added to.
void transmissionOutputRate(const JointVector& motor_slope, const JointMatrix& gears, const JointVector& pd,
                            JointVector& output_rate) {
  const Eigen::Index n = pd.size();
  output_rate.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    double sum = 0.0;
    for (Eigen::Index k = 0; k < n; ++k) sum += (motor_slope[i] * gears(i, k)) * pd[k];
    output_rate[i] = pd[i] + sum;
  }
}

// Eigen's row-major kernel (E^T of a column-major E) sums each row in two lanes, even and odd columns, from
// zero, adds the lanes, then the last column of an odd count (SSE2's two doubles per packet).
void transmissionReaction(const JointVector& motor_slope, const JointMatrix& gears, const JointVector& torque,
                          JointVector& reaction) {
  const Eigen::Index n = torque.size();
  const Eigen::Index paired = n - n % 2;
  reaction.resize(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    double even = 0.0, odd = 0.0;
    for (Eigen::Index k = 0; k < paired; k += 2) {
      even += (motor_slope[k] * gears(k, j)) * torque[k];
      odd += (motor_slope[k + 1] * gears(k + 1, j)) * torque[k + 1];
    }
    double sum = even + odd;
    if (paired < n) sum += (motor_slope[n - 1] * gears(n - 1, j)) * torque[n - 1];
    reaction[j] = torque[j] + sum;
  }
}

void FlexibleJointPlant::addMotorSlopes(JointVector& slope) const {
  for (int i = 0; i < truth_.effectCount(); ++i) {
    const Effect& effect = truth_.effect(i);
    if ((error_mask_ >> i & 1) != 0 && effect.dependsOnCommand()) effect.addMotorSlope(truth_.robot(), ctx_, slope);
  }
}

namespace {

// The state y = [q, qd, p, pd, integral] in its parts, as the right-hand side and its Jacobian read it.
struct PlantStateParts {
  PlantStateParts(const double* y, int n) {
    const Eigen::Map<const Eigen::VectorXd> state(y, 5 * n);
    q = state.segment(0, n);
    qd = state.segment(n, n);
    p = state.segment(2 * n, n);
    pd = state.segment(3 * n, n);
    integral = state.segment(4 * n, n);
  }
  JointVector q, qd, p, pd, integral;
};

}  // namespace

void FlexibleJointPlant::linkAcceleration(const JointVector& q, const JointVector& qd, const JointVector& spring_torque,
                                          JointVector& qdd) {
  const Robot& robot = truth_.robot();
  forwardKinematics(robot, ws_.robot, q);
  ctx_.q = q;
  ctx_.load_torque.setZero(n_);
  addNonGravityLoadsAtCurrentPose(truth_, load_mask_, ws_, ctx_);
  const JointVector link_torque = spring_torque - ctx_.load_torque;
  forwardDynamicsAtCurrentPose(robot, ws_.robot, qd, link_torque, qdd);  // at the pose computed above
}

void FlexibleJointPlant::derivative(double t, const double* y, double* ydot) {
  ensureFeedforward();
  const PlantStateParts parts(y, n_);
  const JointVector &q = parts.q, &qd = parts.qd, &p = parts.p, &pd = parts.pd, &integral = parts.integral;

  JointVector spring_torque, motor_reaction;
  transmissionTorques(p, pd, q, qd, spring_torque, motor_reaction);

  JointVector qdd;
  linkAcceleration(q, qd, spring_torque, qdd);

  // Motor side and controller.
  JointVector motor_torque, clamped_excess;
  computeMotorTorques(t, p, pd, integral, motor_torque, &clamped_excess);
  for (int j = 0; j < n_; ++j) {
    const DriveParameters& d = drives_[j];
    const double friction = d.viscous_friction_nms_per_rad * pd[j] +
                            d.coulomb_friction_nm * std::tanh(pd[j] / d.coulomb_velocity_scale_rad_per_s);
    ydot[j] = qd[j];
    ydot[n_ + j] = qdd[j];
    if (options_.motors_locked) {
      ydot[2 * n_ + j] = 0.0;
      ydot[3 * n_ + j] = 0.0;
    } else {
      ydot[2 * n_ + j] = pd[j];
      ydot[3 * n_ + j] = (motor_torque[j] - motor_reaction[j] - friction) / d.motor_inertia_kgm2;
    }
    ydot[4 * n_ + j] = options_.control ? referenceAt(j, t) - p[j] + windup_gain_[j] * clamped_excess[j] : 0.0;
  }
}

// M qdd + c(q, qd) = tau_s - loads(q), c the bias torques without gravity and the loads with it: at fixed
// tau_s, M d qdd = -(d(M qdd + c) + d loads), the first from the tangent passes of inverse dynamics, the second
// from the loads' own rates along each e_j. False (and nothing usable) when a load does not know its rate.
bool FlexibleJointPlant::analyticLinkDerivatives(const JointVector& qd, const JointVector& qdd) {
  JacobianScratch& w = jacobian_scratch_;
  const Robot& robot = truth_.robot();
  w.torque_by_q.resize(n_, n_);
  for (int j = 0; j < n_; ++j) {
    if (!loadTorqueRateAtCurrentPose(truth_, load_mask_, ws_, ctx_, JointVector::Unit(n_, j), w.load_rate))
      return false;
    w.torque_by_q.col(j) = w.load_rate;
  }
  inverseDynamicsDerivativesAtCurrentPose(robot, ws_.robot, qd, qdd, false, w.link_by_q, w.link_by_qd);
  w.torque_by_q += w.link_by_q;
  w.link_by_q.noalias() = -w.inverse_mass * w.torque_by_q;
  w.torque_by_q.noalias() = -w.inverse_mass * w.link_by_qd;
  w.link_by_qd = w.torque_by_q;
  return true;
}

// The same by forward differences of the link dynamics alone at the fixed transmitted torque (2 n forward
// dynamics), as before issue 17; kept to compare against and for loads that do not know their rates.
void FlexibleJointPlant::linkDerivativesByDifferences(const JointVector& q, const JointVector& qd,
                                                      const JointVector& spring_torque, const JointVector& qdd) {
  JacobianScratch& w = jacobian_scratch_;
  // ctx_.load_torque holds the loads at q (linkAcceleration's; the loads' rates leave it alone).
  const Robot& robot = truth_.robot();
  const JointVector link_torque = spring_torque - ctx_.load_torque;
  const double step = std::sqrt(std::numeric_limits<double>::epsilon());
  JointVector shifted = qd;
  for (int k = 0; k < n_; ++k) {  // same pose, same loads: only the bias torques change
    const double h = step * std::max(1.0, std::abs(qd[k]));
    shifted[k] = qd[k] + h;
    forwardDynamicsAtCurrentPose(robot, ws_.robot, shifted, link_torque, w.shifted_qdd);
    shifted[k] = qd[k];
    w.link_by_qd.col(k) = (w.shifted_qdd - qdd) / h;
  }
  shifted = q;
  for (int k = 0; k < n_; ++k) {
    const double h = step * std::max(1.0, std::abs(q[k]));
    shifted[k] = q[k] + h;
    linkAcceleration(shifted, qd, spring_torque, w.shifted_qdd);
    shifted[k] = q[k];
    w.link_by_q.col(k) = (w.shifted_qdd - qdd) / h;
  }
}

// Closed form (the link accelerations' q and qd columns by tangent passes of inverse dynamics) except the
// transmission error's curvature, a central difference of the effects' own slopes.
void FlexibleJointPlant::jacobian(double t, const double* y, double* jacobian) {
  ensureFeedforward();
  if (!analytic_slope_) {
    throw InvalidArgument("plant: no analytic Jacobian: an effect of the transmission error does not give its slope");
  }
  const int n = n_;
  const PlantStateParts parts(y, n);
  const JointVector &q = parts.q, &qd = parts.qd, &p = parts.p, &pd = parts.pd, &integral = parts.integral;
  Eigen::Map<Eigen::MatrixXd> J(jacobian, stateSize(), stateSize());
  J.setZero();
  JacobianScratch& w = jacobian_scratch_;

  // Transmission: tau_s = K (p + e(p) - q) + D (S pd - qd), the motors feel S^T tau_s, S = I + diag(s) G with
  // s the slopes de_j/dm_j at the motor angles m = G p and s' their curvatures.
  JointVector spring_torque, motor_reaction;
  transmissionTorques(p, pd, q, qd, spring_torque, motor_reaction);  // leaves ctx_.motor at G p
  const JointMatrix& gears = truth_.gears().motorFromJoint();
  JointVector slope = JointVector::Zero(n);
  w.curvature.setZero(n);
  if (error_mask_ != 0) {
    addMotorSlopes(slope);
    constexpr double kMotorStep = 1e-6;  // rad of motor angle; every motor at once (e_j depends on m_j only)
    const JointVector motor = ctx_.motor;
    w.ahead.setZero(n);
    w.behind.setZero(n);
    ctx_.motor.array() += kMotorStep;
    addMotorSlopes(w.ahead);
    ctx_.motor.array() = motor.array() - kMotorStep;
    addMotorSlopes(w.behind);
    ctx_.motor = motor;
    w.curvature = (w.ahead - w.behind) / (2.0 * kMotorStep);
  }
  JointVector damping(n);
  for (int j = 0; j < n; ++j) damping[j] = drives_[j].transmission_damping_nms_per_rad;
  JointMatrix output_by_motor = slope.asDiagonal() * gears;  // S
  output_by_motor.diagonal().array() += 1.0;
  const JointVector motor_rate = gears * pd;
  // d tau_s/dp = K S + diag(D s' (G pd)) G, d tau_s/dpd = D S, d tau_s/dq = -K, d tau_s/dqd = -D.
  w.spring_by_motor.noalias() = stiffness_.asDiagonal() * output_by_motor;
  w.spring_by_motor.noalias() += damping.cwiseProduct(w.curvature).cwiseProduct(motor_rate).asDiagonal() * gears;
  // d(S^T tau_s)/dp = S^T d tau_s/dp + G^T diag(s' tau_s) G (S moves with p), and S^T D S for pd.
  w.reaction_by_motor.noalias() = output_by_motor.transpose() * w.spring_by_motor;
  w.reaction_by_motor.noalias() += gears.transpose() * (w.curvature.cwiseProduct(spring_torque).asDiagonal() * gears);
  w.reaction_by_motor_rate.noalias() = output_by_motor.transpose() * (damping.asDiagonal() * output_by_motor);

  // Link side: qdd = M(q)^-1 (tau_s - loads(q) - bias(q, qd)).
  JointVector qdd;
  linkAcceleration(q, qd, spring_torque, qdd);
  w.link_by_q.resize(n, n);
  w.link_by_qd.resize(n, n);
  // Eigen's LLT here (a Jacobian is rare): its solve for a matrix groups the sums unlike the vector solves.
  w.mass_llt.compute(ws_.robot.mass_matrix);
  w.inverse_mass = w.mass_llt.solve(JointMatrix::Identity(n, n));
  if (!options_.analytic_link_derivatives || !analyticLinkDerivatives(qd, qdd)) {
    linkDerivativesByDifferences(q, qd, spring_torque, qdd);
  }
  for (int j = 0; j < n; ++j) J(j, n + j) = 1.0;
  J.block(n, 0, n, n) = w.link_by_q - w.inverse_mass * stiffness_.asDiagonal();
  J.block(n, n, n, n) = w.link_by_qd - w.inverse_mass * damping.asDiagonal();
  J.block(n, 2 * n, n, n).noalias() = w.inverse_mass * w.spring_by_motor;
  J.block(n, 3 * n, n, n).noalias() = w.inverse_mass * (damping.asDiagonal() * output_by_motor);

  // Motor side: B pdd = tau_m - S^T tau_s - friction(pd); tau_m = kp (r - p) + kd (rd - pd) + ki z + ..., whose
  // slopes vanish while the drive saturates, when the anti-windup takes them over in the integral's rate.
  JointVector motor_torque, clamped_excess;
  computeMotorTorques(t, p, pd, integral, motor_torque, &clamped_excess);
  for (int j = 0; j < n; ++j) {
    const DriveParameters& d = drives_[j];
    const bool free = options_.control && clamped_excess[j] == 0.0;
    const bool saturated = options_.control && clamped_excess[j] != 0.0;
    if (!options_.motors_locked) {
      const double per_inertia = 1.0 / d.motor_inertia_kgm2;
      const double scale = d.coulomb_velocity_scale_rad_per_s;
      const double coulomb = std::tanh(pd[j] / scale);
      const double friction_slope =
          d.viscous_friction_nms_per_rad + d.coulomb_friction_nm * (1.0 - coulomb * coulomb) / scale;
      J(2 * n + j, 3 * n + j) = 1.0;
      for (int k = 0; k < n; ++k) {
        J(3 * n + j, k) = output_by_motor(k, j) * stiffness_[k] * per_inertia;  // -d(S^T tau_s)/dq
        J(3 * n + j, n + k) = output_by_motor(k, j) * damping[k] * per_inertia;
        J(3 * n + j, 2 * n + k) = -w.reaction_by_motor(j, k) * per_inertia;
        J(3 * n + j, 3 * n + k) = -w.reaction_by_motor_rate(j, k) * per_inertia;
      }
      J(3 * n + j, 3 * n + j) -= friction_slope * per_inertia;
      if (free) {
        J(3 * n + j, 2 * n + j) -= d.kp_nm_per_rad * per_inertia;
        J(3 * n + j, 3 * n + j) -= d.kd_nms_per_rad * per_inertia;
        J(3 * n + j, 4 * n + j) = d.ki_nm_per_rad_s * per_inertia;
      }
    }
    if (options_.control) {  // dz/dt = r - p + (clamped - unclamped torque) / (ki Tt)
      J(4 * n + j, 2 * n + j) = -1.0;
      if (saturated) {
        J(4 * n + j, 2 * n + j) += windup_gain_[j] * d.kp_nm_per_rad;
        J(4 * n + j, 3 * n + j) = windup_gain_[j] * d.kd_nms_per_rad;
        J(4 * n + j, 4 * n + j) = -windup_gain_[j] * d.ki_nm_per_rad_s;
      }
    }
  }
  if (!J.allFinite()) throw SolverError("plant: the Jacobian has an entry that is not finite");
}

void FlexibleJointPlant::solveNewtonSystem(double t, const double* y, double gamma, const double* b, double* x) {
  const int size = stateSize();
  std::vector<double> matrix(static_cast<std::size_t>(size) * size);
  jacobian(t, y, matrix.data());
  StructuredLinearSolver solver(n_);
  if (solver.setup(matrix.data(), gamma) != SUNLS_SUCCESS) throw SolverError("plant: the Newton system is singular");
  solver.solve(x, b);
}

namespace {

int plantRightHandSide(realtype t, N_Vector y, N_Vector ydot, void* user_data) {
  auto* plant = static_cast<FlexibleJointPlant*>(user_data);
  try {
    plant->derivative(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
  } catch (const std::exception&) {
    return 1;  // recoverable: CVODE retries with a smaller step, and reports if it cannot
  }
  const double* values = N_VGetArrayPointer(ydot);
  for (int i = 0; i < plant->stateSize(); ++i) {
    if (!std::isfinite(values[i])) return 1;
  }
  return 0;
}

int plantJacobian(realtype t, N_Vector y, N_Vector, SUNMatrix jacobian, void* user_data, N_Vector, N_Vector, N_Vector) {
  auto* plant = static_cast<FlexibleJointPlant*>(user_data);
  double* values = SUNDenseMatrix_Data(jacobian);
  try {
    plant->jacobian(t, N_VGetArrayPointer(y), values);  // throws on an entry that is not finite
  } catch (const std::exception&) {
    return 1;  // recoverable, as for the right-hand side: CVODE retries smaller and reports if it cannot
  }
  return 0;
}

// CVODE's linear-system function for the structured solver: the plant's Jacobian when CVODE asks for a
// fresh one (jacobian_ok false), otherwise the saved one, and gamma, handed to the solver's setup.
int plantLinearSystem(realtype t, N_Vector y, N_Vector, SUNMatrix, booleantype jacobian_ok,
                      booleantype* jacobian_current, realtype gamma, void* user_data, N_Vector, N_Vector, N_Vector) {
  auto* plant = static_cast<FlexibleJointPlant*>(user_data);
  return plant->prepareNewtonSystem(t, N_VGetArrayPointer(y), jacobian_ok != SUNFALSE, gamma, jacobian_current);
}

}  // namespace

int FlexibleJointPlant::prepareNewtonSystem(double t, const double* y, bool jacobian_ok, double gamma,
                                            int* jacobian_current) {
  Solver& s = *solver_;
  *jacobian_current = SUNFALSE;
  if (!jacobian_ok || s.jacobian_evaluations == 0) {
    try {
      jacobian(t, y, s.saved_jacobian.data());  // throws on an entry that is not finite
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

PlantStatistics FlexibleJointPlant::statistics() const {
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
  PlantStatistics counts = statistics_;
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

void FlexibleJointPlant::advance(double end_time) {
  if (!std::isfinite(end_time) || !(end_time > time_)) {
    throw InvalidArgument("plant: advance to t = " + std::to_string(end_time) +
                          " s, which is not after the current t = " + std::to_string(time_) + " s");
  }
  if (!tripped_.empty()) {
    throw PlantLimitError(tripped_ + "; the run stopped there: reset the plant or restore a saved state to go on");
  }
  Solver& s = *solver_;
  if (restart_) {
    s.before_restart = statistics();          // CVodeReInit zeroes CVODE's counts
    if (ahead_) N_VScale(1.0, s.y_now, s.y);  // from the state at time_, not from CVODE's last step ahead of it
    ahead_ = false;
    check(CVodeReInit(s.cvode, time_, s.y), "CVodeReInit");
    restart_ = false;
  }
  // Stepping past the end pays only for advances shorter than CVODE's step, and not for those of half the
  // horizon or more (CVODE's step would span at most about two; at fmu_bench's 10 ms updates with a 10 ms
  // horizon stepping past took 3.98 CVODE steps per update against 2.84 stopping at each). Those end on
  // their time (from where CVODE is, if it is ahead), as without the option: updates of exactly half the
  // horizon too, however their times round (CVODE's own time roundoff, 100 eps (|t| + h), is allowed for).
  // CVODE reports a step it cut to end on the last advance's end as (end - t)(1 - 4 eps) (SUNDIALS 6), so an
  // advance as long counts as shorter than the step, or updates a binary fraction of a second apart
  // (1/1024 s) would never be stepped past. Allowing the whole time roundoff there instead lets the plant
  // step past where CVODE's step is just the update's length, as in a step response's transient, which then
  // costs more steps than stopping (887 against 837 in PlantStepPast.AReferenceThatNeverChanges...): at
  // decimal update times whether CVODE's first step past begins still depends on how the times round.
  bool past = false;
  realtype cvode_time = time_;
  if (options_.step_past_updates_s > 0.0) {
    realtype planned = 0.0;  // 0 before the first step after a (re)start
    if (CVodeGetCurrentTime(s.cvode, &cvode_time) != CV_SUCCESS) cvode_time = time_;
    if (CVodeGetCurrentStep(s.cvode, &planned) != CV_SUCCESS) planned = 0.0;
    const double length = end_time - time_;
    const double horizon = options_.step_past_updates_s;
    const double roundoff = 100.0 * std::numeric_limits<double>::epsilon() * (std::fabs(end_time) + horizon);
    past = cvode_time >= end_time || (length < 0.5 * horizon - roundoff &&
                                      length <= planned * (1.0 + 16.0 * std::numeric_limits<double>::epsilon()));
  }
  if (!past) check(CVodeSetStopTime(s.cvode, end_time), "CVodeSetStopTime");
  // The work budget of this advance: a floor for the start-up transients plus a rate per simulated second
  // far above what the plant needs (about 800 steps per second on the paper's spiral), so that a plant
  // that cannot be integrated fails within seconds instead of running for minutes.
  const double budget = std::min(static_cast<double>(options_.max_steps_per_advance),
                                 kStepBudgetFloor + kStepBudgetPerSecond * (end_time - time_));
  s.last_error.clear();
  realtype reached = time_;
  int flag = 0;
  if (past) {
    flag = integratePast(end_time, cvode_time, static_cast<long>(budget), reached);
  } else if (options_.even_steps) {
    flag = integrateEvenly(end_time, static_cast<long>(budget), reached);  // counts the budget itself
  } else {
    check(CVodeSetMaxNumSteps(s.cvode, static_cast<long>(budget)), "CVodeSetMaxNumSteps");
    flag = CVode(s.cvode, end_time, s.y, &reached, CV_NORMAL);
  }
  if (flag < 0) {
    // Keep the last good state: CVODE leaves y at the last successful step.
    time_ = reached;
    restart_ = true;
    ahead_ = false;
    if (flag == CV_TOO_MUCH_WORK) {
      throw SolverError("plant: the integration spent its work budget (" + std::to_string(static_cast<long>(budget)) +
                        " CVODE steps, CV_TOO_MUCH_WORK) between t = " + std::to_string(reached) + " s and " +
                        std::to_string(end_time) +
                        " s: the plant is too stiff for its parameters (look at the drive gains and the joint "
                        "stiffnesses) or the motion leaves what it can follow" +
                        (s.last_error.empty() ? std::string() : "; CVODE: " + s.last_error));
    }
    throw SolverError("plant: CVODE failed between t = " + std::to_string(reached) + " s and " +
                      std::to_string(end_time) + " s: " + (s.last_error.empty() ? flagName(flag) : s.last_error));
  }
  if (past) {
    ahead_ = true;  // integratePast left the state at end_time in y_now
  } else {
    ahead_ = false;  // stopped on end_time: y is the state there
  }
  time_ = end_time;
  checkWatchdog();
}

// PlantOptions::step_past_updates_s: CVODE's own steps until one ends at or beyond end_time, in one CV_NORMAL
// call; the stop time only bounds how far past end_time they may go. Steps already beyond end_time (an
// earlier advance's) are not taken again. The next advance steps past its end again only if CVODE's report
// of the step it plans (CVodeGetCurrentStep) is longer than the advance. After a CV_ONE_STEP call CVODE
// reports, and takes, its next step cut to what is left before the stop time (SUNDIALS 6, cvode.c): here at
// most step_past_updates_s past this advance's end and often much less, so the plant fell back to stopping
// at updates that CVODE could have stepped over. After a CV_NORMAL call it reports the step it plans.
// fmu_bench (BM_DirectSpiral, step_past_updates 10 ms): 0.21 -> 0.11 CVODE steps per update at 1 ms
// updates. cvode_time: CVODE's time, as advance read it. The work budget is CVODE's count of steps in the call.
int FlexibleJointPlant::integratePast(double end_time, double cvode_time, long budget, double& reached) {
  Solver& s = *solver_;
  reached = cvode_time;
  // CVODE's last step ends at or beyond end_time and began before it: its interpolant covers end_time.
  if (cvode_time >= end_time) {
    check(CVodeGetDky(s.cvode, end_time, 0, s.y_now), "CVodeGetDky");
    return CV_SUCCESS;
  }
  check(CVodeSetStopTime(s.cvode, end_time + options_.step_past_updates_s), "CVodeSetStopTime");
  check(CVodeSetMaxNumSteps(s.cvode, budget), "CVodeSetMaxNumSteps");
  realtype output_time = end_time;
  // The output at end_time is that interpolant's value there, written straight into y_now.
  const int flag = CVode(s.cvode, end_time, s.y_now, &output_time, CV_NORMAL);
  realtype at = reached;
  if (CVodeGetCurrentTime(s.cvode, &at) == CV_SUCCESS) reached = at;
  if (flag < 0) N_VScale(1.0, s.y_now, s.y);  // CVODE's state at its last good step, where advance restarts
  return flag;
}

const double* FlexibleJointPlant::now() const { return ahead_ ? solver_->y_now_data : solver_->y_data; }

// PlantOptions::even_steps: one CVODE step per call. When what is left of the advance is more than CVODE's
// planned step but less than two, the stop time is set at its middle, so that the advance ends in two equal
// steps instead of the planned one and a sliver (a cut step in front of the end would make CVODE keep its
// size and hold back its growth, so the stop time is moved only there). The count of calls keeps the
// advance's work budget.
int FlexibleJointPlant::integrateEvenly(double end_time, long budget, double& reached) {
  Solver& s = *solver_;
  realtype at = time_;
  if (ahead_ && CVodeGetCurrentTime(s.cvode, &at) != CV_SUCCESS) at = time_;  // CVODE stepped past time_ before
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

void FlexibleJointPlant::setWatchdog(double tracking_envelope_rad, double joint_limit_margin_rad) {
  if (!std::isfinite(tracking_envelope_rad) || !(tracking_envelope_rad > 0.0)) {
    throw InvalidArgument("plant: tracking_envelope_rad must be finite and positive; it is " +
                          std::to_string(tracking_envelope_rad));
  }
  if (!std::isfinite(joint_limit_margin_rad) || joint_limit_margin_rad < 0.0) {
    throw InvalidArgument("plant: joint_limit_margin_rad must be finite and not negative; it is " +
                          std::to_string(joint_limit_margin_rad));
  }
  options_.tracking_envelope_rad = tracking_envelope_rad;
  options_.joint_limit_margin_rad = joint_limit_margin_rad;
}

void FlexibleJointPlant::checkWatchdog() {
  const Robot& robot = truth_.robot();
  const double* y = now();
  const double margin = options_.joint_limit_margin_rad;
  // The two limits, each written once for the test below and for the messages.
  const auto beyond_limits = [&](int j) {  // continuous joints: +-inf
    const Joint& joint = robot.joints[static_cast<std::size_t>(j)];
    return (y[j] > joint.upper + margin) | (y[j] < joint.lower - margin);
  };
  const auto following_error = [&](int j) { return referenceAt(j, time_) - y[2 * n_ + j]; };
  const auto beyond_envelope = [&](int j) { return std::abs(following_error(j)) > options_.tracking_envelope_rad; };
  // Every joint first, without a branch per joint; a message only when one is crossed (a NaN crosses none).
  if (tripped_.empty()) {
    bool beyond = false;
    for (int j = 0; j < n_; ++j) beyond |= beyond_limits(j);
    for (int j = 0; j < n_ && options_.control; ++j) beyond |= beyond_envelope(j);
    if (!beyond) return;
  }
  char text[400];
  for (int j = 0; j < n_ && tripped_.empty(); ++j) {
    if (!beyond_limits(j)) continue;
    const Joint& joint = robot.joints[static_cast<std::size_t>(j)];
    std::snprintf(text, sizeof text,
                  "plant: at t = %.9g s link %s is at %.6g rad, beyond its joint limits [%.6g, %.6g] rad by more "
                  "than the %.3g rad margin",
                  time_, joint.name.c_str(), y[j], joint.lower, joint.upper, margin);
    tripped_ = text;
  }
  for (int j = 0; j < n_ && tripped_.empty() && options_.control; ++j) {
    if (!beyond_envelope(j)) continue;
    std::snprintf(text, sizeof text,
                  "plant: at t = %.9g s the drive of %s has a following error of %.6g rad (reference %.6g, motor "
                  "%.6g), beyond its tracking envelope of %.3g rad: the drive cannot follow its reference",
                  time_, robot.joints[static_cast<std::size_t>(j)].name.c_str(), following_error(j),
                  referenceAt(j, time_), y[2 * n_ + j], options_.tracking_envelope_rad);
    tripped_ = text;
  }
  if (!tripped_.empty()) throw PlantLimitError(tripped_);
}

JointVector FlexibleJointPlant::linkPositions() const { return Eigen::Map<const Eigen::VectorXd>(now(), n_); }
JointVector FlexibleJointPlant::linkVelocities() const { return Eigen::Map<const Eigen::VectorXd>(now() + n_, n_); }
JointVector FlexibleJointPlant::motorPositions() const { return Eigen::Map<const Eigen::VectorXd>(now() + 2 * n_, n_); }
JointVector FlexibleJointPlant::motorVelocities() const {
  return Eigen::Map<const Eigen::VectorXd>(now() + 3 * n_, n_);
}

JointVector FlexibleJointPlant::motorTorques() {
  ensureFeedforward();
  const double* y = now();
  const Eigen::Map<const Eigen::VectorXd> state(y, stateSize());
  JointVector torque;
  computeMotorTorques(time_, state.segment(2 * n_, n_), state.segment(3 * n_, n_), state.segment(4 * n_, n_), torque);
  return torque;
}

double FlexibleJointPlant::mechanicalEnergy() {
  const Robot& robot = truth_.robot();
  const JointVector q = linkPositions();
  const JointVector qd = linkVelocities();
  const JointVector p = motorPositions();
  const JointVector pd = motorVelocities();
  double energy = kineticEnergy(robot, ws_.robot, q, qd) + potentialEnergy(robot, ws_.robot, q);
  for (int j = 0; j < n_; ++j) energy += 0.5 * drives_[j].motor_inertia_kgm2 * pd[j] * pd[j];
  JointVector error;
  transmissionError(p, q, error);
  const JointVector stretch = p + error - q;
  energy += 0.5 * stretch.dot(stiffness_.cwiseProduct(stretch));
  for (int i = 0; i < truth_.effectCount(); ++i) {
    if (const auto* spring = dynamic_cast<const SpringBalancerEffect*>(&truth_.effect(i))) {
      energy += spring->potentialEnergy(q[spring->joint()]);
    }
  }
  if (ctx_.payload_mass != 0.0) {
    forwardKinematics(robot, ws_.robot, q);
    energy -= ctx_.payload_mass * robot.gravity.dot(ws_.robot.tool_pose * ctx_.payload_com);
  }
  return energy;
}

const double* FlexibleJointPlant::state() const { return now(); }

PlantState FlexibleJointPlant::saveState() {
  ensureFeedforward();
  PlantState state;
  state.time = time_;
  const double* y = now();
  state.y.assign(y, y + stateSize());
  state.reference = reference_;
  state.reference_velocity = reference_velocity_;
  state.reference_acceleration = reference_acceleration_;
  state.feedforward = feedforward_;
  state.feedforward_rate = feedforward_rate_;
  state.reference_time = reference_time_;
  state.blend_offset = blend_offset_;
  state.blend_offset_velocity = blend_offset_velocity_;
  state.blend_offset_acceleration = blend_offset_acceleration_;
  state.feedforward_offset = feedforward_offset_;
  state.feedforward_offset_rate = feedforward_offset_rate_;
  state.blend_duration = blend_duration_;
  state.tool_wrench = ctx_.tool_wrench;
  state.payload_mass = ctx_.payload_mass;
  state.payload_com = ctx_.payload_com;
  restart_ = true;  // continuing from here must match continuing from a restored copy, bit for bit
  return state;
}

void FlexibleJointPlant::restoreState(const PlantState& state) {
  if (static_cast<int>(state.y.size()) != stateSize() || state.reference.size() != n_ ||
      state.reference_velocity.size() != n_ || state.reference_acceleration.size() != n_ ||
      state.feedforward.size() != n_ || state.feedforward_rate.size() != n_) {
    throw InvalidArgument("plant: the saved state is for a plant of another size");
  }
  // A state without a blend may leave its parts empty (the C API's snapshots do: their plants never blend).
  const JointVector* blend_parts[] = {&state.blend_offset, &state.blend_offset_velocity,
                                      &state.blend_offset_acceleration, &state.feedforward_offset,
                                      &state.feedforward_offset_rate};
  const bool without_blend = state.blend_duration == 0.0;
  for (const JointVector* part : blend_parts) {
    if (part->size() != n_ && !(without_blend && part->size() == 0)) {
      throw InvalidArgument("plant: the saved state's reference blend is for a plant of another size");
    }
    if (!part->allFinite()) throw InvalidArgument("plant: the saved state's reference blend is not finite");
  }
  for (double v : state.y) {
    if (!std::isfinite(v)) throw InvalidArgument("plant: the saved state holds a value that is not finite");
  }
  if (!std::isfinite(state.time)) throw InvalidArgument("plant: the saved state's time is not finite");
  if (!std::isfinite(state.blend_duration) || state.blend_duration < 0.0) {
    throw InvalidArgument("plant: the saved state's blend duration is not finite and non-negative");
  }
  time_ = state.time;
  ahead_ = false;
  std::copy(state.y.begin(), state.y.end(), N_VGetArrayPointer(solver_->y));
  reference_ = state.reference;
  reference_velocity_ = state.reference_velocity;
  reference_acceleration_ = state.reference_acceleration;
  feedforward_ = state.feedforward;
  feedforward_rate_ = state.feedforward_rate;
  feedforward_pending_ = false;
  reference_time_ = state.reference_time;
  JointVector* blend_targets[] = {&blend_offset_, &blend_offset_velocity_, &blend_offset_acceleration_,
                                  &feedforward_offset_, &feedforward_offset_rate_};
  // Without a blend the offsets are never read, and are kept zero (setReference relies on it).
  for (int i = 0; i < 5; ++i) {
    if (!without_blend) {
      *blend_targets[i] = *blend_parts[i];
    } else {
      blend_targets[i]->setZero(n_);
    }
  }
  blend_duration_ = state.blend_duration;
  ctx_.tool_wrench = state.tool_wrench;
  ctx_.payload_mass = state.payload_mass;
  ctx_.payload_com = state.payload_com;
  restart_ = true;
  tripped_.clear();
}

}  // namespace jointcomp
