// Transmission error and the gear train against a hand-written model built from the parameter file read
// as plain JSON: motor = G q with G = diag(product of the stage ratios) plus the 5-6 coupling, the input
// of stage 2 turning at motor / (first ratio), and the error the sum of the file's harmonics.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "effects_test_support.hpp"
#include "model/common/errors.hpp"
#include "model/effects/periodic_table.hpp"
#include "model/effects/transmission_error.hpp"
#include "model/io/parameter_file.hpp"

namespace jointcomp {
namespace {

using effects_test::kDegree;

struct HandHarmonic {
  int joint;
  std::string of;
  double cycles;
  double amplitude_rad;
  double phase;
};

struct HandModel {
  std::vector<std::vector<double>> ratios;  // per joint, motor side first
  Eigen::MatrixXd g;                        // motor = g * q
  std::vector<HandHarmonic> harmonics;
};

HandModel handModel(const Robot& robot) {
  const nlohmann::json file = effects_test::rx170Json();
  HandModel hand;
  const int n = robot.dof();
  hand.ratios.resize(n);
  hand.g = Eigen::MatrixXd::Zero(n, n);
  for (const auto& entry : file.at("gears").at("joints")) {
    const int j = effects_test::jointByName(robot, entry.at("joint").get<std::string>());
    hand.ratios[j] = entry.at("stage_ratios").get<std::vector<double>>();
    double total = 1.0;
    for (double r : hand.ratios[j]) total *= r;
    hand.g(j, j) = total;
  }
  for (const auto& entry : file.at("gears").at("coupling")) {
    const int motor = effects_test::jointByName(robot, entry.at("motor_of").get<std::string>());
    const int joint = effects_test::jointByName(robot, entry.at("joint").get<std::string>());
    hand.g(motor, joint) += entry.at("motor_rad_per_joint_rad").get<double>();
  }
  for (const auto& effect : file.at("effects")) {
    if (effect.at("type") != "transmission_error") continue;
    for (const auto& h : effect.at("harmonics")) {
      hand.harmonics.push_back({effects_test::jointByName(robot, h.at("joint").get<std::string>()),
                                h.at("of").get<std::string>(), h.at("cycles_per_revolution").get<double>(),
                                h.at("amplitude_deg").get<double>() * kDegree, h.at("phase_rad").get<double>()});
    }
  }
  return hand;
}

// Angle of the named part of joint j's train: the motor, the input of stage k, or the output.
double partAngle(const HandModel& hand, int j, const std::string& of, const Eigen::VectorXd& motor) {
  if (of == "motor") return motor[j];
  double divisor = 1.0;
  if (of == "output") {
    for (double r : hand.ratios[j]) divisor *= r;
    return motor[j] / divisor;
  }
  const int stage = std::stoi(of.substr(6));  // "stage_k"
  for (int s = 0; s < stage - 1; ++s) divisor *= hand.ratios[j][s];
  return motor[j] / divisor;
}

Eigen::VectorXd handError(const HandModel& hand, const Eigen::VectorXd& command) {
  const Eigen::VectorXd motor = hand.g * command;
  Eigen::VectorXd dq = Eigen::VectorXd::Zero(command.size());
  for (const HandHarmonic& h : hand.harmonics) {
    dq[h.joint] += h.amplitude_rad * std::sin(h.cycles * partAngle(hand, h.joint, h.of, motor) + h.phase);
  }
  return dq;
}

TEST(GearTrain, RatiosAndCouplingAreThoseOfTheFile) {
  const JointErrorModel model = effects_test::rx170Model();
  const HandModel hand = handModel(model.robot());
  for (int j = 0; j < model.robot().dof(); ++j) {
    EXPECT_EQ(model.gears().stageRatios(j), hand.ratios[j]) << "joint " << j;
  }
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) EXPECT_EQ(model.gears().motorFromJoint()(r, c), hand.g(r, c)) << r << "," << c;
  }
  // The Staubli wrist: motor 6 turns with joint 5 too.
  EXPECT_NE(hand.g(5, 4), 0.0);
}

TEST(GearTrain, MotorAnglesIncludeTheWristCoupling) {
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  const HandModel hand = handModel(robot);
  std::mt19937 rng(8u);
  for (int sample = 0; sample < 50; ++sample) {
    JointContext ctx(robot.dof());
    ctx.command = effects_test::randomConfiguration(robot, rng);
    updateMotorAngles(model, ctx);
    const Eigen::VectorXd expected = hand.g * Eigen::VectorXd(ctx.command);
    for (int j = 0; j < robot.dof(); ++j) {
      EXPECT_NEAR(ctx.motor[j], expected[j], 1e-12 * std::abs(expected[j]) + 1e-15) << "joint " << j;
    }
    // Joint 6's motor, written out: ratio * (q6 + q5).
    EXPECT_NEAR(ctx.motor[5], 28.0 * (ctx.command[5] + ctx.command[4]), 1e-12);
  }
}

TEST(TransmissionError, IsTheFilesHarmonicSum) {
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  const HandModel hand = handModel(robot);
  ASSERT_EQ(hand.harmonics.size(), 4u);
  const Effect& effect = model.effect(model.findEffect(TransmissionErrorEffect::kType));
  EXPECT_TRUE(effect.dependsOnCommand());
  std::mt19937 rng(21u);
  double largest = 0.0;
  for (int sample = 0; sample < 200; ++sample) {
    JointContext ctx(robot.dof());
    ctx.command = effects_test::randomConfiguration(robot, rng);
    ctx.q = effects_test::randomConfiguration(robot, rng);  // the error follows the command, not the link
    ctx.motor = JointVector(hand.g * Eigen::VectorXd(ctx.command));
    JointVector dq = JointVector::Zero(robot.dof());
    effect.addJointError(robot, ctx, dq);
    const Eigen::VectorXd expected = handError(hand, ctx.command);
    for (int j = 0; j < robot.dof(); ++j) EXPECT_NEAR(dq[j], expected[j], 1e-15) << "joint " << j;
    largest = std::max(largest, dq.cwiseAbs().maxCoeff());
  }
  // A few thousandths of a degree, as the paper says.
  EXPECT_GT(largest, 0.001 * kDegree);
  EXPECT_LT(largest, 0.01 * kDegree);
}

TEST(TransmissionError, FundamentalOfJoint2RepeatsTwicePerTurnOfTheStage2Input) {
  // Turning the stage-2 input of joint 2 by half a revolution (2 pi * 3 motor radians, i.e.
  // 2 pi * 3 / 120 joint radians) leaves the 2-cycle harmonic unchanged and flips the 1-cycle one.
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  const HandModel hand = handModel(robot);
  const double first_ratio = hand.ratios[1][0];
  const double half_turn = effects_test::kPi * first_ratio / hand.g(1, 1);
  std::vector<Harmonic> two_cycles;
  for (const Harmonic& h :
       dynamic_cast<const TransmissionErrorEffect&>(model.effect(model.findEffect(TransmissionErrorEffect::kType)))
           .harmonics()) {
    if (h.joint == 1 && h.cycles_per_revolution == 2.0) two_cycles.push_back(h);
  }
  ASSERT_EQ(two_cycles.size(), 1u);
  const TransmissionErrorEffect fundamental(robot, model.gears(), two_cycles);
  JointContext ctx(robot.dof());
  ctx.command[1] = 0.3;
  updateMotorAngles(model, ctx);
  JointVector before = JointVector::Zero(robot.dof());
  fundamental.addJointError(robot, ctx, before);
  ctx.command[1] += half_turn;
  updateMotorAngles(model, ctx);
  JointVector after = JointVector::Zero(robot.dof());
  fundamental.addJointError(robot, ctx, after);
  EXPECT_NE(before[1], 0.0);
  EXPECT_NEAR(after[1], before[1], 1e-15);
}

TEST(TransmissionError, MotorAndOutputHarmonicsFollowTheirParts) {
  // Harmonics on other parts than the file uses: the motor of joint 6 (which joint 5 turns too) and the
  // output of joint 2.
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  HandModel hand = handModel(robot);
  Harmonic motor6;
  motor6.joint = 5;
  motor6.stage = 1;
  motor6.cycles_per_revolution = 1.0;
  motor6.amplitude_rad = 2e-5;
  motor6.phase_rad = 0.3;
  Harmonic output2;
  output2.joint = 1;
  output2.stage = model.gears().stageCount(1) + 1;
  output2.cycles_per_revolution = 3.0;
  output2.amplitude_rad = 4e-5;
  output2.phase_rad = -1.0;
  const TransmissionErrorEffect effect(robot, model.gears(), {motor6, output2});
  EXPECT_EQ(effect.partName(5, 1), "motor");
  EXPECT_EQ(effect.partName(1, output2.stage), "output");
  EXPECT_EQ(effect.partName(1, 2), "stage_2");
  hand.harmonics = {{5, "motor", 1.0, 2e-5, 0.3}, {1, "output", 3.0, 4e-5, -1.0}};
  std::mt19937 rng(4u);
  for (int sample = 0; sample < 50; ++sample) {
    JointContext ctx(robot.dof());
    ctx.command = effects_test::randomConfiguration(robot, rng);
    updateMotorAngles(model, ctx);
    JointVector dq = JointVector::Zero(robot.dof());
    effect.addJointError(robot, ctx, dq);
    const Eigen::VectorXd expected = handError(hand, ctx.command);
    for (int j = 0; j < robot.dof(); ++j) EXPECT_NEAR(dq[j], expected[j], 1e-15) << "joint " << j;
    // The output of joint 2 is the joint itself.
    EXPECT_NEAR(dq[1], 4e-5 * std::sin(3.0 * ctx.command[1] - 1.0), 1e-15);
  }
}

TEST(TransmissionError, ParametersAreAmplitudesInRadiansAndPhases) {
  const JointErrorModel model = effects_test::rx170Model();
  const HandModel hand = handModel(model.robot());
  const Effect& effect = model.effect(model.findEffect(TransmissionErrorEffect::kType));
  const std::vector<double> values = effect.parameters();
  const std::vector<std::string> names = effect.parameterNames();
  ASSERT_EQ(values.size(), 2 * hand.harmonics.size());
  ASSERT_EQ(names.size(), values.size());
  for (std::size_t i = 0; i < hand.harmonics.size(); ++i) {
    EXPECT_NEAR(values[2 * i], hand.harmonics[i].amplitude_rad, 1e-20) << names[2 * i];
    EXPECT_EQ(values[2 * i + 1], hand.harmonics[i].phase) << names[2 * i + 1];
    EXPECT_NE(names[2 * i].find("amplitude_rad"), std::string::npos) << names[2 * i];
    EXPECT_NE(names[2 * i + 1].find("phase_rad"), std::string::npos) << names[2 * i + 1];
  }
  // Names are unique, or identification could not tell the parameters apart.
  for (std::size_t a = 0; a < names.size(); ++a) {
    for (std::size_t b = a + 1; b < names.size(); ++b) EXPECT_NE(names[a], names[b]);
  }
}

// The compensator's evaluation: libm at the anchors, then the angle-addition formula at commands moved by
// 1e-9 .. 1e-1 rad of motor angle, which moves the phases by 1/3 to 0.8 times that: up to 1e-3 the short
// Taylor series, 5e-2 the long one, 1e-1 re-anchors some (beyond kSinCosNearAnchor); against addJointError and
// addMotorSlope at each command.
TEST(TransmissionError, AnchoredValueAndSlopeMatchTheDirectSums) {
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  const auto& effect =
      dynamic_cast<const TransmissionErrorEffect&>(model.effect(model.findEffect(TransmissionErrorEffect::kType)));
  std::vector<SinCosAnchor> anchors(effect.harmonics().size());
  std::mt19937 rng(29u);
  std::uniform_real_distribution<double> motor_angle(-300.0, 300.0);
  int reanchored = 0;
  for (int sample = 0; sample < 40; ++sample) {
    JointContext ctx(robot.dof());
    for (int j = 0; j < robot.dof(); ++j) ctx.motor[j] = motor_angle(rng);
    for (const double move : {0.0, 1e-9, 1e-6, 1e-3, 1e-2, 5e-2, 1e-1}) {
      JointContext moved = ctx;
      for (int j = 0; j < robot.dof(); ++j) moved.motor[j] += (j % 2 == 0 ? move : -move);
      const std::vector<SinCosAnchor> before = anchors;
      JointVector dq = JointVector::Zero(robot.dof()), slope = JointVector::Zero(robot.dof());
      effect.continueJointErrorAndMotorSlope(robot, moved, anchors.data(), move != 0.0, dq, slope);
      for (std::size_t i = 0; i < anchors.size(); ++i) reanchored += move != 0.0 && anchors[i].angle != before[i].angle;
      JointVector direct = JointVector::Zero(robot.dof()), direct_slope = JointVector::Zero(robot.dof());
      effect.addJointError(robot, moved, direct);
      ASSERT_TRUE(effect.addMotorSlope(robot, moved, direct_slope));
      for (int j = 0; j < robot.dof(); ++j) {
        // The phases differ from addJointError's by their rounding (1e-14 rad at 100 rad): about 1e-18 in
        // both, against values of 1e-4 rad and 5e-5 rad per motor radian (a slope's two harmonics may cancel).
        EXPECT_NEAR(dq[j], direct[j], 1e-17) << "sample " << sample << ", move " << move << ", joint " << j;
        EXPECT_NEAR(slope[j], direct_slope[j], 1e-17) << "sample " << sample << ", move " << move << ", joint " << j;
      }
    }
  }
  EXPECT_GT(reanchored, 0);  // the largest moves did leave the anchors
}

// The compensator's higher-order first step reads the error's second and third derivatives by the motor
// angle: central differences of the slope and of the second derivative, at random motor angles; its value
// and slope are addJointErrorAndMotorSlope's, bit for bit.
TEST(TransmissionError, SecondAndThirdDerivativesAreDifferencesOfTheSlopeAndTheSecond) {
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  const auto& effect =
      dynamic_cast<const TransmissionErrorEffect&>(model.effect(model.findEffect(TransmissionErrorEffect::kType)));
  const int n = robot.dof();
  std::vector<SinCosAnchor> anchors(effect.harmonics().size());
  struct Derivatives {
    JointVector dq, slope, second, third;
  };
  const auto derivatives = [&](const JointContext& ctx) {
    Derivatives d{JointVector::Zero(n), JointVector::Zero(n), JointVector::Zero(n), JointVector::Zero(n)};
    effect.continueJointErrorAndMotorDerivatives(robot, ctx, anchors.data(), false, d.dq, d.slope, d.second, d.third);
    return d;
  };
  std::mt19937 rng(41u);
  std::uniform_real_distribution<double> motor_angle(-300.0, 300.0);
  int curved = 0;
  for (int sample = 0; sample < 40; ++sample) {
    JointContext ctx(n);
    for (int j = 0; j < n; ++j) ctx.motor[j] = motor_angle(rng);
    const Derivatives at = derivatives(ctx);
    JointVector dq = JointVector::Zero(n), slope = JointVector::Zero(n);
    effect.continueJointErrorAndMotorSlope(robot, ctx, anchors.data(), false, dq, slope);
    EXPECT_EQ(at.dq, dq) << "sample " << sample;
    EXPECT_EQ(at.slope, slope) << "sample " << sample;
    for (int j = 0; j < n; ++j) {
      constexpr double kStep = 1e-4;  // rad of motor angle
      JointContext ahead = ctx, behind = ctx;
      ahead.motor[j] += kStep;
      behind.motor[j] -= kStep;
      const Derivatives up = derivatives(ahead), down = derivatives(behind);
      const double second = (up.slope[j] - down.slope[j]) / (2 * kStep);
      const double third = (up.second[j] - down.second[j]) / (2 * kStep);
      EXPECT_NEAR(at.second[j], second, 1e-6 * std::abs(second) + 1e-15) << "sample " << sample << ", joint " << j;
      EXPECT_NEAR(at.third[j], third, 1e-6 * std::abs(third) + 1e-15) << "sample " << sample << ", joint " << j;
      curved += at.second[j] != 0.0 && at.third[j] != 0.0;
    }
  }
  EXPECT_GT(curved, 40);  // the harmonics' joints do curve (1-3 on the RX170)
}

// The plant's one-pass evaluation gives addJointError's and addMotorSlope's bits (the plant's stored
// regressions rest on it), at random motor angles over many turns, added onto values already there.
TEST(TransmissionError, OnePassValueAndSlopeAreTheTwoCallsBitForBit) {
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  const auto& effect =
      dynamic_cast<const TransmissionErrorEffect&>(model.effect(model.findEffect(TransmissionErrorEffect::kType)));
  std::mt19937 rng(1717u);
  std::uniform_real_distribution<double> motor_angle(-300.0, 300.0);
  for (int sample = 0; sample < 200; ++sample) {
    JointContext ctx(robot.dof());
    JointVector start(robot.dof());
    for (int j = 0; j < robot.dof(); ++j) {
      ctx.motor[j] = motor_angle(rng);
      start[j] = 1e-3 * motor_angle(rng);
    }
    JointVector dq = start, slope = -start;
    effect.addJointErrorAndMotorSlope(robot, ctx, dq, slope);
    JointVector direct = start, direct_slope = -start;
    effect.addJointError(robot, ctx, direct);
    ASSERT_TRUE(effect.addMotorSlope(robot, ctx, direct_slope));
    EXPECT_EQ(dq, direct) << "sample " << sample;
    EXPECT_EQ(slope, direct_slope) << "sample " << sample;
    EXPECT_NE(dq, start);  // the harmonics did add something
  }
}

}  // namespace
}  // namespace jointcomp

namespace jointcomp {
namespace {

// The slopes the plant uses (d error_j / d motor_j) against central differences of the error itself,
// for the shipped harmonics and for a periodic table, at random motor angles.
// A parameter file's harmonics are bounded (issue 41: 100k harmonics in a 14.8 MB file kept `paper` busy
// for minutes; an order of 1e9 ended in "compensation did not converge" without naming it).
TEST(TransmissionError, TooManyHarmonicsOrAnAbsurdOrderAreRefusedNamingThem) {
  nlohmann::json file = effects_test::rx170Json();
  nlohmann::json* effect = nullptr;
  for (auto& e : file.at("effects"))
    if (e.at("type") == "transmission_error") effect = &e;
  ASSERT_NE(effect, nullptr);
  const nlohmann::json one = effect->at("harmonics").at(0);
  nlohmann::json many = nlohmann::json::array();
  for (std::size_t i = 0; i <= kMaxHarmonics; ++i) many.push_back(one);
  nlohmann::json crowded = file;
  for (auto& e : crowded.at("effects"))
    if (e.at("type") == "transmission_error") e["harmonics"] = many;
  try {
    parseParameters(crowded.dump(), "crowded.json", effects_test::rx170());
    ADD_FAILURE() << "1025 harmonics were read";
  } catch (const ParameterError& error) {
    EXPECT_NE(std::string(error.what()).find("has 1025 entries; at most 1024 are read"), std::string::npos)
        << error.what();
  }
  effect->at("harmonics").at(0)["cycles_per_revolution"] = 1e9;
  try {
    parseParameters(file.dump(), "order.json", effects_test::rx170());
    ADD_FAILURE() << "an order of 1e9 was read";
  } catch (const ParameterError& error) {
    EXPECT_NE(std::string(error.what()).find("harmonics[0]"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("is beyond 10000 cycles per revolution"), std::string::npos)
        << error.what();
  }
}

TEST(MotorSlope, MatchesCentralDifferencesOfTheJointError) {
  JointErrorModel model = effects_test::rx170Model();
  PeriodicTable table;
  table.joint = 3;
  table.stage = 1;
  for (int k = 0; k < 12; ++k) table.coefficients_rad.push_back(2e-5 * std::sin(1.3 * k) + 1e-5 * (k % 3));
  model.addEffect(
      std::make_unique<PeriodicTableEffect>(model.robot(), model.gears(), std::vector<PeriodicTable>{table}));
  const Robot& robot = model.robot();
  std::mt19937 rng(23u);
  std::uniform_real_distribution<double> motor_angle(-300.0, 300.0);
  for (const char* type : {TransmissionErrorEffect::kType, PeriodicTableEffect::kType}) {
    const Effect& effect = model.effect(model.findEffect(type));
    for (int sample = 0; sample < 50; ++sample) {
      JointContext ctx(robot.dof());
      for (int j = 0; j < robot.dof(); ++j) ctx.motor[j] = motor_angle(rng);
      JointVector slope = JointVector::Zero(robot.dof());
      ASSERT_TRUE(effect.addMotorSlope(robot, ctx, slope));
      for (int j = 0; j < robot.dof(); ++j) {
        constexpr double kStep = 1e-5;  // rad of motor angle
        JointContext ahead = ctx, behind = ctx;
        ahead.motor[j] += kStep;
        behind.motor[j] -= kStep;
        JointVector up = JointVector::Zero(robot.dof()), down = JointVector::Zero(robot.dof());
        effect.addJointError(robot, ahead, up);
        effect.addJointError(robot, behind, down);
        const double numeric = (up[j] - down[j]) / (2 * kStep);
        EXPECT_NEAR(slope[j], numeric, 1e-7 * (1.0 + std::abs(numeric))) << type << " joint " << j;
        for (int i = 0; i < robot.dof(); ++i) {
          if (i != j) {
            EXPECT_EQ(up[i], down[i]) << type << ": joint " << i << "'s error moved with motor " << j;
          }
        }
      }
    }
  }
}
}  // namespace
}  // namespace jointcomp
