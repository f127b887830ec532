// Offline compensation: the joint references Q_ref that bring the links to the planned Q_theo,
// Q_ref = Q_theo - dQ(Q_theo, Q_ref) (Olabi et al. 2012 with dQ = dQ_stiff + dQ_gear and any other effect).
// Errors that depend on where the links are (compliance, from the load at Q_theo) are evaluated once;
// errors that depend on the command (transmission error, through the motor angles) are iterated to the
// fixed point, which converges fast because they vary slowly with the command.
#pragma once

#include <vector>

#include "model/effects/joint_error_model.hpp"

namespace jointcomp {

// Throws UnreachableError naming the joint, its value and its limits when `reference` leaves them.
void requireWithinLimits(const Robot& robot, const JointVector& reference);

class Compensator {
public:
  Compensator(const JointErrorModel& model, EffectMask mask, FixedPointOptions options = {});

  // Q_ref for the planned link positions ctx.q (ctx.velocity, time, wrench and payload as planned).
  // Fills ctx.command and ctx.motor with the result. Allocates nothing. Throws UnreachableError when the
  // converged reference leaves a joint's limits (a result that cannot be commanded is no result).
  FixedPointReport compensate(JointContext& ctx, JointVector& reference);

  const JointErrorModel& model() const { return model_; }
  EffectMask mask() const { return mask_; }

private:
  const JointErrorModel& model_;
  EffectMask mask_;
  FixedPointOptions options_;
  bool iterate_;
  JointErrorWorkspace ws_;
  // The selected error effects, split once: those that do not read the command are summed once per point.
  std::vector<int> fixed_effects_, command_effects_;
  JointVector fixed_dq_, dq_;
};

struct TrajectoryCompensationReport {
  int max_iterations = 0;
  double max_residual = 0.0;
  double max_correction = 0.0;  // rad, largest |Q_theo - Q_ref|
};

// Compensates every point of a joint trajectory (rows of q with their velocities); throws SolverError
// naming the point when the iteration does not converge.
TrajectoryCompensationReport compensateTrajectory(const JointErrorModel& model, EffectMask mask,
                                                  const std::vector<JointVector>& planned,
                                                  const std::vector<JointVector>& velocities,
                                                  std::vector<JointVector>& references,
                                                  const FixedPointOptions& options = {});

}  // namespace jointcomp
