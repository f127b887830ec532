// The "offset" effect (model/effects/joint_offset.hpp): dq = constant per joint, named parameters
// "joint_i.offset_rad", known to the registry, read and written by the parameter file.
#include <limits>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "calibration_test_support.hpp"
#include "model/common/errors.hpp"
#include "model/effects/joint_offset.hpp"
#include "model/effects/registry.hpp"
#include "model/io/parameter_file.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

TEST(JointOffsetEffect, AddsAConstantPerJoint) {
  const auto robot = calibration_test::ur10();
  const JointOffsetEffect effect(*robot, {0.1, -0.2, 0.0, 1e-3, 0.0, -5e-4});
  EXPECT_EQ(effect.type(), "offset");
  EXPECT_EQ(effect.role(), EffectRole::JointError);
  EXPECT_FALSE(effect.dependsOnCommand());
  JointContext ctx(6);
  ctx.load_torque.setConstant(100.0);
  JointVector dq = JointVector::Constant(6, 1.0);
  effect.addJointError(*robot, ctx, dq);
  EXPECT_DOUBLE_EQ(dq[0], 1.1);
  EXPECT_DOUBLE_EQ(dq[1], 0.8);
  EXPECT_DOUBLE_EQ(dq[5], 1.0 - 5e-4);
  EXPECT_EQ(effect.parameterNames().front(), "joint_1.offset_rad");
  EXPECT_EQ(effect.parameterNames().back(), "joint_6.offset_rad");
}

TEST(JointOffsetEffect, RejectsBadValuesNamingTheJointAndKeepsTheOldOnes) {
  const auto robot = calibration_test::ur10();
  JointOffsetEffect effect(*robot, {0, 0, 0, 0, 0, 0});
  std::vector<double> bad = {0, 0, std::numeric_limits<double>::quiet_NaN(), 0, 0, 0};
  try {
    effect.setParameters(bad);
    FAIL();
  } catch (const ParameterError& error) {
    EXPECT_THAT(error.what(), HasSubstr("joint_3.offset_rad"));
  }
  EXPECT_EQ(effect.parameters(), std::vector<double>(6, 0.0));
  EXPECT_THROW(effect.setParameters({0, 0}), ParameterError);
  EXPECT_THROW(JointOffsetEffect(*robot, {0.0}), ParameterError);
}

TEST(JointOffsetEffect, IsInTheRegistryAndTheParameterFile) {
  const auto robot = calibration_test::ur10();
  const std::vector<std::string> types = registeredEffectTypes();
  EXPECT_NE(std::find(types.begin(), types.end(), "offset"), types.end());
  const std::string text = R"({"format": "jointcomp-parameters/1", "robot": "ur10",
    "effects": [{"type": "offset", "offset_rad": [0.001, -0.002, 0.003, 0, 0, 0.5], "estimate": "test"}]})";
  const JointErrorModel model = parseParameters(text, "offsets.json", robot);
  ASSERT_EQ(model.effectCount(), 1);
  EXPECT_EQ(model.effect(0).parameters(), (std::vector<double>{0.001, -0.002, 0.003, 0, 0, 0.5}));
  const JointErrorModel again = parseParameters(parametersToJson(model), "again.json", robot);
  EXPECT_EQ(again.effect(0).parameters(), model.effect(0).parameters());
  EXPECT_EQ(again.effect(0).estimate_note, "test");

  const std::string short_list = R"({"format": "jointcomp-parameters/1", "robot": "ur10",
    "effects": [{"type": "offset", "offset_rad": [0.001]}]})";
  try {
    parseParameters(short_list, "short.json", robot);
    FAIL();
  } catch (const ParameterError& error) {
    EXPECT_THAT(error.what(), HasSubstr("offset_rad"));
  }
  const std::string unknown_key = R"({"format": "jointcomp-parameters/1", "robot": "ur10",
    "effects": [{"type": "offset", "offset_rad": [0, 0, 0, 0, 0, 0], "offset_deg": 1}]})";
  EXPECT_THROW(parseParameters(unknown_key, "unknown.json", robot), ParameterError);
}

}  // namespace
}  // namespace jointcomp
