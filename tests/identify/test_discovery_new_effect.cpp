// Adding an effect touches its own files and the registry, nothing else: this test defines an effect type
// that jointcomp does not ship (a coupling of one joint's zero to the next joint's angle, as a belt or a
// parallelogram linkage makes), with its discovery family, registers both in a copy of the built-in
// registry, simulates campaigns whose truth carries it, and checks that discovery names it (type and
// joint), recovers its coefficient, and brings the held-out error to the noise floor; and that the
// parameter file written from the result reads back through the same registry.
#include <cmath>
#include <memory>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/effects/registry.hpp"
#include "model/experiment/campaign_simulation.hpp"
#include "model/identify/discovery.hpp"
#include "model/io/parameter_file.hpp"
#include "tests/identify/identify_test_support.hpp"

namespace jointcomp {
namespace {

using namespace identify_test;

// dq_j = c_j * command_{j+1}: the zero of joint j moves with the angle of the joint after it.
class CouplingEffect : public Effect {
public:
  static constexpr const char* kType = "test_coupling";
  CouplingEffect(const Robot& robot, std::vector<double> coupling) : coupling_(std::move(coupling)) {
    for (const Joint& joint : robot.joints) joint_names_.push_back(joint.name);
    if (coupling_.size() != joint_names_.size()) throw ParameterError("test_coupling: one value per joint");
  }
  static std::unique_ptr<Effect> fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain&,
                                          const std::string& path) {
    JsonFields fields(json, path);
    fields.text("type");
    std::vector<double> coupling = fields.numbers("coupling_rad_per_rad", robot.dof());
    fields.rejectUnknownKeys();
    return std::make_unique<CouplingEffect>(robot, coupling);
  }
  std::string type() const override { return kType; }
  EffectRole role() const override { return EffectRole::JointError; }
  bool dependsOnCommand() const override { return true; }
  void addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const override {
    for (int j = 0; j + 1 < dq.size(); ++j) dq[j] += coupling_[static_cast<std::size_t>(j)] * ctx.command[j + 1];
  }
  std::vector<std::string> parameterNames() const override {
    std::vector<std::string> names;
    for (const std::string& joint : joint_names_) names.push_back(joint + ".coupling_rad_per_rad");
    return names;
  }
  std::vector<double> parameters() const override { return coupling_; }
  void setParameters(const std::vector<double>& values) override { coupling_ = values; }
  nlohmann::json toJson() const override { return {{"type", kType}, {"coupling_rad_per_rad", coupling_}}; }
  std::unique_ptr<Effect> clone() const override { return std::make_unique<CouplingEffect>(*this); }

private:
  std::vector<std::string> joint_names_;
  std::vector<double> coupling_;
};

class CouplingDiscovery : public DiscoveryFamily {
public:
  std::string name() const override { return "coupling"; }
  void offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const override {
    if (joint < 0 || joint + 1 >= data.robot->dof()) return;
    DiscoveryCandidate candidate;
    candidate.type = name();
    candidate.joint = joint;
    candidate.columns = featureColumn(data, [&](int i) { return data.command[i][joint + 1]; });
    candidates.push_back(std::move(candidate));
  }
  std::unique_ptr<Effect> makeEffect(const DiscoveryData& data,
                                     const std::vector<FittedCandidate>& accepted) const override {
    std::vector<double> coupling(static_cast<std::size_t>(data.robot->dof()), 0.0);
    for (const FittedCandidate& a : accepted) coupling[static_cast<std::size_t>(a.candidate->joint)] += a.theta[0];
    return std::make_unique<CouplingEffect>(*data.robot, coupling);
  }
  std::vector<NamedEstimate> describe(const FittedCandidate& fitted, const JointErrorModel& model) const override {
    const std::string& joint = model.robot().joints[static_cast<std::size_t>(fitted.candidate->joint)].name;
    return {{joint + ".coupling_rad_per_rad", fitted.theta[0], fitted.sigma[0]}};
  }
};

EffectRegistry registryWithCoupling() {
  EffectRegistry registry = EffectRegistry::builtin();
  registry.addEffectType(CouplingEffect::kType, &CouplingEffect::fromJson);
  registry.addDiscoveryFamily(std::make_shared<CouplingDiscovery>());
  return registry;
}

TEST(DiscoveryNewEffect, ARegisteredTypeIsFoundNamedAndWritten) {
  const EffectRegistry registry = registryWithCoupling();
  const double truth_coupling = 1.5e-3;  // rad per rad: 0.15 mm per metre of reach per radian of joint 3
  JointErrorModel truth = rx170Model();
  std::vector<double> coupling(6, 0.0);
  coupling[1] = truth_coupling;
  truth.addEffect(std::make_unique<CouplingEffect>(truth.robot(), coupling));
  const MeasurementCampaign fit = randomCampaign(truth, 240, 31);
  const MeasurementCampaign held = randomCampaign(truth, 120, 1031);

  DiscoveryOptions options;
  options.max_harmonic_order = 3;
  options.max_steps = 3;
  options.registry = &registry;
  const DiscoveryResult result = discoverEffects(rx170Model(), {fit}, {held}, options);
  ASSERT_FALSE(result.steps.empty());
  const DiscoveryStep& first = result.steps.front();
  EXPECT_EQ(first.type, "coupling");
  EXPECT_EQ(first.joint, 1);
  ASSERT_EQ(first.parameters.size(), 1u);
  EXPECT_EQ(first.parameters[0].name, truth.robot().joints[1].name + ".coupling_rad_per_rad");
  EXPECT_NEAR(first.parameters[0].value, truth_coupling, 4.0 * first.parameters[0].sigma + 0.05 * truth_coupling);
  EXPECT_GT(result.initial.heldout[0].rms, 3.0 * result.noise_floor);  // the effect is visible before
  EXPECT_LT(result.final_state.heldout[0].rms, 1.3 * result.noise_floor);

  // The model discovery returns carries the effect, and its parameter file reads back through the registry.
  const int index = result.model.findEffect(CouplingEffect::kType);
  ASSERT_GE(index, 0);
  const std::string document = parametersToJson(result.model);
  const JointErrorModel reread =
      parseParameterSet(document, "discovered.json", result.model.sharedRobot(), registry).model;
  const int reread_index = reread.findEffect(CouplingEffect::kType);
  ASSERT_GE(reread_index, 0);
  EXPECT_EQ(reread.effect(reread_index).parameters(), result.model.effect(index).parameters());
  // Without the registration, the same file is refused with the type named.
  try {
    parseParameterSet(document, "discovered.json", result.model.sharedRobot(), EffectRegistry::builtin());
    ADD_FAILURE() << "the built-in registry accepted an unknown effect type";
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown effect type 'test_coupling'"), std::string::npos) << e.what();
  }
}

TEST(DiscoveryNewEffect, TheBuiltInVocabularyDoesNotChange) {
  // Registering into a copy leaves the built-in registry (shared by every caller) as it was.
  const EffectRegistry registry = registryWithCoupling();
  EXPECT_TRUE(registry.hasDiscoveryFamily("coupling"));
  EXPECT_FALSE(EffectRegistry::builtin().hasDiscoveryFamily("coupling"));
  EXPECT_EQ(registry.discoveryVocabulary().size(), EffectRegistry::builtin().discoveryVocabulary().size() + 1);
  EffectRegistry twice = registry;
  EXPECT_THROW(twice.addDiscoveryFamily(std::make_shared<CouplingDiscovery>()), InvalidArgument);
  EXPECT_THROW(twice.addEffectType(CouplingEffect::kType, &CouplingEffect::fromJson), InvalidArgument);
}

}  // namespace
}  // namespace jointcomp
