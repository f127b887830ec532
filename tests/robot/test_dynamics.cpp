// Rigid-body dynamics against identities: gravity is the gradient of the potential energy, the mass
// matrix is the Hessian of the kinetic energy re-derived from body velocities, inverse dynamics is affine
// in qdd, forward dynamics inverts it, the Coriolis terms follow from Lagrange's equations (finite
// differences of M), and energy is conserved without torque.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "model/common/errors.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"
#include "robot_test_support.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;
using testing_support::rotationVector;

std::vector<const Robot*> bothRobots() { return {&testing_support::rx170(), &testing_support::ur10()}; }

JointMatrix massAt(const Robot& robot, const JointVector& q) {
  RobotWorkspace ws(robot);
  JointMatrix mass;
  massMatrix(robot, ws, q, mass);
  return mass;
}

JointVector inverseDynamicsAt(const Robot& robot, const JointVector& q, const JointVector& qd, const JointVector& qdd) {
  RobotWorkspace ws(robot);
  JointVector tau;
  inverseDynamics(robot, ws, q, qd, qdd, tau);
  return tau;
}

JointVector gravityAt(const Robot& robot, const JointVector& q) {
  RobotWorkspace ws(robot);
  JointVector tau;
  gravityTorques(robot, ws, q, tau);
  return tau;
}

// The RX170 and the UR10 (every axis z) and the tilted RX170 (the general axes' way).
std::vector<const Robot*> robotsWithTiltedAxes() {
  static const Robot tilted = testing_support::tiltedRx170();
  std::vector<const Robot*> robots = bothRobots();
  robots.push_back(&tilted);
  return robots;
}

// Both ways of gravity (the world-frame sum over forward kinematics, and the joint-frame recursion from the
// sines) against the potential's gradient, and against each other to rounding.
TEST(Dynamics, GravityTorquesAreTheGradientOfThePotentialEnergy) {
  for (const Robot* robot : robotsWithTiltedAxes()) {
    RobotWorkspace ws(*robot);
    std::mt19937 rng(201u);
    const double h = 1e-5;
    for (int sample = 0; sample < 100; ++sample) {
      const JointVector q = testing_support::randomConfiguration(*robot, rng);
      JointVector tau, in_joint_frames;
      gravityTorques(*robot, ws, q, tau);
      ASSERT_EQ(tau.size(), robot->dof());
      double cosines[kMaxJoints], sines[kMaxJoints];
      for (int i = 0; i < robot->dof(); ++i) {
        cosines[i] = std::cos(q[i]);
        sines[i] = std::sin(q[i]);
      }
      gravityTorquesInJointFrames(*robot, cosines, sines, in_joint_frames);
      ASSERT_EQ(in_joint_frames.size(), robot->dof());
      const double scale = 1.0 + tau.cwiseAbs().maxCoeff();
      for (int i = 0; i < robot->dof(); ++i) {
        JointVector plus = q;
        JointVector minus = q;
        plus[i] += h;
        minus[i] -= h;
        const double gradient = (potentialEnergy(*robot, ws, plus) - potentialEnergy(*robot, ws, minus)) / (2.0 * h);
        EXPECT_NEAR(tau[i], gradient, 1e-5) << robot->name << " joint " << i + 1;
        EXPECT_NEAR(in_joint_frames[i], gradient, 1e-5) << robot->name << " joint " << i + 1;
        EXPECT_NEAR(in_joint_frames[i], tau[i], 1e-12 * scale) << robot->name << " joint " << i + 1;
      }
    }
  }
}

TEST(Dynamics, PotentialEnergyIsTheSumOfMassTimesHeight) {
  // Independent of the library's sum: m g z of every body centre from forward kinematics (gravity -z).
  for (const Robot* robot : bothRobots()) {
    ASSERT_LT((robot->gravity - Eigen::Vector3d(0, 0, -9.81)).norm(), 1e-15);
    RobotWorkspace ws(*robot);
    std::mt19937 rng(202u);
    for (int sample = 0; sample < 20; ++sample) {
      const JointVector q = testing_support::randomConfiguration(*robot, rng);
      forwardKinematics(*robot, ws, q);
      double expected = 0.0;
      for (int i = 0; i < robot->dof(); ++i) expected += robot->joints[i].body.mass * 9.81 * ws.com[i].z();
      EXPECT_NEAR(potentialEnergy(*robot, ws, q), expected, 1e-10);
    }
  }
}

TEST(Dynamics, GravityAtCurrentPoseEqualsGravityTorques) {
  for (const Robot* robot : bothRobots()) {
    RobotWorkspace ws(*robot);
    std::mt19937 rng(203u);
    const JointVector q = testing_support::randomConfiguration(*robot, rng);
    forwardKinematics(*robot, ws, q);
    JointVector at_current;
    gravityTorquesAtCurrentPose(*robot, ws, at_current);
    EXPECT_LT((at_current - gravityAt(*robot, q)).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(Dynamics, MassMatrixIsSymmetricPositiveDefinite) {
  for (const Robot* robot : bothRobots()) {
    std::mt19937 rng(204u);
    for (int sample = 0; sample < 100; ++sample) {
      const JointVector q = testing_support::randomConfiguration(*robot, rng);
      const JointMatrix mass = massAt(*robot, q);
      ASSERT_EQ(mass.rows(), robot->dof());
      ASSERT_EQ(mass.cols(), robot->dof());
      EXPECT_LT((mass - mass.transpose()).cwiseAbs().maxCoeff(), 1e-12 * mass.cwiseAbs().maxCoeff());
      const Eigen::MatrixXd dense = mass;
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(dense);
      EXPECT_GT(eigen.eigenvalues().minCoeff(), 0.0) << robot->name;
    }
  }
}

// Kinetic energy re-derived from body velocities: v of each centre of mass and omega of each body from
// central differences of forward kinematics along qd, inertia rotated into the base frame.
double kineticEnergyFromBodyVelocities(const Robot& robot, const JointVector& q, const JointVector& qd) {
  RobotWorkspace plus(robot);
  RobotWorkspace minus(robot);
  const double h = 1e-6;
  forwardKinematics(robot, plus, q + h * qd);
  forwardKinematics(robot, minus, q - h * qd);
  RobotWorkspace at(robot);
  forwardKinematics(robot, at, q);
  double energy = 0.0;
  for (int i = 0; i < robot.dof(); ++i) {
    const BodyInertia& body = robot.joints[i].body;
    const Eigen::Vector3d velocity = (plus.com[i] - minus.com[i]) / (2.0 * h);
    const Eigen::Vector3d omega =
        rotationVector(plus.joint_pose[i].linear() * minus.joint_pose[i].linear().transpose()) / (2.0 * h);
    const Eigen::Matrix3d rotation = at.joint_pose[i].linear();
    const Eigen::Matrix3d inertia = rotation * body.inertia * rotation.transpose();
    energy += 0.5 * body.mass * velocity.squaredNorm() + 0.5 * omega.dot(inertia * omega);
  }
  return energy;
}

TEST(Dynamics, KineticEnergyMatchesBodyVelocitiesAndTheMassMatrix) {
  for (const Robot* robot : bothRobots()) {
    RobotWorkspace ws(*robot);
    std::mt19937 rng(205u);
    for (int sample = 0; sample < 50; ++sample) {
      const JointVector q = testing_support::randomConfiguration(*robot, rng);
      const JointVector qd = testing_support::randomVector(robot->dof(), rng, 1.5);
      const double expected = kineticEnergyFromBodyVelocities(*robot, q, qd);
      const JointMatrix mass = massAt(*robot, q);
      EXPECT_NEAR(0.5 * qd.dot(mass * qd), expected, 1e-7 * std::max(1.0, expected)) << robot->name;
      EXPECT_NEAR(kineticEnergy(*robot, ws, q, qd), expected, 1e-7 * std::max(1.0, expected)) << robot->name;
    }
    // Each entry of M on its own: M_ij = T(e_i + e_j) - T(e_i) - T(e_j) with unit velocities.
    const JointVector q = testing_support::randomConfiguration(*robot, rng);
    const JointMatrix mass = massAt(*robot, q);
    for (int i = 0; i < robot->dof(); ++i) {
      for (int j = 0; j < robot->dof(); ++j) {
        JointVector ei = JointVector::Zero(robot->dof());
        JointVector ej = JointVector::Zero(robot->dof());
        ei[i] = 1.0;
        ej[j] = 1.0;
        const double entry = i == j ? 2.0 * kineticEnergyFromBodyVelocities(*robot, q, ei)
                                    : kineticEnergyFromBodyVelocities(*robot, q, ei + ej) -
                                          kineticEnergyFromBodyVelocities(*robot, q, ei) -
                                          kineticEnergyFromBodyVelocities(*robot, q, ej);
        EXPECT_NEAR(mass(i, j), entry, 1e-7) << robot->name << " M(" << i << ", " << j << ")";
      }
    }
  }
}

TEST(Dynamics, InverseDynamicsIsAffineInAccelerationWithTheMassMatrix) {
  for (const Robot* robot : bothRobots()) {
    std::mt19937 rng(206u);
    for (int sample = 0; sample < 100; ++sample) {
      const int n = robot->dof();
      const JointVector q = testing_support::randomConfiguration(*robot, rng);
      const JointVector qd = testing_support::randomVector(n, rng, 2.0);
      const JointVector qdd = testing_support::randomVector(n, rng, 5.0);
      const JointVector full = inverseDynamicsAt(*robot, q, qd, qdd);
      const JointVector bias = inverseDynamicsAt(*robot, q, qd, JointVector::Zero(n));
      const JointVector expected = massAt(*robot, q) * qdd + bias;
      EXPECT_LT((full - expected).cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, full.cwiseAbs().maxCoeff()))
          << robot->name;
    }
  }
}

TEST(Dynamics, InverseDynamicsAtRestIsGravity) {
  for (const Robot* robot : bothRobots()) {
    std::mt19937 rng(207u);
    for (int sample = 0; sample < 20; ++sample) {
      const int n = robot->dof();
      const JointVector q = testing_support::randomConfiguration(*robot, rng);
      const JointVector tau = inverseDynamicsAt(*robot, q, JointVector::Zero(n), JointVector::Zero(n));
      EXPECT_LT((tau - gravityAt(*robot, q)).cwiseAbs().maxCoeff(), 1e-9) << robot->name;
    }
  }
}

TEST(Dynamics, CoriolisTermsFollowFromLagrangesEquations) {
  // c(q, qd) = ID(q, qd, 0) - g(q) must equal Mdot qd - d/dq (1/2 qd^T M qd), with Mdot and the gradient
  // from central differences of the mass matrix; and qd^T (Mdot - 2C) qd = 0, i.e. qd . c = 1/2 qd^T Mdot qd.
  for (const Robot* robot : bothRobots()) {
    std::mt19937 rng(208u);
    const double h = 1e-6;
    for (int sample = 0; sample < 50; ++sample) {
      const int n = robot->dof();
      const JointVector q = testing_support::randomConfiguration(*robot, rng);
      const JointVector qd = testing_support::randomVector(n, rng, 2.0);
      const JointVector coriolis = inverseDynamicsAt(*robot, q, qd, JointVector::Zero(n)) - gravityAt(*robot, q);
      const JointMatrix mass_dot = (massAt(*robot, q + h * qd) - massAt(*robot, q - h * qd)) / (2.0 * h);
      JointVector expected = mass_dot * qd;
      for (int i = 0; i < n; ++i) {
        JointVector plus = q;
        JointVector minus = q;
        plus[i] += h;
        minus[i] -= h;
        expected[i] -= 0.5 * qd.dot((massAt(*robot, plus) - massAt(*robot, minus)) * qd) / (2.0 * h);
      }
      const double scale = std::max(1.0, expected.cwiseAbs().maxCoeff());
      EXPECT_LT((coriolis - expected).cwiseAbs().maxCoeff(), 1e-6 * scale) << robot->name;
      EXPECT_NEAR(qd.dot(coriolis), 0.5 * qd.dot(mass_dot * qd), 1e-6 * scale) << robot->name;
      // The velocity terms are quadratic in qd.
      const JointVector doubled = inverseDynamicsAt(*robot, q, 2.0 * qd, JointVector::Zero(n)) - gravityAt(*robot, q);
      EXPECT_LT((doubled - 4.0 * coriolis).cwiseAbs().maxCoeff(), 1e-9 * scale) << robot->name;
    }
  }
}

TEST(Dynamics, ForwardDynamicsInvertsInverseDynamics) {
  for (const Robot* robot : bothRobots()) {
    RobotWorkspace ws(*robot);
    std::mt19937 rng(209u);
    for (int sample = 0; sample < 100; ++sample) {
      const int n = robot->dof();
      const JointVector q = testing_support::randomConfiguration(*robot, rng);
      const JointVector qd = testing_support::randomVector(n, rng, 2.0);
      const JointVector tau = testing_support::randomVector(n, rng, 100.0);
      JointVector qdd;
      forwardDynamics(*robot, ws, q, qd, tau, qdd);
      ASSERT_EQ(qdd.size(), n);
      const JointVector back = inverseDynamicsAt(*robot, q, qd, qdd);
      EXPECT_LT((back - tau).cwiseAbs().maxCoeff(), 1e-8 * std::max(1.0, tau.cwiseAbs().maxCoeff())) << robot->name;
      // And the other way round: the acceleration that produced a torque is recovered.
      const JointVector wanted = testing_support::randomVector(n, rng, 3.0);
      JointVector recovered;
      forwardDynamics(*robot, ws, q, qd, inverseDynamicsAt(*robot, q, qd, wanted), recovered);
      EXPECT_LT((recovered - wanted).cwiseAbs().maxCoeff(), 1e-7) << robot->name;
      // At the pose of a forward kinematics already done (the plant's one FK per right-hand side): the same bits.
      JointVector again;
      forwardKinematics(*robot, ws, q);
      forwardDynamicsAtCurrentPose(*robot, ws, qd, tau, again);
      EXPECT_EQ(again, qdd) << robot->name;
    }
  }
}

// The plant's Cholesky in plain loops against Eigen's LLT: on the robots' mass matrices at random poses and on
// random symmetric positive definite matrices of every size up to kMaxJoints, the factor reproduces the
// matrix and the solves agree to 1e-12 (relative), and up to 8 joints they are Eigen's bits (what keeps the
// plant's stored regressions); a matrix that is not positive definite, or holds a NaN, is refused.
TEST(Dynamics, CholeskyInPlainLoopsAgreesWithEigensLlt) {
  std::mt19937 rng(1717u);
  auto check = [](const JointMatrix& matrix, const JointVector& b, const std::string& what) {
    JointMatrix factor;
    ASSERT_TRUE(choleskyFactor(matrix, factor)) << what;
    const JointMatrix lower = factor.triangularView<Eigen::Lower>();
    const double scale = matrix.cwiseAbs().maxCoeff();
    EXPECT_LT((lower * lower.transpose() - matrix).cwiseAbs().maxCoeff(), 1e-13 * scale) << what;
    JointVector x = b;
    choleskySolveInPlace(factor, x);
    const Eigen::LLT<JointMatrix> llt(matrix);
    const JointVector expected = llt.solve(b);
    EXPECT_LT((x - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff()) << what;
    const JointMatrix eigen_lower = llt.matrixL();
    EXPECT_EQ(lower, eigen_lower) << what;
    if (matrix.rows() <= 8) {
      EXPECT_EQ(x, expected) << what;
    }
  };
  for (const Robot* robot : bothRobots()) {
    for (int sample = 0; sample < 50; ++sample) {
      const JointVector q = testing_support::randomConfiguration(*robot, rng);
      check(massAt(*robot, q), testing_support::randomVector(robot->dof(), rng, 100.0), robot->name);
    }
  }
  for (int n = 1; n <= kMaxJoints; ++n) {
    for (int sample = 0; sample < 20; ++sample) {
      JointMatrix a(n, n);
      for (int i = 0; i < n; ++i) a.col(i) = testing_support::randomVector(n, rng, 1.0);
      const JointMatrix spd = a * a.transpose() + 0.1 * JointMatrix::Identity(n, n);
      check(spd, testing_support::randomVector(n, rng, 1.0), "random " + std::to_string(n) + " x " + std::to_string(n));
    }
  }
  JointMatrix factor;
  JointMatrix indefinite = JointMatrix::Identity(3, 3);
  indefinite(2, 2) = -1.0;
  EXPECT_FALSE(choleskyFactor(indefinite, factor));
  JointMatrix singular = JointMatrix::Ones(3, 3);
  EXPECT_FALSE(choleskyFactor(singular, factor));
  JointMatrix not_a_number = JointMatrix::Identity(3, 3);
  not_a_number(1, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(choleskyFactor(not_a_number, factor));
}

struct State {
  JointVector q, qd;
};

State rk4Step(const Robot& robot, RobotWorkspace& ws, const State& s, double dt) {
  const int n = robot.dof();
  const JointVector zero = JointVector::Zero(n);
  auto acceleration = [&](const JointVector& q, const JointVector& qd) {
    JointVector qdd;
    forwardDynamics(robot, ws, q, qd, zero, qdd);
    return qdd;
  };
  const JointVector k1q = s.qd;
  const JointVector k1v = acceleration(s.q, s.qd);
  const JointVector k2q = s.qd + 0.5 * dt * k1v;
  const JointVector k2v = acceleration(s.q + 0.5 * dt * k1q, k2q);
  const JointVector k3q = s.qd + 0.5 * dt * k2v;
  const JointVector k3v = acceleration(s.q + 0.5 * dt * k2q, k3q);
  const JointVector k4q = s.qd + dt * k3v;
  const JointVector k4v = acceleration(s.q + dt * k3q, k4q);
  State next;
  next.q = s.q + dt / 6.0 * (k1q + 2.0 * k2q + 2.0 * k3q + k4q);
  next.qd = s.qd + dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
  return next;
}

double totalEnergy(const Robot& robot, RobotWorkspace& ws, const State& s) {
  return kineticEnergy(robot, ws, s.q, s.qd) + potentialEnergy(robot, ws, s.q);
}

TEST(Dynamics, EnergyIsConservedWithoutTorque) {
  for (const Robot* robot : bothRobots()) {
    RobotWorkspace ws(*robot);
    std::mt19937 rng(210u);
    for (int sample = 0; sample < 10; ++sample) {
      State state{testing_support::randomConfiguration(*robot, rng, 0.3),
                  testing_support::randomVector(robot->dof(), rng, 1.0)};
      // The rate at which gravity alone does work: what dE/dt would be if the dynamics were wrong.
      const double gravity_power = std::abs(state.qd.dot(gravityAt(*robot, state.q)));
      // d/dt (T + V) by a central difference of two short RK4 steps, forward and backward in time.
      const double h = 1e-3;
      const double rate = (totalEnergy(*robot, ws, rk4Step(*robot, ws, state, h)) -
                           totalEnergy(*robot, ws, rk4Step(*robot, ws, state, -h))) /
                          (2.0 * h);
      EXPECT_LT(std::abs(rate), 1e-6 * std::max(1.0, gravity_power)) << robot->name << " power " << gravity_power;
      // The same over 0.1 s of free motion.
      const double start = totalEnergy(*robot, ws, state);
      for (int step = 0; step < 200; ++step) state = rk4Step(*robot, ws, state, 5e-4);
      EXPECT_NEAR(totalEnergy(*robot, ws, state), start, 1e-6 * std::max(1.0, std::abs(start))) << robot->name;
    }
  }
}

TEST(Dynamics, WrenchTorquesAreJacobianTransposeTimesWrench) {
  for (const Robot* robot : bothRobots()) {
    RobotWorkspace ws(*robot);
    std::mt19937 rng(211u);
    for (int sample = 0; sample < 50; ++sample) {
      const JointVector q = testing_support::randomConfiguration(*robot, rng);
      forwardKinematics(*robot, ws, q);
      Vector6 wrench;
      for (int k = 0; k < 6; ++k) wrench[k] = testing_support::randomVector(1, rng, 200.0)[0];
      JointVector tau;
      wrenchTorquesAtCurrentPose(*robot, ws, wrench, tau);
      Jacobian jacobian;
      toolJacobian(*robot, ws, jacobian);
      const JointVector expected = jacobian.transpose() * wrench;
      ASSERT_EQ(tau.size(), robot->dof());
      EXPECT_LT((tau - expected).cwiseAbs().maxCoeff(), 1e-10) << robot->name;
    }
  }
}

TEST(Dynamics, PayloadGravityIsTheWrenchOfItsWeight) {
  // A point mass fixed at the flange adds to the holding torques exactly what the tool wrench of its weight
  // asks: tau_loaded = tau_unloaded + J^T (-m g, 0) (the wrench the tool exerts to carry it). This checks
  // the fixed-joint merge, gravity and the wrench mapping against each other.
  const double payload = 12.5;
  std::ifstream file(testing_support::rx170Path());
  std::stringstream text;
  text << file.rdbuf();
  std::string urdf = text.str();
  const std::string payload_xml =
      "  <joint name=\"payload_joint\" type=\"fixed\"><parent link=\"flange\"/><child link=\"payload\"/>"
      "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/></joint>\n"
      "  <link name=\"payload\"><inertial><origin xyz=\"0 0 0\" rpy=\"0 0 0\"/><mass value=\"" +
      std::to_string(payload) +
      "\"/><inertia ixx=\"0\" ixy=\"0\" ixz=\"0\" iyy=\"0\" iyz=\"0\" izz=\"0\"/></inertial></link>\n</robot>";
  const std::size_t end = urdf.rfind("</robot>");
  ASSERT_NE(end, std::string::npos);
  urdf.replace(end, std::string("</robot>").size(), payload_xml);
  const Robot loaded = loadRobotFromUrdfString(urdf, "rx170+payload");
  const Robot& bare = testing_support::rx170();
  ASSERT_EQ(loaded.tip_link, "payload");
  RobotWorkspace ws_loaded(loaded);
  RobotWorkspace ws_bare(bare);
  std::mt19937 rng(212u);
  for (int sample = 0; sample < 50; ++sample) {
    const JointVector q = testing_support::randomConfiguration(bare, rng);
    JointVector tau_loaded, tau_bare, tau_wrench;
    gravityTorques(loaded, ws_loaded, q, tau_loaded);
    gravityTorques(bare, ws_bare, q, tau_bare);
    Vector6 wrench = Vector6::Zero();
    wrench.head<3>() = -payload * bare.gravity;
    wrenchTorquesAtCurrentPose(bare, ws_bare, wrench, tau_wrench);
    EXPECT_LT((tau_loaded - (tau_bare + tau_wrench)).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((ws_loaded.tool_pose.matrix() - ws_bare.tool_pose.matrix()).cwiseAbs().maxCoeff(), 1e-15);
  }
}

// The torque rates along a motion, (d tau / dq) qd, against central differences of the torques at
// q -+ h qd (h = 1e-6, truncation about 1e-12 of the values): gravity, a force at a point of the last body
// (J_p^T f through pointJacobian) and a tool wrench, to 1e-6 of the rate's size.
TEST(Dynamics, StaticTorqueRatesAreTheDerivativesAlongTheMotion) {
  for (const Robot* robot : bothRobots()) {
    RobotWorkspace ws(*robot);
    std::mt19937 rng(1727u);
    const double h = 1e-6;
    for (int sample = 0; sample < 50; ++sample) {
      const JointVector q = testing_support::randomConfiguration(*robot, rng);
      const JointVector qd = testing_support::randomVector(robot->dof(), rng, 2.0);
      const Eigen::Vector3d offset = testing_support::randomVector(3, rng, 0.3).head<3>();
      const Eigen::Vector3d force = testing_support::randomVector(3, rng, 200.0).head<3>();
      Vector6 wrench;
      for (int k = 0; k < 6; ++k) wrench[k] = testing_support::randomVector(1, rng, 200.0)[0];
      // The three torques at a configuration, the point fixed to the tool at `offset` in the tool frame.
      const auto torques = [&](const JointVector& at, JointVector& gravity, JointVector& point, JointVector& tool) {
        gravityTorques(*robot, ws, at, gravity);
        Jacobian jacobian;
        pointJacobian(*robot, ws, ws.tool_pose * offset, jacobian);
        point = jacobian.topRows<3>().transpose() * force;
        wrenchTorquesAtCurrentPose(*robot, ws, wrench, tool);
      };
      JointVector g_plus, p_plus, w_plus, g_minus, p_minus, w_minus, unused_g, unused_p, unused_w;
      torques(q + h * qd, g_plus, p_plus, w_plus);
      torques(q - h * qd, g_minus, p_minus, w_minus);
      torques(q, unused_g, unused_p, unused_w);  // the pose the rates are taken at
      JointVector gravity_rate = JointVector::Zero(robot->dof());
      JointVector point_rate = JointVector::Zero(robot->dof());
      JointVector wrench_rate = JointVector::Constant(robot->dof(), 1.0);  // added to: starts at 1
      addGravityTorqueRateAtCurrentPose(*robot, ws, qd, gravity_rate);
      addPointForceTorqueRateAtCurrentPose(*robot, ws, ws.tool_pose * offset, force, qd, point_rate);
      addWrenchTorqueRateAtCurrentPose(*robot, ws, wrench, qd, wrench_rate);
      const JointVector gravity_expected = (g_plus - g_minus) / (2.0 * h);
      const JointVector point_expected = (p_plus - p_minus) / (2.0 * h);
      const JointVector wrench_expected = (w_plus - w_minus) / (2.0 * h) + JointVector::Constant(robot->dof(), 1.0);
      const auto scale = [](const JointVector& v) { return std::max(1.0, v.cwiseAbs().maxCoeff()); };
      EXPECT_LT((gravity_rate - gravity_expected).cwiseAbs().maxCoeff(), 1e-6 * scale(gravity_expected))
          << robot->name << " sample " << sample;
      EXPECT_LT((point_rate - point_expected).cwiseAbs().maxCoeff(), 1e-6 * scale(point_expected))
          << robot->name << " sample " << sample;
      EXPECT_LT((wrench_rate - wrench_expected).cwiseAbs().maxCoeff(), 1e-6 * scale(wrench_expected))
          << robot->name << " sample " << sample;
    }
  }
}

// The joint-frame recursion's rate: a central difference of gravity along qd, and the world-frame rate.
TEST(Dynamics, GravityRateInJointFramesIsTheDerivativeAlongTheMotion) {
  for (const Robot* robot : robotsWithTiltedAxes()) {
    RobotWorkspace ws(*robot);
    std::mt19937 rng(1728u);
    const double h = 1e-6;
    const int n = robot->dof();
    for (int sample = 0; sample < 50; ++sample) {
      const JointVector q = testing_support::randomConfiguration(*robot, rng);
      const JointVector qd = testing_support::randomVector(n, rng, 2.0);
      double cosines[kMaxJoints], sines[kMaxJoints];
      for (int i = 0; i < n; ++i) {
        cosines[i] = std::cos(q[i]);
        sines[i] = std::sin(q[i]);
      }
      JointVector tau, rate;
      gravityTorquesAndRateInJointFrames(*robot, cosines, sines, qd, tau, rate);
      JointVector tau_alone;
      gravityTorquesInJointFrames(*robot, cosines, sines, tau_alone);
      EXPECT_EQ(tau, tau_alone) << robot->name;  // the rate does not change the torques
      const JointVector expected = (gravityAt(*robot, q + h * qd) - gravityAt(*robot, q - h * qd)) / (2.0 * h);
      forwardKinematics(*robot, ws, q);
      JointVector world = JointVector::Zero(n);
      addGravityTorqueRateAtCurrentPose(*robot, ws, qd, world);
      const double scale = std::max(1.0, expected.cwiseAbs().maxCoeff());
      EXPECT_LT((rate - expected).cwiseAbs().maxCoeff(), 1e-6 * scale) << robot->name << " sample " << sample;
      EXPECT_LT((rate - world).cwiseAbs().maxCoeff(), 1e-12 * scale) << robot->name << " sample " << sample;
    }
  }
  const Robot& rx170 = testing_support::rx170();
  const double cosines[kMaxJoints] = {1, 1, 1, 1, 1, 1}, sines[kMaxJoints] = {};
  JointVector tau, rate;
  JointVector qd = JointVector::Zero(6);
  qd[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(gravityTorquesAndRateInJointFrames(rx170, cosines, sines, qd, tau, rate), InvalidArgument);
}

TEST(Dynamics, MissingInertialThrowsOnEveryDynamicsCallNamingTheLink) {
  const Robot robot = loadRobotFromUrdfFile(testing_support::urdfTestFile("missing_inertial.urdf"));
  ASSERT_FALSE(robot.hasInertials());
  RobotWorkspace ws(robot);
  const int n = robot.dof();
  const JointVector zero = JointVector::Zero(n);
  JointVector tau;
  JointMatrix mass;
  auto expectNamesLink = [](const auto& call, const char* what) {
    try {
      call();
      ADD_FAILURE() << what << " did not throw";
    } catch (const InvalidArgument& error) {
      EXPECT_THAT(error.what(), HasSubstr("link_2")) << what;
      EXPECT_THAT(error.what(), HasSubstr("missing_inertial.urdf")) << what;
    } catch (const std::exception& error) {
      ADD_FAILURE() << what << " threw the wrong type: " << error.what();
    }
  };
  expectNamesLink([&] { gravityTorques(robot, ws, zero, tau); }, "gravityTorques");
  expectNamesLink([&] { gravityTorquesAtCurrentPose(robot, ws, tau); }, "gravityTorquesAtCurrentPose");
  const double cosines[kMaxJoints] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1}, sines[kMaxJoints] = {};
  expectNamesLink([&] { gravityTorquesInJointFrames(robot, cosines, sines, tau); }, "gravityTorquesInJointFrames");
  expectNamesLink([&] { inverseDynamics(robot, ws, zero, zero, zero, tau); }, "inverseDynamics");
  expectNamesLink([&] { massMatrix(robot, ws, zero, mass); }, "massMatrix");
  expectNamesLink([&] { forwardDynamics(robot, ws, zero, zero, zero, tau); }, "forwardDynamics");
  expectNamesLink([&] { potentialEnergy(robot, ws, zero); }, "potentialEnergy");
  expectNamesLink([&] { kineticEnergy(robot, ws, zero, zero); }, "kineticEnergy");
  // Kinematics does not need masses.
  EXPECT_NO_THROW(forwardKinematics(robot, ws, zero));
}

TEST(Dynamics, MasslessDistalInertiaMakesForwardDynamicsFailWithSolverError) {
  // The last body is a point mass on its own axis: turning joint 2 moves no inertia, M is singular.
  const std::string urdf = R"(<?xml version="1.0"?>
<robot name="point_on_axis">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1" effort="1"/></joint>
  <link name="l1"><inertial><origin xyz="0.5 0 0"/><mass value="2"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="1 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1" effort="1"/></joint>
  <link name="l2"><inertial><origin xyz="0 0 0.2"/><mass value="1"/>
    <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
</robot>)";
  const Robot robot = loadRobotFromUrdfString(urdf, "point_on_axis");
  RobotWorkspace ws(robot);
  const JointVector zero = JointVector::Zero(2);
  JointVector qdd;
  EXPECT_THROW(forwardDynamics(robot, ws, zero, zero, zero, qdd), SolverError);
}

TEST(Dynamics, ArgumentsOfTheWrongSizeOrNotFiniteThrowInvalidArgument) {
  const Robot& robot = testing_support::rx170();
  RobotWorkspace ws(robot);
  const JointVector zero = JointVector::Zero(6);
  JointVector nan = zero;
  nan[4] = std::numeric_limits<double>::quiet_NaN();
  JointVector tau;
  JointMatrix mass;
  EXPECT_THROW(inverseDynamics(robot, ws, zero, JointVector::Zero(5), zero, tau), InvalidArgument);
  EXPECT_THROW(inverseDynamics(robot, ws, zero, zero, nan, tau), InvalidArgument);
  EXPECT_THROW(inverseDynamics(robot, ws, nan, zero, zero, tau), InvalidArgument);
  EXPECT_THROW(forwardDynamics(robot, ws, zero, nan, zero, tau), InvalidArgument);
  EXPECT_THROW(forwardDynamics(robot, ws, zero, zero, JointVector::Zero(7), tau), InvalidArgument);
  EXPECT_THROW(massMatrix(robot, ws, nan, mass), InvalidArgument);
  EXPECT_THROW(gravityTorques(robot, ws, JointVector::Zero(3), tau), InvalidArgument);
  EXPECT_THROW(kineticEnergy(robot, ws, zero, nan), InvalidArgument);
}

}  // namespace
}  // namespace jointcomp
