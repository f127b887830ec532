// Statics of the flexible-joint plant. With the motors held, a link started undeflected (or from the
// equilibrium, perturbed) and damped by the joint springs must come to rest where each joint spring
// carries the load:  K (p + e(p) - q) = g(q) + balancer(q).  The load is computed here from
// gravityTorques and SpringBalancerEffect::torque, the transmission error e(p) from the harmonics and
// the gear ratios; the rest pose is also compared with the quasi-static model (settleStatically). And
// reset() must start the plant at rest: the right-hand side vanishes there, motors free and controlled.
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/plant/plant_test_support.hpp"

#include "model/effects/compliance.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/effects/spring_balancer.hpp"
#include "model/effects/transmission_error.hpp"
#include "model/io/parameter_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp {
namespace {

using namespace plant_testing;

JointVector stiffnesses(const JointErrorModel& model) {
  const auto& compliance =
      dynamic_cast<const ComplianceEffect&>(model.effect(model.findEffect(ComplianceEffect::kType)));
  JointVector k(model.robot().dof());
  for (int j = 0; j < k.size(); ++j) k[j] = compliance.stiffness(j);
  return k;
}

// Drives whose joint springs are damped near critically for the link held by a locked motor (with the
// diagonal of the mass matrix at q as the link inertia), so that the links settle within a second.
std::vector<DriveParameters> settlingDrives(const JointErrorModel& model, const JointVector& q) {
  std::vector<DriveParameters> drives = loadDriveParameters(kParameters, model.robot());
  RobotWorkspace ws(model.robot());
  JointMatrix mass;
  massMatrix(model.robot(), ws, q, mass);
  const JointVector k = stiffnesses(model);
  for (int j = 0; j < model.robot().dof(); ++j) {
    drives[j].transmission_damping_nms_per_rad = 1.4 * std::sqrt(k[j] * mass(j, j));
  }
  return drives;
}

PlantOptions heldMotors() {
  PlantOptions options;
  options.control = false;
  options.motors_locked = true;
  options.relative_tolerance = 1e-10;
  options.absolute_tolerance = 1e-13;
  return options;
}

// Overwrites the link positions and velocities of the plant's state.
void setLinks(FlexibleJointPlant& plant, const JointVector& q, const JointVector& qd) {
  PlantState state = plant.saveState();
  const int n = plant.dof();
  for (int j = 0; j < n; ++j) {
    state.y[j] = q[j];
    state.y[n + j] = qd[j];
  }
  plant.restoreState(state);
}

struct Settled {
  JointVector q, qd, p;
};

Settled settle(FlexibleJointPlant& plant, double seconds) {
  plant.advance(plant.time() + seconds);
  return {plant.linkPositions(), plant.linkVelocities(), plant.motorPositions()};
}

void expectComplianceEquilibrium(const JointErrorModel& model, const Settled& s, const std::string& what) {
  const JointVector k = stiffnesses(model);
  const JointVector predicted = s.p + transmissionErrorAt(model, s.p) - staticLoad(model, s.q).cwiseQuotient(k);
  for (int j = 0; j < s.q.size(); ++j) {
    EXPECT_NEAR(s.q[j], predicted[j], 1e-9) << what << ", joint " << j + 1;
    EXPECT_LT(std::abs(s.qd[j]), 1e-8) << what << ", joint " << j + 1 << " still moving";
  }
  // The quasi-static robot commanded p must be where the plant came to rest.
  JointErrorWorkspace ws(model.robot());
  JointContext ctx(model.robot().dof());
  ctx.command = s.p;
  const FixedPointReport report = settleStatically(model, model.allEffects(), ws, ctx);
  ASSERT_TRUE(report.converged) << what;
  for (int j = 0; j < s.q.size(); ++j) EXPECT_NEAR(s.q[j], ctx.q[j], 1e-9) << what << ", joint " << j + 1;
}

const std::vector<JointVector>& poses() {
  static const std::vector<JointVector> list = {
      joints({0, 60, 60, 0, 60, 0}),        // the spiral's posture: the arm reaches out
      joints({30, -20, 110, 45, -70, 90}),  // wrist turned, joint 5 and 6 loaded
      joints({-90, 10, 30, -120, 100, -40}),
  };
  return list;
}

TEST(PlantStatics, UndeflectedLinksSettleOnTheComplianceEquilibrium) {
  const JointErrorModel model = loadParameterFile(kParameters, rx170());
  for (const JointVector& command : poses()) {
    FlexibleJointPlant plant(model, settlingDrives(model, command), heldMotors());
    plant.reset(command);
    // Links where the motors are (springs relaxed), at rest: gravity pulls them down onto the springs.
    setLinks(plant, plant.motorPositions(), JointVector::Zero(6));
    const Settled s = settle(plant, 2.5);
    ASSERT_EQ(s.p, command) << "locked motors moved";
    // The fall is not nothing: joint 2 and 3 deflect by hundredths of a degree or more.
    const JointVector deflection = s.q - s.p - transmissionErrorAt(model, s.p);
    EXPECT_GT(deflection.head(3).cwiseAbs().maxCoeff(), 1e-4);
    expectComplianceEquilibrium(model, s, "undeflected start at " + std::to_string(command[1] / kDegree));
  }
}

TEST(PlantStatics, PerturbedEquilibriumReturnsToIt) {
  const JointErrorModel model = loadParameterFile(kParameters, rx170());
  std::mt19937 rng(4711);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (const JointVector& command : poses()) {
    FlexibleJointPlant plant(model, settlingDrives(model, command), heldMotors());
    plant.reset(command);
    JointVector q = plant.linkPositions();
    JointVector qd(6);
    for (int j = 0; j < 6; ++j) {
      q[j] += 2e-3 * uniform(rng);
      qd[j] = 0.05 * uniform(rng);
    }
    setLinks(plant, q, qd);
    expectComplianceEquilibrium(model, settle(plant, 2.5), "perturbed at " + std::to_string(command[1] / kDegree));
  }
}

// A payload and a tool wrench change the load; the plant's rest pose follows the quasi-static model
// with the same payload and wrench.
TEST(PlantStatics, PayloadAndWrenchAgreeWithTheQuasiStaticModel) {
  const JointErrorModel model = loadParameterFile(kParameters, rx170());
  const JointVector command = poses()[0];
  FlexibleJointPlant plant(model, settlingDrives(model, command), heldMotors());
  plant.reset(command);
  const Eigen::Vector3d com(0.02, -0.01, 0.15);
  Vector6 wrench;
  wrench << 40.0, -25.0, 60.0, 3.0, -2.0, 1.5;
  plant.setPayload(20.0, com);
  plant.setToolWrench(wrench);
  const Settled s = settle(plant, 2.5);
  JointErrorWorkspace ws(model.robot());
  JointContext ctx(6);
  ctx.command = command;
  ctx.payload_mass = 20.0;
  ctx.payload_com = com;
  ctx.tool_wrench = wrench;
  ASSERT_TRUE(settleStatically(model, model.allEffects(), ws, ctx).converged);
  JointContext unloaded(6);
  unloaded.command = command;
  ASSERT_TRUE(settleStatically(model, model.allEffects(), ws, unloaded).converged);
  EXPECT_GT((ctx.q - unloaded.q).cwiseAbs().maxCoeff(), 1e-5) << "the payload should move the links visibly";
  for (int j = 0; j < 6; ++j) EXPECT_NEAR(s.q[j], ctx.q[j], 1e-9) << "joint " << j + 1;
}

// reset() promises a start at rest in static equilibrium, motors at the command: the right-hand side
// must vanish there with the motors free and the controller on (any acceleration would be a transient
// the plant makes up). The motors feel the spring through d(p + e)/dp = 1 + e'(p) (derivative()), so the
// integral state must make the controller give tau_s (1 + e'), not tau_s: at commit 96de58d reset() sets
// it for tau_s and joints 2 and 3 start with motor accelerations of -tau_s e' / B, up to 0.07 rad/s^2.
TEST(PlantStatics, ResetStartsAtRest) {
  const JointErrorModel model = loadParameterFile(kParameters, rx170());
  const std::vector<DriveParameters> drives = loadDriveParameters(kParameters, model.robot());
  FlexibleJointPlant plant(model, drives);
  for (const JointVector& command : poses()) {
    plant.reset(command);
    EXPECT_EQ(plant.motorPositions(), command);
    const PlantState state = plant.saveState();
    std::vector<double> ydot(state.y.size());
    plant.derivative(plant.time(), state.y.data(), ydot.data());
    for (int j = 0; j < 6; ++j) {
      // Link and motor accelerations; 1e-6 rad/s^2 moves a joint 5e-13 rad in a millisecond.
      EXPECT_NEAR(ydot[6 + j], 0.0, 1e-6) << "link acceleration, joint " << j + 1;
      EXPECT_NEAR(ydot[18 + j], 0.0, 1e-6) << "motor acceleration, joint " << j + 1 << " at " << command.transpose();
    }
  }
}

// The same promise, seen in the motion: held at its reset command for 0.2 s, the motors of the
// controlled plant stay where they were put.
TEST(PlantStatics, ControlledPlantStaysAtItsResetPose) {
  const JointErrorModel model = loadParameterFile(kParameters, rx170());
  FlexibleJointPlant plant(model, loadDriveParameters(kParameters, model.robot()));
  const JointVector command = poses()[0];
  plant.reset(command);
  const JointVector q0 = plant.linkPositions();
  plant.advance(0.2);
  EXPECT_LT((plant.motorPositions() - command).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT((plant.linkPositions() - q0).cwiseAbs().maxCoeff(), 1e-8);
}

}  // namespace
}  // namespace jointcomp
