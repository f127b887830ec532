// Offline compensation of the dynamic joint errors: the joint references that make the modelled robot
// (flexible joints, drives and their controller, every effect of the parameter file) put its links on a
// planned trajectory with time, at any speed.
//
// Two stages, both before the motion:
// 1. Closed form, sample by sample: the full inverse-dynamics load of the planned motion (inertia and
//    Coriolis, besides gravity, payload and tool wrench) deflects the joints through their compliance,
//    and the static compensator inverts that together with every other effect (the paper's
//    Q_ref = Q_theo - dQ, with dQ under the dynamic load). This removes what the links' own inertia does.
// 2. Iterative refinement against the nominal plant (iterative learning control): the reference is run
//    through the plant built from the nominal model and drives, and each sample of the reference moves by
//    the link error the run left there, until the largest error is below the tolerance. This removes what
//    stage 1 does not model: the drives' tracking lag (motor inertia, friction, the PID and its
//    feed-forward), the transmission damping and the reference's interpolation between samples.
// Why both: stage 1 alone leaves the drive lag, which dominates at speed (issue 18: 3e-5 rad on a 5 degree
// move in 2 s); stage 2 alone would need many more plant runs from the planned positions. Together the
// refinement converges in a few runs (each one plant run of the trajectory).
#pragma once

#include <vector>

#include "model/compensation/compensator.hpp"
#include "model/compensation/joint_trajectory.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/plant/flexible_joint_plant.hpp"
#include "model/robot/drive_parameters.hpp"
#include "model/robot/workspace.hpp"

namespace jointcomp {

struct DynamicCompensationOptions {
  // Largest link error of the nominal plant on the reference: 2e-6 rad is 3 um at the RX170's 1.5 m, half
  // the simulated tracker's noise; the refinement reaches it in 5 runs on the paper's spiral, 10 at ten
  // times its speed.
  double tolerance_rad = 2e-6;
  int max_iterations = 40;  // plant runs of stage 2, at most
  // The conditions of the motion: a payload at the tool (its weight loads the joints) and a known tool
  // wrench (a process force, base frame), both in the inverse model and in the nominal plant.
  double payload_mass = 0.0;                              // kg
  Eigen::Vector3d payload_com = Eigen::Vector3d::Zero();  // m, tool frame
  Vector6 tool_wrench = Vector6::Zero();
  FixedPointOptions fixed_point;
  // The nominal plant's runs, integrated tighter than the plant's default (whose relative tolerance of
  // 1e-6 allows errors of that order on joint angles near 1 rad), so that the refinement sees the
  // reference's effect rather than the integrator's.
  PlantOptions plant = tightPlantOptions(3e-7);
  static PlantOptions tightPlantOptions(double relative_tolerance) {
    PlantOptions tight;
    tight.relative_tolerance = relative_tolerance;
    tight.absolute_tolerance = 0.01 * relative_tolerance;  // rad
    return tight;
  }
};

struct DynamicCompensationReport {
  int iterations = 0;                 // plant runs made
  double initial_error_rad = 0.0;     // largest link error of the closed-form reference (stages 1 and 1b)
  double max_error_rad = 0.0;         // the same for the reference returned (the best run's)
  std::vector<double> error_per_run;  // largest link error of each run, in order
  double max_correction_rad = 0.0;    // largest |Q_theo - Q_ref|
};

// The references (and their velocities, which the controller interpolates with) for `planned`: its
// samples' times, positions and velocities (accelerations by central differences). Throws SolverError when
// the refinement does not reach the tolerance (within max_iterations runs, or before it stops improving
// for five runs) or a run of the nominal plant fails, InvalidArgument when
// the trajectory or the drives are malformed (fewer than three samples, times not increasing, a drive
// per joint missing), UnreachableError when a reference leaves the joint limits.
DynamicCompensationReport compensateDynamically(const JointErrorModel& nominal,
                                                const std::vector<DriveParameters>& drives,
                                                const JointTrajectory& planned, std::vector<JointVector>& reference,
                                                std::vector<JointVector>& reference_velocity,
                                                const DynamicCompensationOptions& options = {});

// What the closed form run one sample at a time carries from one sample to the next: the drive inverse
// filter's state and the correction at the last sample (whose change gives the stage-1 reference's velocity).
struct OnlineDynamicState {
  bool started = false;         // false until the first sample: that one sets the rest the filter starts from
  double time = 0.0;            // s, of the last sample
  JointVector correction;       // stage-1 reference minus planned position at the last sample
  JointVector demand_at_start;  // the drive filter's right side at the first sample (held by the integral)
  JointVector demand;           // its right side at the last sample
  JointVector delta;            // the drive inverse's addition to the reference at the last sample
  JointVector integral;         // and its integral
};

// Stages 1 and 1b sample by sample, for a trajectory that arrives while it runs (the FMU's dynamic mode):
// the drive inverse is a causal filter, so only its state passes between samples; the stage-1 reference's
// velocity is the planned one plus the correction's backward difference, its acceleration the planned one.
// Without stage 2 it leaves what the closed form leaves (the test measures it against the offline form).
// Allocates nothing per sample.
class OnlineDynamicCompensator {
public:
  // Throws InvalidArgument for a drive count other than the robot's joint count or malformed options.
  OnlineDynamicCompensator(const JointErrorModel& nominal, const std::vector<DriveParameters>& drives,
                           const DynamicCompensationOptions& options = {});

  // The reference and its velocity for the planned sample (time, q, qd, qdd, with `tool_wrench` as the
  // known process force) after the samples `before` has seen; `after` receives the state with this sample
  // (it may be `before`'s own object only if the caller does not need to repeat the sample). A sample at
  // a time not after the last one is InvalidArgument; a compensation that does not converge is reported
  // (converged false, outputs unchanged), one that leaves the joint limits throws UnreachableError.
  FixedPointReport compensate(const OnlineDynamicState& before, double time, const JointVector& q,
                              const JointVector& qd, const JointVector& qdd, const Vector6& tool_wrench,
                              JointVector& reference, JointVector& reference_velocity, OnlineDynamicState& after);

  OnlineDynamicState initialState() const;

private:
  const JointErrorModel& nominal_;
  std::vector<DriveParameters> drives_;
  DynamicCompensationOptions options_;
  Compensator compensator_;
  RobotWorkspace robot_ws_;
  JointErrorWorkspace load_ws_;
  JointContext ctx_, at_reference_;
  JointVector with_motion_, at_rest_, stage_one_, motor_reaction_, demand_;
  int compliance_;
};

// Runs `reference` (with its velocities) through `plant` the way the spiral experiment does: reset at the
// first sample, then at each sample set the reference, read the links, advance to the next sample time.
// Returns the link positions at the samples.
std::vector<JointVector> runReference(FlexibleJointPlant& plant, const std::vector<double>& time,
                                      const std::vector<JointVector>& reference,
                                      const std::vector<JointVector>& reference_velocity);

}  // namespace jointcomp
