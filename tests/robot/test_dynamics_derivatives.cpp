// The derivatives of inverse and forward dynamics (one tangent pass per column) against (extrapolated) central
// differences of inverseDynamics and forwardDynamics on random states of the RX170 and the UR10, against
// identities that need no step (the bias torques are quadratic in qd, so a difference in qd of any size is
// exact; gravity's part of d tau/dq is the gravity torques' rate, derived separately), and the forward
// dynamics' against -M^-1 of the inverse dynamics'.
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"
#include "robot_test_support.hpp"

namespace jointcomp {
namespace {

std::vector<const Robot*> bothRobots() { return {&testing_support::rx170(), &testing_support::ur10()}; }

struct State {
  JointVector q, qd, qdd;
};

State randomState(const Robot& robot, std::mt19937& rng) {
  return {testing_support::randomConfiguration(robot, rng), testing_support::randomVector(robot.dof(), rng, 2.0),
          testing_support::randomVector(robot.dof(), rng, 5.0)};
}

// Central differences of f (a joint vector of a joint vector) at x, one column per joint, Richardson-
// extrapolated from steps h and h/2 (error O(h^4): 1e-12 at h = 1e-3, above the rounding of ~1e-13 |f|).
template <class Function>
JointMatrix centralDifferences(const JointVector& x, Function f) {
  const int n = static_cast<int>(x.size());
  JointMatrix result(n, n);
  for (int j = 0; j < n; ++j) {
    const auto difference = [&](double h) {
      JointVector plus = x, minus = x;
      plus[j] += h;
      minus[j] -= h;
      return JointVector((f(plus) - f(minus)) / (2.0 * h));
    };
    const double h = 1e-3 * std::max(1.0, std::abs(x[j]));
    result.col(j) = (4.0 * difference(0.5 * h) - difference(h)) / 3.0;
  }
  return result;
}

// Every entry within `relative` of itself plus `row_floor` of its row's largest entry: a central difference's
// rounding error scales with the function it differences (a joint's torque), not with the entry, and whole
// columns vanish (turning joint 1 about the vertical moves no torque).
void expectClose(const JointMatrix& actual, const JointMatrix& reference, double relative, double row_floor,
                 const std::string& what) {
  ASSERT_EQ(actual.rows(), reference.rows());
  ASSERT_EQ(actual.cols(), reference.cols());
  for (int i = 0; i < reference.rows(); ++i) {
    const double row_scale = reference.row(i).cwiseAbs().maxCoeff();
    for (int j = 0; j < reference.cols(); ++j) {
      const double tolerance = relative * std::abs(reference(i, j)) + row_floor * row_scale + 1e-13;
      EXPECT_LE(std::abs(actual(i, j) - reference(i, j)), tolerance)
          << what << ": entry (" << i + 1 << ", " << j + 1 << ") is " << actual(i, j) << ", the reference "
          << reference(i, j);
    }
  }
}

TEST(DynamicsDerivatives, InverseDynamicsMatchesCentralDifferences) {
  for (const Robot* robot : bothRobots()) {
    RobotWorkspace ws(*robot), scratch(*robot);
    std::mt19937 rng(1701u);
    for (int sample = 0; sample < 20; ++sample) {
      const State s = randomState(*robot, rng);
      JointMatrix by_q, by_qd;
      inverseDynamicsDerivatives(*robot, ws, s.q, s.qd, s.qdd, by_q, by_qd);
      const auto tau = [&](const JointVector& q, const JointVector& qd) {
        JointVector result;
        inverseDynamics(*robot, scratch, q, qd, s.qdd, result);
        return result;
      };
      const std::string what = robot->name + " sample " + std::to_string(sample);
      expectClose(by_q, centralDifferences(s.q, [&](const JointVector& q) { return tau(q, s.qd); }), 1e-6, 1e-9,
                  what + ", d tau/dq");
      expectClose(by_qd, centralDifferences(s.qd, [&](const JointVector& qd) { return tau(s.q, qd); }), 1e-6, 1e-9,
                  what + ", d tau/dqd");
    }
  }
}

TEST(DynamicsDerivatives, RateColumnsAreExactDifferencesOfTheQuadraticBias) {
  // tau(qd) = M qdd + c(qd, qd) + g with c bilinear: (tau(qd + s e_j) - tau(qd - s e_j)) / 2s is exact for
  // any s, here 1 rad/s, so only rounding separates the two.
  for (const Robot* robot : bothRobots()) {
    RobotWorkspace ws(*robot), scratch(*robot);
    std::mt19937 rng(1702u);
    for (int sample = 0; sample < 20; ++sample) {
      const State s = randomState(*robot, rng);
      JointMatrix by_q, by_qd;
      inverseDynamicsDerivatives(*robot, ws, s.q, s.qd, s.qdd, by_q, by_qd);
      JointMatrix exact(robot->dof(), robot->dof());
      for (int j = 0; j < robot->dof(); ++j) {
        JointVector plus = s.qd, minus = s.qd, tau_plus, tau_minus;
        plus[j] += 1.0;
        minus[j] -= 1.0;
        inverseDynamics(*robot, scratch, s.q, plus, s.qdd, tau_plus);
        inverseDynamics(*robot, scratch, s.q, minus, s.qdd, tau_minus);
        exact.col(j) = (tau_plus - tau_minus) / 2.0;
      }
      expectClose(by_qd, exact, 1e-12, 1e-12, robot->name + " sample " + std::to_string(sample));
    }
  }
}

TEST(DynamicsDerivatives, GravitysPartIsTheGravityTorquesRate) {
  for (const Robot* robot : bothRobots()) {
    RobotWorkspace ws(*robot);
    std::mt19937 rng(1703u);
    const int n = robot->dof();
    for (int sample = 0; sample < 20; ++sample) {
      const State s = randomState(*robot, rng);
      forwardKinematics(*robot, ws, s.q);
      JointMatrix with_q, with_qd, without_q, without_qd;
      inverseDynamicsDerivativesAtCurrentPose(*robot, ws, s.qd, s.qdd, true, with_q, with_qd);
      inverseDynamicsDerivativesAtCurrentPose(*robot, ws, s.qd, s.qdd, false, without_q, without_qd);
      JointMatrix gravity(n, n);
      for (int j = 0; j < n; ++j) {
        JointVector rate = JointVector::Zero(n);
        addGravityTorqueRateAtCurrentPose(*robot, ws, JointVector::Unit(n, j), rate);
        gravity.col(j) = rate;
      }
      const std::string what = robot->name + " sample " + std::to_string(sample);
      expectClose(with_q - without_q, gravity, 1e-12, 1e-12, what + ", d g/dq");
      expectClose(with_qd, without_qd, 0.0, 0.0, what + ", d tau/dqd (gravity has none)");
    }
  }
}

TEST(DynamicsDerivatives, ForwardDynamicsMatchesCentralDifferencesAndInvertsInverseDynamics) {
  for (const Robot* robot : bothRobots()) {
    RobotWorkspace ws(*robot), scratch(*robot);
    std::mt19937 rng(1704u);
    for (int sample = 0; sample < 20; ++sample) {
      const State s = randomState(*robot, rng);
      JointVector tau;
      inverseDynamics(*robot, scratch, s.q, s.qd, s.qdd, tau);
      JointVector qdd;
      JointMatrix by_q, by_qd;
      forwardDynamicsDerivatives(*robot, ws, s.q, s.qd, tau, qdd, by_q, by_qd);
      const std::string what = robot->name + " sample " + std::to_string(sample);
      EXPECT_LE((qdd - s.qdd).norm(), 1e-9 * (1.0 + s.qdd.norm())) << what;
      const auto acceleration = [&](const JointVector& q, const JointVector& qd) {
        JointVector result;
        forwardDynamics(*robot, scratch, q, qd, tau, result);
        return result;
      };
      expectClose(by_q, centralDifferences(s.q, [&](const JointVector& q) { return acceleration(q, s.qd); }), 1e-6,
                  1e-9, what + ", d qdd/dq");
      expectClose(by_qd, centralDifferences(s.qd, [&](const JointVector& qd) { return acceleration(s.q, qd); }), 1e-6,
                  1e-9, what + ", d qdd/dqd");
      // M d qdd/dx = -d tau/dx at the same state.
      JointMatrix mass, tau_by_q, tau_by_qd;
      massMatrix(*robot, scratch, s.q, mass);
      inverseDynamicsDerivatives(*robot, scratch, s.q, s.qd, qdd, tau_by_q, tau_by_qd);
      expectClose(-mass * by_q, tau_by_q, 1e-10, 1e-10, what + ", M d qdd/dq");
      expectClose(-mass * by_qd, tau_by_qd, 1e-10, 1e-10, what + ", M d qdd/dqd");
    }
  }
}

}  // namespace
}  // namespace jointcomp
