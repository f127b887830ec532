// Rigid-body dynamics of the chain: gravity, recursive Newton-Euler, mass matrix, forward dynamics.
// Each call needs robot.hasInertials() (else InvalidArgument naming the link), allocates nothing, and
// runs forward kinematics itself unless its name says it reuses the last one.
#pragma once

#include "model/robot/workspace.hpp"

namespace jointcomp {

// Joint torques that hold the robot still against gravity at q: tau = dV/dq.
void gravityTorques(const Robot& robot, RobotWorkspace& ws, const JointVector& q, JointVector& tau);
// The same at the configuration of the last forwardKinematics call.
void gravityTorquesAtCurrentPose(const Robot& robot, RobotWorkspace& ws, JointVector& tau);
// The same from the joints' cosines and sines (robot.dof() of each), without forward kinematics: gravity
// carried out along the chain into each body's frame and the distal first moments carried back, both in
// joint frames, about a third of the arithmetic of the chain's poses. For a caller that needs gravity
// alone (offline compensation); equal to gravityTorques up to rounding.
void gravityTorquesInJointFrames(const Robot& robot, const double* cosines, const double* sines, JointVector& tau);
// The same and its rate along qd, (d tau / dq) qd (addGravityTorqueRateAtCurrentPose's, into `rate`), for the
// plant's static feed-forward.
void gravityTorquesAndRateInJointFrames(const Robot& robot, const double* cosines, const double* sines,
                                        const JointVector& qd, JointVector& tau, JointVector& rate);

// The rates of static torques along a motion, (d tau / dq) qd, for a feed-forward that follows the motion
// without a second evaluation at q + qd dt; each at the last forwardKinematics call and added to `rate`.
// gravityTorquesAtCurrentPose's:
void addGravityTorqueRateAtCurrentPose(const Robot& robot, const RobotWorkspace& ws, const JointVector& qd,
                                       JointVector& rate);
// Those of a force fixed in the base frame acting at a point fixed to the last body (given in the base frame):
// the rate of J_p^T force, J_p the point's Jacobian (pointJacobian's top rows).
void addPointForceTorqueRateAtCurrentPose(const Robot& robot, const RobotWorkspace& ws, const Eigen::Vector3d& point,
                                          const Eigen::Vector3d& force, const JointVector& qd, JointVector& rate);
// wrenchTorquesAtCurrentPose's, for a wrench fixed in the base frame.
void addWrenchTorqueRateAtCurrentPose(const Robot& robot, const RobotWorkspace& ws, const Vector6& wrench,
                                      const JointVector& qd, JointVector& rate);

// Inverse dynamics by recursive Newton-Euler: tau = M(q) qdd + C(q, qd) qd + g(q).
void inverseDynamics(const Robot& robot, RobotWorkspace& ws, const JointVector& q, const JointVector& qd,
                     const JointVector& qdd, JointVector& tau);

// Joint-space mass matrix M(q) (composite rigid bodies), symmetric, into ws.mass_matrix and `mass`.
void massMatrix(const Robot& robot, RobotWorkspace& ws, const JointVector& q, JointMatrix& mass);

// Forward dynamics: qdd = M(q)^-1 (tau - C(q, qd) qd - g(q)). Throws SolverError if M is not positive
// definite (massless chain ends).
void forwardDynamics(const Robot& robot, RobotWorkspace& ws, const JointVector& q, const JointVector& qd,
                     const JointVector& tau, JointVector& qdd);
// The same at the pose of the last forwardKinematics(robot, ws, q) (the plant computes it once per
// right-hand side for its loads and its dynamics); qd and tau are not checked here.
void forwardDynamicsAtCurrentPose(const Robot& robot, RobotWorkspace& ws, const JointVector& qd, const JointVector& tau,
                                  JointVector& qdd);

// The partial derivatives of inverse dynamics tau = RNEA(q, qd, qdd) at fixed qdd: d tau/dq (which holds
// (dM/dq) qdd, the Coriolis and the gravity terms' derivatives) and d tau/dqd, column j by one tangent
// (forward-mode) pass of the recursions along e_j, into n x n `by_q` and `by_qd`.
void inverseDynamicsDerivatives(const Robot& robot, RobotWorkspace& ws, const JointVector& q, const JointVector& qd,
                                const JointVector& qdd, JointMatrix& by_q, JointMatrix& by_qd);
// The same at the pose of the last forwardKinematics (qd and qdd not checked); gravity left out unless asked
// (the plant takes gravity's derivative with its other loads'). Overwrites ws's Newton-Euler scratch.
void inverseDynamicsDerivativesAtCurrentPose(const Robot& robot, RobotWorkspace& ws, const JointVector& qd,
                                             const JointVector& qdd, bool with_gravity, JointMatrix& by_q,
                                             JointMatrix& by_qd);
// The partial derivatives of forward dynamics qdd = FD(q, qd, tau) at fixed tau, from M d qdd = -d RNEA:
// d qdd/dq and d qdd/dqd (n x n), and qdd itself. Throws SolverError as forwardDynamics does.
void forwardDynamicsDerivatives(const Robot& robot, RobotWorkspace& ws, const JointVector& q, const JointVector& qd,
                                const JointVector& tau, JointVector& qdd, JointMatrix& by_q, JointMatrix& by_qd);

// The Cholesky factor L (M = L L^T, lower triangle of `factor`; the upper is left as it was) of a symmetric
// positive definite matrix, reading its lower triangle; false when it is not positive definite (or holds a
// value that is not a number). Eigen's LLT's arithmetic in plain loops: the same bits (its solve's up to 8
// joints), without the dynamic-size block dispatch that cost several times the arithmetic at a serial arm's
// sizes (checked against it in tests/robot/test_dynamics.cpp).
bool choleskyFactor(const JointMatrix& matrix, JointMatrix& factor);
// x <- M^-1 x with the factor of choleskyFactor.
void choleskySolveInPlace(const JointMatrix& factor, JointVector& x);

// tau = J^T w for a wrench w (force, then moment about the tool point; base frame): the joint torques
// with which the tool exerts w on its surroundings, or equally those that hold the robot against a
// wrench -w applied to the tool. At the last forwardKinematics call.
void wrenchTorquesAtCurrentPose(const Robot& robot, const RobotWorkspace& ws, const Vector6& wrench, JointVector& tau);

// Potential energy of gravity (J), for tests and energy checks.
double potentialEnergy(const Robot& robot, RobotWorkspace& ws, const JointVector& q);
// Kinetic energy 1/2 qd^T M qd (J).
double kineticEnergy(const Robot& robot, RobotWorkspace& ws, const JointVector& q, const JointVector& qd);

}  // namespace jointcomp
