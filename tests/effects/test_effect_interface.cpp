// What every effect promises through the common interface: setParameters rejects what is out of range
// with a ParameterError naming the parameter (and leaves the effect as it was), clone() is a deep copy,
// the registry knows the effect types by name, and perturbedModel moves every parameter within its
// stated bounds, reproducibly from its seed.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "effects_test_support.hpp"
#include "model/common/errors.hpp"
#include "model/effects/compliance.hpp"
#include "model/effects/perturbation.hpp"
#include "model/effects/registry.hpp"
#include "model/effects/spring_balancer.hpp"
#include "model/effects/transmission_error.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

bool bitIdentical(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

// The joint errors of one error effect at a fixed context (load and motor angles set by hand).
JointVector errorsOf(const Effect& effect, const Robot& robot) {
  JointContext ctx(robot.dof());
  for (int j = 0; j < robot.dof(); ++j) {
    ctx.load_torque[j] = 100.0 * (j + 1);
    ctx.command[j] = 0.1 * (j + 1);
    ctx.motor[j] = 7.0 * (j + 1);
  }
  JointVector dq = JointVector::Zero(robot.dof());
  effect.addJointError(robot, ctx, dq);
  return dq;
}

// ---- setParameters --------------------------------------------------------------------------------

TEST(SetParameters, ComplianceTakesInfiniteStiffnessAsARigidJoint) {
  JointErrorModel model = effects_test::rx170Model();
  Effect& compliance = model.effect(model.findEffect(ComplianceEffect::kType));
  std::vector<double> values = compliance.parameters();
  values[2] = kInf;
  compliance.setParameters(values);
  JointContext ctx(6);
  ctx.load_torque = JointVector::Constant(6, 100.0);
  JointVector dq = JointVector::Zero(6);
  compliance.addJointError(model.robot(), ctx, dq);
  EXPECT_EQ(dq[2], 0.0);
  EXPECT_NE(dq[1], 0.0);
  // Written as null, and read back as rigid.
  const nlohmann::json written = compliance.toJson();
  EXPECT_TRUE(written.at("stiffness_nm_per_rad")[2].is_null());
}

TEST(SetParameters, ComplianceRejectsNanAndNonPositiveStiffnessNamingTheJoint) {
  JointErrorModel model = effects_test::rx170Model();
  Effect& compliance = model.effect(model.findEffect(ComplianceEffect::kType));
  const std::vector<double> good = compliance.parameters();
  for (double bad : {kNaN, 0.0, -1.0, -0.0, -kInf}) {
    std::vector<double> values = good;
    values[2] = bad;
    try {
      compliance.setParameters(values);
      ADD_FAILURE() << "accepted stiffness " << bad;
    } catch (const ParameterError& error) {
      EXPECT_THAT(error.what(), HasSubstr("joint_3")) << "value " << bad;
      EXPECT_THAT(error.what(), HasSubstr("stiffness")) << "value " << bad;
    }
  }
  std::vector<double> short_list(good.begin(), good.end() - 1);
  EXPECT_THROW(compliance.setParameters(short_list), ParameterError);
  EXPECT_TRUE(bitIdentical(compliance.parameters(), good));
}

TEST(SetParameters, ARejectedComplianceUpdateLeavesTheEffectAsItWas) {
  // A caller (identification) that catches the ParameterError must be left with the old effect: the
  // predicted errors, not only parameters(), must not change.
  JointErrorModel model = effects_test::rx170Model();
  Effect& compliance = model.effect(model.findEffect(ComplianceEffect::kType));
  const JointVector before = errorsOf(compliance, model.robot());
  std::vector<double> values = compliance.parameters();
  values[0] = 1.0;   // valid, but must not be applied
  values[3] = kNaN;  // the bad one
  EXPECT_THROW(compliance.setParameters(values), ParameterError);
  EXPECT_EQ(errorsOf(compliance, model.robot()), before)
      << "joint 1 error before " << before[0] << ", after " << errorsOf(compliance, model.robot())[0];
}

TEST(SetParameters, SpringBalancerRejectsNonFiniteAndNegativeValues) {
  JointErrorModel model = effects_test::rx170Model();
  Effect& spring = model.effect(model.findEffect(SpringBalancerEffect::kType));
  const std::vector<double> good = spring.parameters();
  const std::vector<std::string> names = spring.parameterNames();
  ASSERT_EQ(names.size(), good.size());
  for (std::size_t i = 0; i < good.size(); ++i) {
    std::vector<double> values = good;
    values[i] = kNaN;
    try {
      spring.setParameters(values);
      ADD_FAILURE() << "accepted NaN for " << names[i];
    } catch (const ParameterError& error) {
      EXPECT_THAT(error.what(), HasSubstr(names[i]));
    }
  }
  for (std::size_t i : {0u, 1u, 3u}) {  // anchor distances and stiffness
    std::vector<double> values = good;
    values[i] = -0.5;
    EXPECT_THROW(spring.setParameters(values), ParameterError) << names[i];
  }
  EXPECT_TRUE(bitIdentical(spring.parameters(), good));
}

TEST(SetParameters, ARejectedHarmonicUpdateLeavesTheEffectAsItWas) {
  JointErrorModel model = effects_test::rx170Model();
  Effect& te = model.effect(model.findEffect(TransmissionErrorEffect::kType));
  const std::vector<double> good = te.parameters();
  const JointVector before = errorsOf(te, model.robot());
  std::vector<double> values = good;
  values[0] *= 2.0;  // valid amplitude of harmonic 0
  values[3] = kNaN;  // phase of harmonic 1
  EXPECT_THROW(te.setParameters(values), ParameterError);
  EXPECT_TRUE(bitIdentical(te.parameters(), good)) << "amplitude 0 became " << te.parameters()[0];
  EXPECT_EQ(errorsOf(te, model.robot()), before);
}

TEST(SetParameters, AcceptedValuesAreReadBackBitForBit) {
  JointErrorModel model = effects_test::rx170Model();
  for (int i = 0; i < model.effectCount(); ++i) {
    Effect& effect = model.effect(i);
    std::vector<double> values = effect.parameters();
    for (double& v : values) v = v * 1.0625 + (v == 0.0 ? 0.001 : 0.0);
    effect.setParameters(values);
    EXPECT_TRUE(bitIdentical(effect.parameters(), values)) << effect.type();
  }
}

// ---- clone ------------------------------------------------------------------------------------------

TEST(Clone, IsADeepCopy) {
  const JointErrorModel model = effects_test::rx170Model();
  ASSERT_EQ(model.effectCount(), 3);
  for (int i = 0; i < model.effectCount(); ++i) {
    const Effect& original = model.effect(i);
    const std::vector<double> before = original.parameters();
    const JointVector errors_before = errorsOf(original, model.robot());
    std::unique_ptr<Effect> copy = original.clone();
    ASSERT_NE(copy.get(), &original);
    EXPECT_EQ(copy->type(), original.type());
    EXPECT_TRUE(bitIdentical(copy->parameters(), before));
    EXPECT_EQ(copy->toJson(), original.toJson());
    std::vector<double> changed = before;
    for (double& v : changed) v = 2.0 * v + 0.01;
    copy->setParameters(changed);
    copy->estimate_note = "changed in the clone";
    EXPECT_TRUE(bitIdentical(original.parameters(), before)) << original.type();
    EXPECT_EQ(errorsOf(original, model.robot()), errors_before) << original.type();
    EXPECT_NE(original.estimate_note, "changed in the clone");
    EXPECT_FALSE(bitIdentical(copy->parameters(), before));
  }
}

TEST(Clone, CopyingAModelCopiesItsEffects) {
  const JointErrorModel original = effects_test::rx170Model();
  JointErrorModel copy = original;
  for (int i = 0; i < copy.effectCount(); ++i) {
    ASSERT_NE(&copy.effect(i), &original.effect(i));
    std::vector<double> values = copy.effect(i).parameters();
    for (double& v : values) v = 3.0 * v + 0.02;
    copy.effect(i).setParameters(values);
  }
  const JointErrorModel fresh = effects_test::rx170Model();
  for (int i = 0; i < original.effectCount(); ++i) {
    EXPECT_TRUE(bitIdentical(original.effect(i).parameters(), fresh.effect(i).parameters())) << i;
  }
  // Assignment too.
  JointErrorModel assigned = fresh;
  assigned = original;
  assigned.effect(0).setParameters(copy.effect(0).parameters());
  EXPECT_TRUE(bitIdentical(original.effect(0).parameters(), fresh.effect(0).parameters()));
}

// ---- registry ---------------------------------------------------------------------------------------

TEST(Registry, ListsTheBuiltInEffects) {
  const std::vector<std::string> types = registeredEffectTypes();
  for (const char* expected : {"compliance", "spring_balancer", "transmission_error"}) {
    EXPECT_NE(std::find(types.begin(), types.end(), expected), types.end()) << expected;
  }
  // Each name once.
  for (std::size_t a = 0; a < types.size(); ++a) {
    for (std::size_t b = a + 1; b < types.size(); ++b) EXPECT_NE(types[a], types[b]);
  }
}

TEST(Registry, CreatesEachFileEffectByName) {
  const JointErrorModel model = effects_test::rx170Model();
  const nlohmann::json file = effects_test::rx170Json();
  for (std::size_t i = 0; i < file.at("effects").size(); ++i) {
    const nlohmann::json& json = file.at("effects")[i];
    std::unique_ptr<Effect> effect =
        createEffect(json, model.robot(), model.gears(), "test: effects[" + std::to_string(i) + "]");
    EXPECT_EQ(effect->type(), json.at("type").get<std::string>());
    EXPECT_TRUE(bitIdentical(effect->parameters(), model.effect(static_cast<int>(i)).parameters())) << effect->type();
  }
}

TEST(Registry, RejectsAnUnknownTypeNamingIt) {
  const JointErrorModel model = effects_test::rx170Model();
  const nlohmann::json json = {{"type", "backlash_of_the_moon"}, {"value", 1.0}};
  try {
    createEffect(json, model.robot(), model.gears(), "where.json: effects[4]");
    FAIL() << "an unknown type was accepted";
  } catch (const ParameterError& error) {
    EXPECT_THAT(error.what(), HasSubstr("backlash_of_the_moon"));
    EXPECT_THAT(error.what(), HasSubstr("where.json: effects[4]"));
  }
  EXPECT_THROW(createEffect(nlohmann::json::array(), model.robot(), model.gears(), "x"), ParameterError);
  EXPECT_THROW(createEffect(nlohmann::json{{"type", 3}}, model.robot(), model.gears(), "x"), ParameterError);
}

// ---- perturbation -----------------------------------------------------------------------------------

enum class Kind { Stiffness, Amplitude, Phase, Geometry };

// Classes by effect type and position (not by the parameter names the library uses).
Kind kindOf(const Effect& effect, std::size_t index) {
  if (effect.type() == "compliance") return Kind::Stiffness;
  if (effect.type() == "spring_balancer") return index == 3 ? Kind::Stiffness : Kind::Geometry;
  return index % 2 == 0 ? Kind::Amplitude : Kind::Phase;
}

std::vector<std::vector<double>> allParameters(const JointErrorModel& model) {
  std::vector<std::vector<double>> result;
  for (int i = 0; i < model.effectCount(); ++i) result.push_back(model.effect(i).parameters());
  return result;
}

// An effect type that overrides none of the fast paths (as a user's new type may not): the defaults give
// its value and slope as the two calls do, keep no continuation, mark every joint, and refuse the higher
// derivatives with a message naming it.
class RippleOfTheCommand : public Effect {
public:
  std::string type() const override { return "ripple"; }
  EffectRole role() const override { return EffectRole::JointError; }
  bool dependsOnCommand() const override { return true; }
  void addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const override {
    for (int j = 0; j < dq.size(); ++j) dq[j] += 1e-5 * std::sin(3.0 * ctx.motor[j]);
  }
  bool addMotorSlope(const Robot&, const JointContext& ctx, JointVector& slope) const override {
    for (int j = 0; j < slope.size(); ++j) slope[j] += 3e-5 * std::cos(3.0 * ctx.motor[j]);
    return true;
  }
  std::vector<std::string> parameterNames() const override { return {}; }
  std::vector<double> parameters() const override { return {}; }
  void setParameters(const std::vector<double>&) override {}
  nlohmann::json toJson() const override { return {{"type", "ripple"}}; }
  std::unique_ptr<Effect> clone() const override { return std::make_unique<RippleOfTheCommand>(*this); }
};

TEST(EffectInterface, DefaultsOfTheFastPathsAreTheTwoCalls) {
  const JointErrorModel model = effects_test::rx170Model();
  const RippleOfTheCommand ripple;
  const Effect& effect = ripple;
  JointContext ctx(6);
  for (int j = 0; j < 6; ++j) ctx.motor[j] = 10.0 * j - 17.0;
  JointVector dq = JointVector::Constant(6, 1e-3), slope = JointVector::Constant(6, -2e-3);
  JointVector direct = dq, direct_slope = slope;
  EXPECT_TRUE(effect.continueJointErrorAndMotorSlope(model.robot(), ctx, nullptr, true, dq, slope));
  effect.addJointError(model.robot(), ctx, direct);
  effect.addMotorSlope(model.robot(), ctx, direct_slope);
  EXPECT_EQ(dq, direct);
  EXPECT_EQ(slope, direct_slope);
  EXPECT_EQ(effect.continuationSize(), 0u);
  EXPECT_FALSE(effect.knowsMotorDerivatives());
  bool joints[kMaxJoints] = {};
  effect.markCommandJoints(6, joints);
  for (int j = 0; j < 6; ++j) EXPECT_TRUE(joints[j]);
  JointVector second = JointVector::Zero(6), third = JointVector::Zero(6);
  try {
    effect.continueJointErrorAndMotorDerivatives(model.robot(), ctx, nullptr, false, dq, slope, second, third);
    FAIL() << "no error";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("ripple"));
  }
}

// The joint springs are found by their role, wherever they stand in the model's list: their stiffness is
// the compliance effect's; a model without them has rigid joints (+infinity) and says so with -1.
TEST(EffectInterface, TheJointSpringsAreFoundByTheirRole) {
  const JointErrorModel model = effects_test::rx170Model();
  const int springs = model.jointSprings();
  ASSERT_GE(springs, 0);
  EXPECT_EQ(model.effect(springs).type(), ComplianceEffect::kType);
  const auto& compliance = static_cast<const ComplianceEffect&>(model.effect(springs));
  const JointVector stiffness = model.jointStiffness();
  for (int j = 0; j < 6; ++j) EXPECT_EQ(stiffness[j], compliance.stiffness(j));
  // The same effects in reverse order, and without the springs.
  std::vector<std::unique_ptr<Effect>> reversed, without;
  for (int i = model.effectCount() - 1; i >= 0; --i) {
    reversed.push_back(model.effect(i).clone());
    if (i != springs) without.push_back(model.effect(i).clone());
  }
  const JointErrorModel turned(model.sharedRobot(), model.gears(), std::move(reversed));
  EXPECT_EQ(turned.jointSprings(), model.effectCount() - 1 - springs);
  EXPECT_EQ(turned.jointStiffness(), stiffness);
  const JointErrorModel rigid(model.sharedRobot(), model.gears(), std::move(without));
  EXPECT_EQ(rigid.jointSprings(), -1);
  EXPECT_EQ(rigid.jointStiffness(), JointVector::Constant(6, kInf));
}

TEST(Perturbation, SameSeedSameParametersOtherSeedOthers) {
  const JointErrorModel nominal = effects_test::rx170Model();
  PerturbationSpec spec;
  const auto a = allParameters(perturbedModel(nominal, spec));
  const auto b = allParameters(perturbedModel(nominal, spec));
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(bitIdentical(a[i], b[i])) << "effect " << i;
  spec.seed += 1;
  const auto c = allParameters(perturbedModel(nominal, spec));
  int differing = 0;
  int total = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t k = 0; k < a[i].size(); ++k) {
      differing += a[i][k] != c[i][k] ? 1 : 0;
      ++total;
    }
  }
  EXPECT_GT(differing, total / 2);
}

TEST(Perturbation, StaysWithinTheStatedBoundsAndMovesEveryKind) {
  const JointErrorModel nominal = effects_test::rx170Model();
  for (std::uint64_t seed : {1ULL, 2012ULL, 123456789ULL}) {
    PerturbationSpec spec;
    spec.seed = seed;
    const JointErrorModel truth = perturbedModel(nominal, spec);
    ASSERT_EQ(truth.effectCount(), nominal.effectCount());
    int moved[4] = {0, 0, 0, 0};
    for (int i = 0; i < nominal.effectCount(); ++i) {
      const std::vector<double> p0 = nominal.effect(i).parameters();
      const std::vector<double> p = truth.effect(i).parameters();
      ASSERT_EQ(p.size(), p0.size());
      for (std::size_t k = 0; k < p.size(); ++k) {
        const Kind kind = kindOf(nominal.effect(i), k);
        const std::string what = nominal.effect(i).parameterNames()[k] + " seed " + std::to_string(seed);
        if (p[k] != p0[k]) ++moved[static_cast<int>(kind)];
        switch (kind) {
          case Kind::Stiffness:
            EXPECT_LE(std::abs(p[k] - p0[k]), spec.stiffness_relative * std::abs(p0[k]) * (1 + 1e-15)) << what;
            break;
          case Kind::Amplitude:
            EXPECT_LE(std::abs(p[k] - p0[k]), spec.amplitude_relative * std::abs(p0[k]) * (1 + 1e-15)) << what;
            break;
          case Kind::Phase: EXPECT_LE(std::abs(p[k] - p0[k]), spec.phase_absolute_rad * (1 + 1e-15)) << what; break;
          case Kind::Geometry:
            EXPECT_LE(std::abs(p[k] - p0[k]), spec.geometry_relative * std::abs(p0[k]) * (1 + 1e-15)) << what;
            break;
        }
      }
    }
    for (int kind = 0; kind < 4; ++kind) EXPECT_GT(moved[kind], 0) << "kind " << kind << ", seed " << seed;
  }
}

TEST(Perturbation, ZeroBoundsGiveTheNominalModel) {
  const JointErrorModel nominal = effects_test::rx170Model();
  PerturbationSpec spec;
  spec.stiffness_relative = 0.0;
  spec.amplitude_relative = 0.0;
  spec.phase_absolute_rad = 0.0;
  spec.geometry_relative = 0.0;
  const JointErrorModel truth = perturbedModel(nominal, spec);
  for (int i = 0; i < nominal.effectCount(); ++i) {
    EXPECT_TRUE(bitIdentical(truth.effect(i).parameters(), nominal.effect(i).parameters())) << i;
  }
}

TEST(Perturbation, LeavesTheNominalModelAlone) {
  const JointErrorModel nominal = effects_test::rx170Model();
  const auto before = allParameters(nominal);
  const JointErrorModel truth = perturbedModel(nominal, PerturbationSpec{});
  const auto after = allParameters(nominal);
  for (std::size_t i = 0; i < before.size(); ++i) EXPECT_TRUE(bitIdentical(before[i], after[i]));
  EXPECT_EQ(&truth.robot(), &nominal.robot());
}

}  // namespace
}  // namespace jointcomp
