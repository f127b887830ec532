// Dynamics in the base frame (Luh-Walker-Paul style): every vector of every body is expressed in base
// coordinates, which keeps the recursions short and lets the mass matrix use composite bodies directly.
#include "model/robot/dynamics.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "model/common/errors.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {
namespace {

void requireInertials(const Robot& robot) {
  if (!robot.hasInertials()) {
    throw InvalidArgument(robot.source + ": link '" + robot.link_without_inertial +
                          "' has no <inertial>; dynamics need the mass of every moving link");
  }
}

void updateBodyInertias(const Robot& robot, RobotWorkspace& ws) {
  for (int i = 0; i < robot.dof(); ++i) {
    const Eigen::Matrix3d& rotation = ws.joint_pose[i].linear();
    ws.inertia[i].noalias() = rotation * robot.joints[i].body.inertia * rotation.transpose();
  }
}

// Newton-Euler at the configuration of the last forward kinematics, with ws.inertia updated to it; gravity is
// included when asked.
void newtonEulerAtCurrentPose(const Robot& robot, RobotWorkspace& ws, const JointVector& qd, const JointVector& qdd,
                              bool with_gravity, JointVector& tau) {
  const int n = robot.dof();
  const Eigen::Vector3d base_acc = with_gravity ? Eigen::Vector3d(-robot.gravity) : Eigen::Vector3d::Zero();
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();
  Eigen::Vector3d omega_dot = Eigen::Vector3d::Zero();
  Eigen::Vector3d origin_acc = base_acc;  // linear acceleration of the current joint origin
  Eigen::Vector3d previous_origin = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d step = ws.origin[i] - previous_origin;
    origin_acc += omega_dot.cross(step) + omega.cross(omega.cross(step));
    const Eigen::Vector3d joint_rate = ws.axis[i] * qd[i];
    omega_dot += ws.axis[i] * qdd[i] + omega.cross(joint_rate);
    omega += joint_rate;
    ws.omega[i] = omega;
    ws.omega_dot[i] = omega_dot;
    const Eigen::Vector3d r = ws.com[i] - ws.origin[i];
    ws.acc[i] = origin_acc + omega_dot.cross(r) + omega.cross(omega.cross(r));
    previous_origin = ws.origin[i];
  }
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();  // about the current joint origin
  for (int i = n - 1; i >= 0; --i) {
    const double mass = robot.joints[i].body.mass;
    const Eigen::Vector3d body_force = mass * ws.acc[i];
    const Eigen::Vector3d body_moment =
        ws.inertia[i] * ws.omega_dot[i] + ws.omega[i].cross(ws.inertia[i] * ws.omega[i]);
    if (i + 1 < n) moment += (ws.origin[i + 1] - ws.origin[i]).cross(force);
    moment += body_moment + (ws.com[i] - ws.origin[i]).cross(body_force);
    force += body_force;
    ws.force[i] = force;
    ws.moment[i] = moment;
    tau[i] = ws.axis[i].dot(moment);
  }
}

// The mass matrix at the last forward kinematics, with ws.inertia updated to it.
void massMatrixAtCurrentPose(const Robot& robot, RobotWorkspace& ws, JointMatrix& mass) {
  const int n = robot.dof();
  mass.resize(n, n);
  // Composite body of joints j..n-1: mass, first moment, inertia about the base origin.
  double composite_mass = 0.0;
  Eigen::Vector3d first_moment = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia_about_origin = Eigen::Matrix3d::Zero();
  for (int j = n - 1; j >= 0; --j) {
    const double m = robot.joints[j].body.mass;
    const Eigen::Vector3d& c = ws.com[j];
    composite_mass += m;
    first_moment += m * c;
    inertia_about_origin += ws.inertia[j] + m * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
    // Force and moment (about the base origin) that a unit acceleration of joint j asks of the composite.
    const Eigen::Vector3d& axis = ws.axis[j];
    const Eigen::Vector3d force = axis.cross(first_moment - composite_mass * ws.origin[j]);
    const Eigen::Vector3d moment = inertia_about_origin * axis - first_moment.cross(axis.cross(ws.origin[j]));
    for (int i = 0; i <= j; ++i) {
      const double value = ws.axis[i].dot(moment - ws.origin[i].cross(force));
      mass(i, j) = value;
      mass(j, i) = value;
    }
  }
}

}  // namespace

void gravityTorquesAtCurrentPose(const Robot& robot, RobotWorkspace& ws, JointVector& tau) {
  requireInertials(robot);
  tau.resize(robot.dof());
  // tau_i = axis_i . sum_{j >= i} (c_j - o_i) x (-m_j g): accumulate the distal mass and first moment.
  double distal_mass = 0.0;
  Eigen::Vector3d distal_moment = Eigen::Vector3d::Zero();
  for (int i = robot.dof() - 1; i >= 0; --i) {
    const double m = robot.joints[i].body.mass;
    distal_mass += m;
    distal_moment += m * ws.com[i];
    tau[i] = -ws.axis[i].dot((distal_moment - distal_mass * ws.origin[i]).cross(robot.gravity));
  }
}

namespace {
// Products with a joint's axis for gravityInJointFrames; ZAxes: every axis is the usual z axis, where each
// is a shuffle of coordinates (the compiler cannot know that of a general axis without a branch per use).
template <bool ZAxes>
struct AxisProducts {
  // Rot(axis, angle) v from the angle's cosine and sine (the transpose's product with -s).
  static Eigen::Vector3d turned(const Eigen::Vector3d& axis, double c, double s, const Eigen::Vector3d& v) {
    if constexpr (ZAxes) {
      return {c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z()};
    } else {
      return rotatedAboutAxis(axis, c, s, v);
    }
  }
  static Eigen::Vector3d cross(const Eigen::Vector3d& axis, const Eigen::Vector3d& v) {
    if constexpr (ZAxes) {
      return {-v.y(), v.x(), 0.0};
    } else {
      return axis.cross(v);
    }
  }
  static double dot(const Eigen::Vector3d& axis, const Eigen::Vector3d& v) {
    if constexpr (ZAxes) {
      return v.z();
    } else {
      return axis.dot(v);
    }
  }
};

bool everyAxisIsZ(const Robot& robot) {
  return std::all_of(robot.joints.begin(), robot.joints.end(), [](const Joint& joint) { return isZAxis(joint.axis); });
}

// tau_i = -axis_i . (h_i x g_i) in body i's frame, with g_i = Rot_i^T P_i^T g_(i-1) (gravity carried down
// from the root's) and h_i = sum_{j >= i} m_j (c_j - o_i) = m_i c_i + M_(i+1) t_(i+1) + P_(i+1) Rot_(i+1) h_(i+1)
// (the distal first moment carried back): the world formula's triple product in body i's frame. WithRate:
// their derivatives along qd as well, from d(Rot_i)/dt = Rot_i [axis_i]x qd_i:
// g_i' = Rot_i^T P_i^T g_(i-1)' - qd_i axis_i x g_i,
// h_i' = P_(i+1) Rot_(i+1) (h_(i+1)' + qd_(i+1) axis_(i+1) x h_(i+1)).
template <bool WithRate, bool ZAxes>
void gravityInJointFrames(const Robot& robot, const double* cosines, const double* sines, const double* qd,
                          JointVector& tau, JointVector* rate) {
  using Axis = AxisProducts<ZAxes>;
  const int n = robot.dof();
  std::array<Eigen::Vector3d, kMaxJoints> gravity, gravity_rate;
  Eigen::Vector3d g = robot.gravity, g_rate = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Joint& joint = robot.joints[static_cast<std::size_t>(i)];
    const Eigen::Matrix3d placement = joint.placement.linear();  // a plain 3 x 3: the products on it unroll
    g = Axis::turned(joint.axis, cosines[i], -sines[i], placement.transpose() * g);
    gravity[static_cast<std::size_t>(i)] = g;
    if constexpr (WithRate) {
      g_rate = Axis::turned(joint.axis, cosines[i], -sines[i], placement.transpose() * g_rate) -
               qd[i] * Axis::cross(joint.axis, g);
      gravity_rate[static_cast<std::size_t>(i)] = g_rate;
    }
  }
  Eigen::Vector3d moment = Eigen::Vector3d::Zero(), moment_rate = Eigen::Vector3d::Zero();
  double distal_mass = 0.0;
  for (int i = n - 1; i >= 0; --i) {
    const Joint& joint = robot.joints[static_cast<std::size_t>(i)];
    if (i < n - 1) {
      const Joint& next = robot.joints[static_cast<std::size_t>(i + 1)];
      const Eigen::Matrix3d placement = next.placement.linear();
      if constexpr (WithRate) {
        moment_rate = placement * Axis::turned(next.axis, cosines[i + 1], sines[i + 1],
                                               moment_rate + qd[i + 1] * Axis::cross(next.axis, moment));
      }
      moment = placement * Axis::turned(next.axis, cosines[i + 1], sines[i + 1], moment) +
               distal_mass * next.placement.translation();
    }
    moment += joint.body.mass * joint.body.com;
    distal_mass += joint.body.mass;
    const Eigen::Vector3d& g_i = gravity[static_cast<std::size_t>(i)];
    tau[i] = -Axis::dot(joint.axis, moment.cross(g_i));
    if constexpr (WithRate) {
      (*rate)[i] =
          -Axis::dot(joint.axis, moment_rate.cross(g_i) + moment.cross(gravity_rate[static_cast<std::size_t>(i)]));
    }
  }
}
}  // namespace

void gravityTorquesInJointFrames(const Robot& robot, const double* cosines, const double* sines, JointVector& tau) {
  requireInertials(robot);
  tau.resize(robot.dof());
  if (everyAxisIsZ(robot)) {
    gravityInJointFrames<false, true>(robot, cosines, sines, nullptr, tau, nullptr);
  } else {
    gravityInJointFrames<false, false>(robot, cosines, sines, nullptr, tau, nullptr);
  }
}

void gravityTorquesAndRateInJointFrames(const Robot& robot, const double* cosines, const double* sines,
                                        const JointVector& qd, JointVector& tau, JointVector& rate) {
  requireInertials(robot);
  checkJointVector(robot, qd, "qd");
  tau.resize(robot.dof());
  rate.resize(robot.dof());
  if (everyAxisIsZ(robot)) {
    gravityInJointFrames<true, true>(robot, cosines, sines, qd.data(), tau, &rate);
  } else {
    gravityInJointFrames<true, false>(robot, cosines, sines, qd.data(), tau, &rate);
  }
}

namespace {

// The velocities the torque rates need, from the last forward kinematics and qd: each axis turns with the
// bodies before its joint, each joint origin moves with them (a joint's own rotation moves neither).
struct ChainRates {
  std::array<Eigen::Vector3d, kMaxJoints> axis_rate;        // d(axis_i)/dt
  std::array<Eigen::Vector3d, kMaxJoints> origin_velocity;  // d(o_i)/dt
  std::array<Eigen::Vector3d, kMaxJoints> omega;            // angular velocity of body i
};

void chainRates(const Robot& robot, const RobotWorkspace& ws, const JointVector& qd, ChainRates& rates) {
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // of the previous joint's origin (the base's is still)
  for (int i = 0; i < robot.dof(); ++i) {
    if (i > 0) velocity += omega.cross(ws.origin[i] - ws.origin[i - 1]);
    rates.origin_velocity[i] = velocity;
    rates.axis_rate[i] = omega.cross(ws.axis[i]);
    omega += ws.axis[i] * qd[i];
    rates.omega[i] = omega;
  }
}

}  // namespace

void addGravityTorqueRateAtCurrentPose(const Robot& robot, const RobotWorkspace& ws, const JointVector& qd,
                                       JointVector& rate) {
  requireInertials(robot);
  ChainRates rates;
  chainRates(robot, ws, qd, rates);
  // tau_i = -axis_i . (lever_i x g), lever_i = sum_{j >= i} m_j (c_j - o_i): the product rule on both factors.
  double distal_mass = 0.0;
  Eigen::Vector3d distal_moment = Eigen::Vector3d::Zero(), distal_moment_rate = Eigen::Vector3d::Zero();
  for (int i = robot.dof() - 1; i >= 0; --i) {
    const double m = robot.joints[i].body.mass;
    const Eigen::Vector3d com_velocity = rates.origin_velocity[i] + rates.omega[i].cross(ws.com[i] - ws.origin[i]);
    distal_mass += m;
    distal_moment += m * ws.com[i];
    distal_moment_rate += m * com_velocity;
    const Eigen::Vector3d lever = distal_moment - distal_mass * ws.origin[i];
    const Eigen::Vector3d lever_rate = distal_moment_rate - distal_mass * rates.origin_velocity[i];
    rate[i] -= rates.axis_rate[i].dot(lever.cross(robot.gravity)) + ws.axis[i].dot(lever_rate.cross(robot.gravity));
  }
}

void addPointForceTorqueRateAtCurrentPose(const Robot& robot, const RobotWorkspace& ws, const Eigen::Vector3d& point,
                                          const Eigen::Vector3d& force, const JointVector& qd, JointVector& rate) {
  const int n = robot.dof();
  if (n == 0) return;
  ChainRates rates;
  chainRates(robot, ws, qd, rates);
  const Eigen::Vector3d point_velocity =
      rates.origin_velocity[n - 1] + rates.omega[n - 1].cross(point - ws.origin[n - 1]);
  // tau_i = axis_i . ((p - o_i) x f).
  for (int i = 0; i < n; ++i) {
    rate[i] += rates.axis_rate[i].dot((point - ws.origin[i]).cross(force)) +
               ws.axis[i].dot((point_velocity - rates.origin_velocity[i]).cross(force));
  }
}

void addWrenchTorqueRateAtCurrentPose(const Robot& robot, const RobotWorkspace& ws, const Vector6& wrench,
                                      const JointVector& qd, JointVector& rate) {
  addPointForceTorqueRateAtCurrentPose(robot, ws, ws.tool_pose.translation(), wrench.head<3>(), qd, rate);
  ChainRates rates;
  chainRates(robot, ws, qd, rates);
  for (int i = 0; i < robot.dof(); ++i) rate[i] += rates.axis_rate[i].dot(wrench.tail<3>());
}

void gravityTorques(const Robot& robot, RobotWorkspace& ws, const JointVector& q, JointVector& tau) {
  forwardKinematics(robot, ws, q);
  gravityTorquesAtCurrentPose(robot, ws, tau);
}

void inverseDynamics(const Robot& robot, RobotWorkspace& ws, const JointVector& q, const JointVector& qd,
                     const JointVector& qdd, JointVector& tau) {
  requireInertials(robot);
  checkJointVector(robot, qd, "qd");
  checkJointVector(robot, qdd, "qdd");
  forwardKinematics(robot, ws, q);
  tau.resize(robot.dof());
  updateBodyInertias(robot, ws);
  newtonEulerAtCurrentPose(robot, ws, qd, qdd, true, tau);
}

void massMatrix(const Robot& robot, RobotWorkspace& ws, const JointVector& q, JointMatrix& mass) {
  requireInertials(robot);
  forwardKinematics(robot, ws, q);
  updateBodyInertias(robot, ws);
  massMatrixAtCurrentPose(robot, ws, mass);
}

void forwardDynamics(const Robot& robot, RobotWorkspace& ws, const JointVector& q, const JointVector& qd,
                     const JointVector& tau, JointVector& qdd) {
  requireInertials(robot);
  checkJointVector(robot, qd, "qd");
  checkJointVector(robot, tau, "tau");
  forwardKinematics(robot, ws, q);
  forwardDynamicsAtCurrentPose(robot, ws, qd, tau, qdd);
}

void forwardDynamicsAtCurrentPose(const Robot& robot, RobotWorkspace& ws, const JointVector& qd, const JointVector& tau,
                                  JointVector& qdd) {
  const int n = robot.dof();
  qdd.setZero(n);
  ws.bias.resize(n);
  updateBodyInertias(robot, ws);  // once for both: they depend on q only
  newtonEulerAtCurrentPose(robot, ws, qd, qdd, true, ws.bias);
  massMatrixAtCurrentPose(robot, ws, ws.mass_matrix);
  if (!choleskyFactor(ws.mass_matrix, ws.mass_factor)) {
    throw SolverError(robot.source + ": the mass matrix is not positive definite at this configuration");
  }
  qdd = tau - ws.bias;
  choleskySolveInPlace(ws.mass_factor, qdd);
}

namespace {

// One tangent (forward-mode) pass of newtonEulerAtCurrentPose, whose results ws holds, along e_joint in q
// (`pose`) or in qd, at fixed qdd: d tau into `column`. Turning joint j rotates the bodies j..n-1 by axis_j
// about o_j (their axes beyond j, origins, centres, inertias); the bodies before it keep their pose and
// rates, so the forward pass starts at it. `pose` a template argument: the rate passes drop the rotation's
// terms at compile time (a third of the Jacobian's time otherwise).
template <bool pose, class Column>
void newtonEulerTangent(const Robot& robot, const RobotWorkspace& ws, const JointVector& qd, const JointVector& qdd,
                        int joint, Column column) {
  const int n = robot.dof();
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  const Eigen::Vector3d rotation = pose ? ws.axis[joint] : zero;  // of every body from `joint` on
  std::array<Eigen::Vector3d, kMaxJoints> d_omega, d_omega_dot, d_acc;
  Eigen::Vector3d d_w = zero, d_w_dot = zero, d_origin_acc = zero;
  for (int i = joint; i < n; ++i) {
    const Eigen::Vector3d& omega_before = i > 0 ? ws.omega[i - 1] : zero;
    const Eigen::Vector3d& omega_dot_before = i > 0 ? ws.omega_dot[i - 1] : zero;
    Eigen::Vector3d d_axis = zero;
    if (i > joint) {  // at the joint itself its origin and axis stay, and the tangents before it are zero
      const Eigen::Vector3d step = ws.origin[i] - ws.origin[i - 1];
      d_origin_acc += d_w_dot.cross(step) + d_w.cross(omega_before.cross(step)) + omega_before.cross(d_w.cross(step));
      if (pose) {
        const Eigen::Vector3d d_step = rotation.cross(step);
        d_origin_acc += omega_dot_before.cross(d_step) + omega_before.cross(omega_before.cross(d_step));
        d_axis = rotation.cross(ws.axis[i]);
      }
    }
    const Eigen::Vector3d joint_rate = ws.axis[i] * qd[i];
    Eigen::Vector3d d_joint_rate = d_axis * qd[i];
    if (!pose && i == joint) d_joint_rate += ws.axis[i];
    d_w_dot += d_axis * qdd[i] + d_w.cross(joint_rate) + omega_before.cross(d_joint_rate);
    d_w += d_joint_rate;
    const Eigen::Vector3d r = ws.com[i] - ws.origin[i];
    d_acc[i] = d_origin_acc + d_w_dot.cross(r) + d_w.cross(ws.omega[i].cross(r)) + ws.omega[i].cross(d_w.cross(r));
    if (pose) {
      const Eigen::Vector3d d_r = rotation.cross(r);
      d_acc[i] += ws.omega_dot[i].cross(d_r) + ws.omega[i].cross(ws.omega[i].cross(d_r));
    }
    d_omega[i] = d_w;
    d_omega_dot[i] = d_w_dot;
  }
  Eigen::Vector3d d_force = zero, d_moment = zero;
  for (int i = n - 1; i >= 0; --i) {
    const bool moved = i >= joint;
    if (i + 1 < n) {
      const Eigen::Vector3d lever = ws.origin[i + 1] - ws.origin[i];
      d_moment += lever.cross(d_force);
      if (pose && moved) d_moment += rotation.cross(lever).cross(ws.force[i + 1]);
    }
    if (moved) {
      const double mass = robot.joints[i].body.mass;
      const Eigen::Matrix3d& inertia = ws.inertia[i];
      const Eigen::Vector3d& omega = ws.omega[i];
      const Eigen::Vector3d inertia_omega = inertia * omega;
      const Eigen::Vector3d r = ws.com[i] - ws.origin[i];
      const Eigen::Vector3d d_body_force = mass * d_acc[i];
      // d(I v) = I dv + dI v with dI v = rotation x (I v) - I (rotation x v).
      Eigen::Vector3d d_inertia_omega = inertia * d_omega[i];
      Eigen::Vector3d d_body_moment = inertia * d_omega_dot[i] + d_omega[i].cross(inertia_omega);
      if (pose) {
        d_inertia_omega += rotation.cross(inertia_omega) - inertia * rotation.cross(omega);
        d_body_moment += rotation.cross(inertia * ws.omega_dot[i]) - inertia * rotation.cross(ws.omega_dot[i]) +
                         rotation.cross(r).cross(mass * ws.acc[i]);
      }
      d_moment += d_body_moment + omega.cross(d_inertia_omega) + r.cross(d_body_force);
      d_force += d_body_force;
    }
    double d_tau = ws.axis[i].dot(d_moment);
    if (pose && i > joint) d_tau += rotation.cross(ws.axis[i]).dot(ws.moment[i]);
    column[i] = d_tau;
  }
}

}  // namespace

void inverseDynamicsDerivativesAtCurrentPose(const Robot& robot, RobotWorkspace& ws, const JointVector& qd,
                                             const JointVector& qdd, bool with_gravity, JointMatrix& by_q,
                                             JointMatrix& by_qd) {
  const int n = robot.dof();
  by_q.resize(n, n);
  by_qd.resize(n, n);
  updateBodyInertias(robot, ws);
  JointVector tau(n);
  newtonEulerAtCurrentPose(robot, ws, qd, qdd, with_gravity, tau);  // the values the tangents run along
  for (int j = 0; j < n; ++j) {
    newtonEulerTangent<true>(robot, ws, qd, qdd, j, by_q.col(j));
    newtonEulerTangent<false>(robot, ws, qd, qdd, j, by_qd.col(j));
  }
}

void inverseDynamicsDerivatives(const Robot& robot, RobotWorkspace& ws, const JointVector& q, const JointVector& qd,
                                const JointVector& qdd, JointMatrix& by_q, JointMatrix& by_qd) {
  requireInertials(robot);
  checkJointVector(robot, qd, "qd");
  checkJointVector(robot, qdd, "qdd");
  forwardKinematics(robot, ws, q);
  inverseDynamicsDerivativesAtCurrentPose(robot, ws, qd, qdd, true, by_q, by_qd);
}

void forwardDynamicsDerivatives(const Robot& robot, RobotWorkspace& ws, const JointVector& q, const JointVector& qd,
                                const JointVector& tau, JointVector& qdd, JointMatrix& by_q, JointMatrix& by_qd) {
  forwardDynamics(robot, ws, q, qd, tau, qdd);  // checks, and leaves M's factor in ws
  inverseDynamicsDerivativesAtCurrentPose(robot, ws, qd, qdd, true, by_q, by_qd);
  // M d qdd = -d RNEA at fixed tau.
  JointVector column;
  for (int j = 0; j < robot.dof(); ++j) {
    column = -by_q.col(j);
    choleskySolveInPlace(ws.mass_factor, column);
    by_q.col(j) = column;
    column = -by_qd.col(j);
    choleskySolveInPlace(ws.mass_factor, column);
    by_qd.col(j) = column;
  }
}

// Eigen's unblocked LLT's arithmetic, in its order, so that the plant's results stay the same bits: the
// diagonal less the sum of the row's squares, each entry less the sum of its products (both summed from
// the first term on), divided by the root.
bool choleskyFactor(const JointMatrix& matrix, JointMatrix& factor) {
  const Eigen::Index n = matrix.rows();
  factor.resize(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    double diagonal = matrix(j, j);
    if (j > 0) {
      double squares = factor(j, 0) * factor(j, 0);
      for (Eigen::Index k = 1; k < j; ++k) squares += factor(j, k) * factor(j, k);
      diagonal -= squares;
    }
    if (!(diagonal > 0.0)) return false;  // not positive definite, or not a number
    const double root = std::sqrt(diagonal);
    factor(j, j) = root;
    for (Eigen::Index i = j + 1; i < n; ++i) {
      double value = matrix(i, j);
      if (j > 0) {
        double products = factor(i, 0) * factor(j, 0);
        for (Eigen::Index k = 1; k < j; ++k) products += factor(i, k) * factor(j, k);
        value -= products;
      }
      factor(i, j) = value / root;
    }
  }
  return true;
}

// The two triangular solves in the order of Eigen's LLT::solveInPlace up to 8 joints (its panel width;
// beyond, the sums are grouped differently, at the rounding level): forward, subtracting term by term;
// backward, subtracting the dot product of L's column below the diagonal, which Eigen's own sum gives.
void choleskySolveInPlace(const JointMatrix& factor, JointVector& x) {
  const Eigen::Index n = factor.rows();
  for (Eigen::Index i = 0; i < n; ++i) {  // L y = b
    double value = x[i];
    for (Eigen::Index k = 0; k < i; ++k) value -= factor(i, k) * x[k];
    x[i] = value / factor(i, i);
  }
  for (Eigen::Index i = n - 1; i >= 0; --i) {  // L^T x = y
    const Eigen::Index below = n - 1 - i;
    double value = x[i];
    if (below > 0) value -= factor.col(i).segment(i + 1, below).cwiseProduct(x.segment(i + 1, below)).sum();
    x[i] = value / factor(i, i);
  }
}

void wrenchTorquesAtCurrentPose(const Robot& robot, const RobotWorkspace& ws, const Vector6& wrench, JointVector& tau) {
  tau.resize(robot.dof());
  const Eigen::Vector3d point = ws.tool_pose.translation();
  for (int i = 0; i < robot.dof(); ++i) {
    tau[i] = ws.axis[i].cross(point - ws.origin[i]).dot(wrench.head<3>()) + ws.axis[i].dot(wrench.tail<3>());
  }
}

double potentialEnergy(const Robot& robot, RobotWorkspace& ws, const JointVector& q) {
  requireInertials(robot);
  forwardKinematics(robot, ws, q);
  double energy = 0.0;
  for (int i = 0; i < robot.dof(); ++i) energy -= robot.joints[i].body.mass * robot.gravity.dot(ws.com[i]);
  return energy;
}

double kineticEnergy(const Robot& robot, RobotWorkspace& ws, const JointVector& q, const JointVector& qd) {
  checkJointVector(robot, qd, "qd");
  JointMatrix mass;
  massMatrix(robot, ws, q, mass);
  return 0.5 * qd.dot(mass * qd);
}

}  // namespace jointcomp
