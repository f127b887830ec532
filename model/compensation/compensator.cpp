#include "model/compensation/compensator.hpp"

#include <cmath>
#include <cstdio>

#include "model/common/errors.hpp"

namespace jointcomp {

Compensator::Compensator(const JointErrorModel& model, EffectMask mask, FixedPointOptions options)
    : model_(model), mask_(mask), options_(options), iterate_(false), ws_(model.robot()) {
  if (!(options_.tolerance > 0.0) || options_.max_iterations < 1) {
    throw InvalidArgument("compensator: tolerance must be positive and max_iterations at least 1");
  }
  for (int i = 0; i < model.effectCount(); ++i) {
    if (!((mask >> i) & 1U) || model.effect(i).role() != EffectRole::JointError) continue;
    if (!model.effect(i).dependsOnCommand()) {
      fixed_effects_.push_back(i);
      continue;
    }
    iterate_ = true;
    const Effect& effect = model.effect(i);
    command_effects_.push_back(i);
    first_anchor_.push_back(anchors_.size());
    anchors_.resize(anchors_.size() + effect.continuationSize());
    derivatives_known_ = derivatives_known_ && effect.knowsMotorDerivatives();
  }
  loads_read_kinematics_ = loadsReadKinematics(model, mask);
  bool active[kMaxJoints] = {};
  for (const int i : command_effects_) model.effect(i).markCommandJoints(model.robot().dof(), active);
  for (int j = 0; j < model.robot().dof(); ++j) {
    if (active[j]) active_joints_[active_count_++] = j;
  }
  // G's nonzero entries row by row (the diagonal and the few couplings of a 6 x 6 matrix).
  const JointMatrix& g = model.gears().motorFromJoint();
  gear_row_start_[0] = 0;
  for (Eigen::Index i = 0; i < g.rows(); ++i) {
    for (Eigen::Index j = 0; j < g.cols(); ++j) {
      if (g(i, j) == 0.0) continue;
      gear_columns_[gear_entry_count_] = static_cast<int>(j);
      gear_values_[gear_entry_count_] = g(i, j);
      ++gear_entry_count_;
    }
    gear_row_start_[i + 1] = gear_entry_count_;
    gear_diagonal_[i] = g(i, i);
    const int entries = gear_row_start_[i + 1] - gear_row_start_[i];
    if (entries > 1 || (entries == 1 && gear_columns_[gear_row_start_[i]] != i)) {
      coupled_rows_[coupled_row_count_++] = static_cast<int>(i);
    }
  }
  // Sized once: iterate writes and reads only the active joints' entries, and only for a cold start's first step.
  second_.setZero(g.rows());
  third_.setZero(g.rows());
}

// The sums of GearTrain::motorAngles, column by column from 0.0, without the zero terms (which add nothing
// but +-0) and without Eigen's general matrix-vector dispatch, which costs more than the product. A row
// with its diagonal term alone is 0.0 + that term, all rows in one pass the compiler vectorises; the few
// coupled rows are then summed again in full, so every row has the same bits as the full sum.
void Compensator::motorAngles(const JointVector& command, JointVector& motor) const {
  const Eigen::Index n = command.size();
  motor.resize(n);
  const double* in = command.data();
  double* out = motor.data();
  for (Eigen::Index i = 0; i < n; ++i) out[i] = 0.0 + gear_diagonal_[i] * in[i];
  for (int r = 0; r < coupled_row_count_; ++r) {
    const int i = coupled_rows_[r];
    double sum = 0.0;  // in a register: no store-to-load chain through motor
    for (int e = gear_row_start_[i]; e < gear_row_start_[i + 1]; ++e) sum += gear_values_[e] * in[gear_columns_[e]];
    out[i] = sum;
  }
}

namespace {
// Newton steps only where the plain fixed point contracts, |d(error)/d(command)| <= this: there the
// reference is unique and Newton only gets there sooner. Where the error turns faster than the command
// (a wild transmission error), the plain step's divergence is reported as before, not one of the many
// commands that would put the link there.
constexpr double kLargestNewtonSlope = 0.5;
}  // namespace

void Compensator::prepare(JointContext& ctx, bool along_path) {
  const Robot& robot = model_.robot();
  checkJointVector(robot, ctx.q, "planned q");
  // compensate() takes the plain sines (sinCos's bits, and no anchors to store); compensateFrom() starts the
  // anchors with its first call.
  if (loadsWithoutKinematics(loads_read_kinematics_, ctx)) {
    // Gravity alone needs no poses: about 40 % fewer instructions than the forward kinematics and their sum.
    double cosines[kMaxJoints], sines[kMaxJoints];
    if (along_path) {
      for (int i = 0; i < robot.dof(); ++i) {
        sinCosNear(ctx.q[i], joint_anchors_set_, joint_anchors_[static_cast<std::size_t>(i)], sines[i], cosines[i]);
      }
      joint_anchors_set_ = true;
    } else {
      sinCosBatch(ctx.q.data(), robot.dof(), sines, cosines);
    }
    loadTorqueInJointFrames(model_, mask_, ws_, ctx, cosines, sines);
  } else {
    if (along_path) {
      forwardKinematicsNear(robot, ws_.robot, ctx.q, joint_anchors_, joint_anchors_set_);
      joint_anchors_set_ = true;
    } else {
      forwardKinematics(robot, ws_.robot, ctx.q);
    }
    loadTorqueAtCurrentPose(model_, mask_, ws_, ctx);
  }
  // Errors that do not read the command (compliance at ctx.q's load) are the same at every iteration.
  fixed_dq_.setZero(ctx.q.size());
  for (const int i : fixed_effects_) model_.effect(i).addJointError(robot, ctx, fixed_dq_);
}

FixedPointReport Compensator::compensate(JointContext& ctx, JointVector& reference) {
  prepare(ctx, false);
  ctx.command.resize(ctx.q.size());
  for (Eigen::Index j = 0; j < ctx.q.size(); ++j) ctx.command[j] = ctx.q[j] - fixed_dq_[j];
  anchors_set_ = true;
  return iterate(ctx, reference, false, true);
}

FixedPointReport Compensator::compensateFrom(JointContext& ctx, const JointVector& correction_guess,
                                             JointVector& reference) {
  prepare(ctx, true);
  checkJointVector(model_.robot(), correction_guess, "correction guess");
  const bool continue_anchors = anchors_set_;
  ctx.command.resize(ctx.q.size());
  // Without command-dependent errors the answer is closed: the guess has nothing to add; nor has it for a
  // joint that does not iterate.
  for (Eigen::Index j = 0; j < ctx.q.size(); ++j) ctx.command[j] = ctx.q[j] - fixed_dq_[j];
  for (int a = 0; a < active_count_; ++a) {
    const int j = active_joints_[a];
    ctx.command[j] = ctx.q[j] - correction_guess[j];
  }
  anchors_set_ = true;
  return iterate(ctx, reference, continue_anchors, false);
}

bool Compensator::evaluateCommandEffects(const JointContext& ctx, bool reuse_anchors, bool higher_order) {
  const Robot& robot = model_.robot();
  const int* active = active_joints_.data();
  if (higher_order) {
    for (int a = 0; a < active_count_; ++a) second_[active[a]] = third_[active[a]] = 0.0;
  }
  bool slopes_known = true;
  for (std::size_t k = 0; k < command_effects_.size(); ++k) {
    const Effect& effect = model_.effect(command_effects_[k]);
    SinCosAnchor* anchors = anchors_.data() + first_anchor_[k];
    if (higher_order) {
      effect.continueJointErrorAndMotorDerivatives(robot, ctx, anchors, reuse_anchors, dq_, slope_, second_, third_);
    } else {
      slopes_known =
          effect.continueJointErrorAndMotorSlope(robot, ctx, anchors, reuse_anchors, dq_, slope_) && slopes_known;
    }
  }
  return slopes_known;
}

double Compensator::startAtFixedErrors(const JointContext& ctx, JointVector& reference) const {
  double fixed_check = 0.0;  // x * 0 is 0 for a finite x and not a number otherwise
  for (Eigen::Index j = 0; j < ctx.q.size(); ++j) {
    reference[j] = ctx.q[j] - fixed_dq_[j];
    fixed_check += reference[j] * 0.0;
  }
  return fixed_check;
}

void Compensator::activeMotorAngles(JointContext& ctx) const {
  // Each row's nonzero terms summed from 0.0 as motorAngles sums them, so the same bits.
  for (int a = 0; a < active_count_; ++a) {
    const int i = active_joints_[a];
    double sum = 0.0;
    for (int e = gear_row_start_[i]; e < gear_row_start_[i + 1]; ++e) {
      sum += gear_values_[e] * ctx.command[gear_columns_[e]];
    }
    ctx.motor[i] = sum;
  }
}

double Compensator::plainStep(const JointContext& ctx, JointVector& reference, bool& finite) const {
  const int* active = active_joints_.data();
  // Their sum is finite when every change is (without a branch per joint); only when it is not are the
  // changes searched for the first that is not (a finite sum's overflow is no such change).
  double residual = 0.0, change_sum = 0.0;
  for (int a = 0; a < active_count_; ++a) {
    const int j = active[a];
    const double next = ctx.q[j] - dq_[j];
    const double change = std::abs(next - ctx.command[j]);
    residual = std::max(residual, change);
    change_sum += change;
    reference[j] = next;
  }
  finite = true;
  for (int a = 0; a < active_count_ && !std::isfinite(change_sum); ++a) {
    const int j = active[a];
    const double change = std::abs(reference[j] - ctx.command[j]);
    if (!std::isfinite(change)) {
      finite = false;
      residual = change;
      break;
    }
  }
  return residual;
}

void Compensator::higherOrderStep(JointContext& ctx, const JointVector& reference) const {
  // The Newton step and one step more, on the cubic Taylor model of the error about the command, from the
  // Newton step: the command then misses the fixed point by the model's fourth-order remainder instead of
  // Newton's second-order term. On the RX170's spiral the first step lands within about 1e-14 rad instead
  // of 2e-9, and a lone point meets the 1e-12 tolerance at its second evaluation of the error, not its
  // third.
  for (int a = 0; a < active_count_; ++a) {
    const int j = active_joints_[a];
    const double gear = gear_diagonal_[j];
    const double error_per_command = slope_[j] * gear;
    const double derivative = 1.0 + error_per_command;
    const double newton = (reference[j] - ctx.command[j]) / derivative;
    const double curvature = second_[j] * gear * gear, third_order = third_[j] * gear * gear * gear;
    const double model = newton * newton * (0.5 * curvature + newton * third_order * (1.0 / 6.0));
    const double model_slope = derivative + newton * (curvature + 0.5 * newton * third_order);
    double correction = -model / model_slope;
    if (!(std::abs(correction) <= 0.5 * std::abs(newton))) correction = 0.0;  // beyond the model's reach
    // (a slope beyond kLargestNewtonSlope, or not a number: the plain step, as newtonStep)
    ctx.command[j] +=
        std::abs(error_per_command) <= kLargestNewtonSlope ? newton + correction : reference[j] - ctx.command[j];
  }
}

void Compensator::newtonStep(JointContext& ctx, const JointVector& reference, bool slopes_known) const {
  for (int a = 0; a < active_count_; ++a) {
    const int j = active_joints_[a];
    const double error_per_command = slopes_known ? slope_[j] * gear_diagonal_[j] : 0.0;
    const double step = reference[j] - ctx.command[j];
    // (not a number fails the test: the plain step)
    ctx.command[j] += std::abs(error_per_command) <= kLargestNewtonSlope ? step / (1.0 + error_per_command) : step;
  }
}

FixedPointReport Compensator::iterate(JointContext& ctx, JointVector& reference, bool continue_anchors,
                                      bool cold_start) {
  const Eigen::Index n = ctx.q.size();
  dq_.resize(n);
  slope_.resize(n);
  reference.resize(n);
  FixedPointReport report;
  // A joint that does not iterate is at its fixed point (its command is Q_theo less its fixed errors, the
  // map's image of any command): the steps below visit the active joints only.
  const double fixed_check = startAtFixedErrors(ctx, reference);
  // (A command-independent error that is not finite has no fixed point: no iteration, not converged.)
  report.iterations = 1;
  report.residual = fixed_check;
  ctx.motor.resize(n);
  for (; fixed_check == 0.0 && report.iterations <= options_.max_iterations; ++report.iterations) {
    // The motors the errors read, those of the active joints (all motors once the iteration ends).
    activeMotorAngles(ctx);
    // The first step from a cold start is long (the whole command-dependent error, 1e-4 rad on the RX170): for
    // it the error's second and third derivatives too, which harmonics give at little cost (the
    // higher-order step). A later step, or the first from a near guess, is short enough for Newton.
    const bool higher_order = cold_start && report.iterations == 1 && derivatives_known_;
    for (int a = 0; a < active_count_; ++a) {
      const int j = active_joints_[a];
      dq_[j] = fixed_dq_[j];
      slope_[j] = 0.0;
    }
    // The continuations' sines near their anchors: later iterates are within a small angle of the first, and
    // along a path (continue_anchors) the first is within one of the previous point's.
    const bool slopes_known = evaluateCommandEffects(ctx, continue_anchors || report.iterations > 1, higher_order);
    // The stopping test of the plain fixed point: how far its map Q_theo - dQ(command) moves the command.
    bool finite = true;
    report.residual = plainStep(ctx, reference, finite);
    if (!iterate_ || report.residual <= options_.tolerance) {
      report.converged = finite;
      break;
    }
    if (!finite) break;
    // Newton on each joint: the error of joint j moves with its command by slope_j * G_jj (through its own
    // motor; a coupled motor's other terms are left to the iteration, which they slow only by their size).
    if (higher_order) {
      higherOrderStep(ctx, reference);
    } else {
      newtonStep(ctx, reference, slopes_known);
    }
  }
  report.iterations = std::min(report.iterations, options_.max_iterations);
  for (Eigen::Index j = 0; j < n; ++j) ctx.command[j] = reference[j];  // element-wise: no store-forwarding stall
  motorAngles(ctx.command, ctx.motor);
  if (report.converged) requireWithinLimits(model_.robot(), reference);
  return report;
}

void requireWithinLimits(const Robot& robot, const JointVector& reference) {
  for (int j = 0; j < reference.size(); ++j) {
    const Joint& joint = robot.joints[static_cast<std::size_t>(j)];
    if (reference[j] >= joint.lower && reference[j] <= joint.upper) continue;
    char text[320];
    std::snprintf(text, sizeof text,
                  "compensation: the reference of %s would be %.6g rad, outside its limits [%.6g, %.6g] rad: the "
                  "planned pose cannot be reached under its loads",
                  joint.name.c_str(), reference[j], joint.lower, joint.upper);
    throw UnreachableError(text);
  }
}

TrajectoryCompensationReport compensateTrajectory(const JointErrorModel& model, EffectMask mask,
                                                  const std::vector<JointVector>& planned,
                                                  const std::vector<JointVector>& velocities,
                                                  std::vector<JointVector>& references,
                                                  const FixedPointOptions& options) {
  if (!velocities.empty() && velocities.size() != planned.size()) {
    throw InvalidArgument("compensateTrajectory: " + std::to_string(planned.size()) + " positions but " +
                          std::to_string(velocities.size()) + " velocities");
  }
  Compensator compensator(model, mask, options);
  JointContext ctx(model.robot().dof());
  references.resize(planned.size());
  TrajectoryCompensationReport report;
  for (std::size_t k = 0; k < planned.size(); ++k) {
    ctx.q = planned[k];
    if (!velocities.empty()) ctx.velocity = velocities[k];
    const FixedPointReport point = compensator.compensate(ctx, references[k]);
    if (!point.converged) {
      throw SolverError("compensation did not converge at trajectory point " + std::to_string(k) + " (residual " +
                        std::to_string(point.residual) + " rad after " + std::to_string(point.iterations) +
                        " iterations)");
    }
    report.max_iterations = std::max(report.max_iterations, point.iterations);
    report.max_residual = std::max(report.max_residual, point.residual);
    report.max_correction = std::max(report.max_correction, (planned[k] - references[k]).cwiseAbs().maxCoeff());
  }
  return report;
}

}  // namespace jointcomp
