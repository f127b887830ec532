// The load torque computeLoadTorque gives, against independent derivations: a payload is the same as
// adding its mass to the last body (gravity of a modified robot) and the same as the gradient of its own
// potential energy (finite differences); a tool wrench subtracts J^T w with J^T w taken from the virtual
// work of the wrench along finite-difference tool motions.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "effects_test_support.hpp"
#include "model/effects/payload.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {
namespace {

// Rotation vector of a rotation matrix (small rotations), through the quaternion.
Eigen::Vector3d rotationVector(const Eigen::Matrix3d& rotation) {
  Eigen::Quaterniond quaternion(rotation);
  if (quaternion.w() < 0.0) quaternion.coeffs() = -quaternion.coeffs();
  const Eigen::Vector3d v = quaternion.vec();
  const double s = v.norm();
  if (s < 1e-300) return Eigen::Vector3d::Zero();
  return (2.0 * std::atan2(s, quaternion.w()) / s) * v;
}

Eigen::Isometry3d toolPose(const Robot& robot, const JointVector& q) {
  RobotWorkspace ws(robot);
  forwardKinematics(robot, ws, q);
  return ws.tool_pose;
}

JointVector loadTorque(const JointErrorModel& model, EffectMask mask, JointContext ctx) {
  JointErrorWorkspace ws(model.robot());
  computeLoadTorque(model, mask, ws, ctx);
  return ctx.load_torque;
}

// The robot with a point mass rigidly added to its last body (mass and centre of mass merged).
Robot withPayloadInLastBody(const Robot& robot, double mass, const Eigen::Vector3d& com_in_tool) {
  Robot heavier = robot;
  BodyInertia& body = heavier.joints.back().body;
  const Eigen::Vector3d point = robot.tool * com_in_tool;  // last joint frame
  body.com = (body.mass * body.com + mass * point) / (body.mass + mass);
  body.mass += mass;
  return heavier;
}

TEST(Payload, IsTheSameAsAHeavierLastBody) {
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  const double mass = 25.0;
  const Eigen::Vector3d com(0.04, -0.03, 0.12);
  const Robot heavier = withPayloadInLastBody(robot, mass, com);
  RobotWorkspace heavy_ws(heavier);
  std::mt19937 rng(31u);
  for (int sample = 0; sample < 50; ++sample) {
    JointContext ctx(robot.dof());
    ctx.q = effects_test::randomConfiguration(robot, rng);
    ctx.payload_mass = mass;
    ctx.payload_com = com;
    const JointVector with_payload = loadTorque(model, 0, ctx);
    JointVector expected;
    gravityTorques(heavier, heavy_ws, ctx.q, expected);
    const double scale = expected.cwiseAbs().maxCoeff();
    for (int j = 0; j < robot.dof(); ++j) {
      EXPECT_NEAR(with_payload[j], expected[j], 1e-12 * scale) << "sample " << sample << ", joint " << j;
    }
  }
}

TEST(Payload, IsTheGradientOfItsPotentialEnergy) {
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  const double mass = 12.5;
  const Eigen::Vector3d com(-0.02, 0.05, 0.2);
  // V = -m g . p(q), p the payload's centre of mass in the base frame.
  const auto energy = [&](const JointVector& q) { return -mass * robot.gravity.dot(toolPose(robot, q) * com); };
  std::mt19937 rng(32u);
  const double h = 1e-5;
  for (int sample = 0; sample < 30; ++sample) {
    JointContext ctx(robot.dof());
    ctx.q = effects_test::randomConfiguration(robot, rng);
    const JointVector without = loadTorque(model, model.allEffects(), ctx);
    ctx.payload_mass = mass;
    ctx.payload_com = com;
    const JointVector with = loadTorque(model, model.allEffects(), ctx);
    for (int j = 0; j < robot.dof(); ++j) {
      JointVector plus = ctx.q;
      JointVector minus = ctx.q;
      plus[j] += h;
      minus[j] -= h;
      const double fd = (energy(plus) - energy(minus)) / (2.0 * h);
      EXPECT_NEAR(with[j] - without[j], fd, 1e-6 * (1.0 + std::abs(fd))) << "sample " << sample << ", joint " << j;
    }
  }
}

TEST(Payload, ZeroMassChangesNothing) {
  const JointErrorModel model = effects_test::rx170Model();
  std::mt19937 rng(33u);
  JointContext ctx(model.robot().dof());
  ctx.q = effects_test::randomConfiguration(model.robot(), rng);
  const JointVector without = loadTorque(model, model.allEffects(), ctx);
  ctx.payload_com = Eigen::Vector3d(0.1, 0.2, 0.3);
  EXPECT_EQ(loadTorque(model, model.allEffects(), ctx), without);
}

TEST(ToolWrench, SubtractsJTransposeW) {
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  std::mt19937 rng(34u);
  std::uniform_real_distribution<double> force(-200.0, 200.0);
  std::uniform_real_distribution<double> moment(-30.0, 30.0);
  const double h = 1e-6;
  for (int sample = 0; sample < 30; ++sample) {
    JointContext ctx(robot.dof());
    ctx.q = effects_test::randomConfiguration(robot, rng);
    const JointVector without = loadTorque(model, model.allEffects(), ctx);
    Vector6 w;
    w << force(rng), force(rng), force(rng), moment(rng), moment(rng), moment(rng);
    ctx.tool_wrench = w;
    const JointVector with = loadTorque(model, model.allEffects(), ctx);
    // (J^T w)_j = f . dp/dq_j + m . omega_j: the virtual work of the wrench along a motion of joint j.
    for (int j = 0; j < robot.dof(); ++j) {
      JointVector plus = ctx.q;
      JointVector minus = ctx.q;
      plus[j] += h;
      minus[j] -= h;
      const Eigen::Isometry3d a = toolPose(robot, plus);
      const Eigen::Isometry3d b = toolPose(robot, minus);
      const Eigen::Vector3d velocity = (a.translation() - b.translation()) / (2.0 * h);
      const Eigen::Vector3d omega = rotationVector(a.linear() * b.linear().transpose()) / (2.0 * h);
      const double work = w.head<3>().dot(velocity) + w.tail<3>().dot(omega);
      EXPECT_NEAR(with[j] - without[j], -work, 1e-6 * (1.0 + std::abs(work))) << "sample " << sample << ", joint " << j;
    }
  }
}

TEST(ToolWrench, PushingUpOnTheToolIsLikeLighterGravity) {
  // An upward force at the tool equal to a payload's weight cancels that payload when both sit at the
  // tool point.
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  std::mt19937 rng(35u);
  for (int sample = 0; sample < 20; ++sample) {
    JointContext ctx(robot.dof());
    ctx.q = effects_test::randomConfiguration(robot, rng);
    const JointVector bare = loadTorque(model, model.allEffects(), ctx);
    ctx.payload_mass = 8.0;
    ctx.tool_wrench.head<3>() = -8.0 * robot.gravity;
    const JointVector both = loadTorque(model, model.allEffects(), ctx);
    EXPECT_LT((both - bare).cwiseAbs().maxCoeff(), 1e-10 * (1.0 + bare.cwiseAbs().maxCoeff()));
  }
}

}  // namespace
// The load torque's rate along a motion (what the plant's feed-forward follows) against central differences
// of computeLoadTorque at q -+ h qd: gravity, the spring balancer of the parameter file, a payload in the
// context, a payload effect and a tool wrench together, to 1e-6 of the rate's size; true, all being known.
TEST(LoadTorqueRate, IsTheDerivativeOfTheLoadTorqueAlongTheMotion) {
  JointErrorModel model = effects_test::rx170Model();
  model.addEffect(std::make_unique<PayloadEffect>(model.robot(), 4.0, Eigen::Vector3d(0.02, -0.05, 0.12)));
  const Robot& robot = model.robot();
  const EffectMask mask = model.allEffects();
  std::mt19937 rng(1728u);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double h = 1e-6;
  JointErrorWorkspace ws(robot);
  for (int sample = 0; sample < 50; ++sample) {
    JointContext ctx(robot.dof());
    ctx.q = effects_test::randomConfiguration(robot, rng);
    ctx.payload_mass = 7.5;
    ctx.payload_com = Eigen::Vector3d(0.1 * unit(rng), 0.1 * unit(rng), 0.2);
    for (int k = 0; k < 6; ++k) ctx.tool_wrench[k] = 100.0 * unit(rng);
    JointVector qd(robot.dof());
    for (int j = 0; j < robot.dof(); ++j) qd[j] = 2.0 * unit(rng);
    JointContext plus = ctx, minus = ctx;
    plus.q += h * qd;
    minus.q -= h * qd;
    const JointVector expected = (loadTorque(model, mask, plus) - loadTorque(model, mask, minus)) / (2.0 * h);
    computeLoadTorque(model, mask, ws, ctx);
    JointVector rate;
    ASSERT_TRUE(loadTorqueRateAtCurrentPose(model, mask, ws, ctx, qd, rate));
    const double scale = std::max(1.0, expected.cwiseAbs().maxCoeff());
    EXPECT_LT((rate - expected).cwiseAbs().maxCoeff(), 1e-6 * scale) << "sample " << sample;
  }
}

// A load effect that does not know its rate: the model says so (the plant then takes a difference quotient).
TEST(LoadTorqueRate, AnEffectWithoutItsRateIsReported) {
  struct ConstantLoad : Effect {
    std::string type() const override { return "constant_load"; }
    EffectRole role() const override { return EffectRole::Load; }
    void addLoadTorque(const Robot&, const RobotWorkspace&, JointContext& ctx) const override {
      ctx.load_torque[0] += 1.0;
    }
    std::vector<std::string> parameterNames() const override { return {}; }
    std::vector<double> parameters() const override { return {}; }
    void setParameters(const std::vector<double>&) override {}
    nlohmann::json toJson() const override { return {{"type", type()}}; }
    std::unique_ptr<Effect> clone() const override { return std::make_unique<ConstantLoad>(*this); }
  };
  JointErrorModel model = effects_test::rx170Model();
  const EffectMask without = model.allEffects();
  model.addEffect(std::make_unique<ConstantLoad>());
  JointErrorWorkspace ws(model.robot());
  JointContext ctx(model.robot().dof());
  ctx.q = JointVector::Constant(6, 0.3);
  computeLoadTorque(model, model.allEffects(), ws, ctx);
  JointVector rate;
  const JointVector qd = JointVector::Constant(6, 0.5);
  EXPECT_FALSE(loadTorqueRateAtCurrentPose(model, model.allEffects(), ws, ctx, qd, rate));
  EXPECT_TRUE(loadTorqueRateAtCurrentPose(model, without, ws, ctx, qd, rate));
}

}  // namespace jointcomp
