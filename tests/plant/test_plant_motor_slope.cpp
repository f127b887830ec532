// The plant takes the transmission error's slope E = de/dp from the effects (diag(de_j/dm_j) G) instead of
// twelve extra evaluations by central differences. The right-hand side with the effects' slopes equals,
// to the differences' own accuracy, the one of a plant whose transmission error hides its slope (the same
// effect wrapped, so the plant falls back to central differences), at random states with the drives
// moving; and a model whose effects all give their slope takes the analytic path.
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "tests/plant/plant_test_support.hpp"

#include "model/effects/transmission_error.hpp"
#include "model/io/parameter_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp {
namespace {

using namespace plant_testing;

// An effect that is another one in all but its slope: the plant must differentiate it numerically.
class SlopeHidden : public Effect {
public:
  explicit SlopeHidden(std::unique_ptr<Effect> inner) : inner_(std::move(inner)) {}
  std::string type() const override { return inner_->type(); }
  EffectRole role() const override { return inner_->role(); }
  bool dependsOnCommand() const override { return inner_->dependsOnCommand(); }
  void addJointError(const Robot& robot, const JointContext& ctx, JointVector& dq) const override {
    inner_->addJointError(robot, ctx, dq);
  }
  std::vector<std::string> parameterNames() const override { return inner_->parameterNames(); }
  std::vector<double> parameters() const override { return inner_->parameters(); }
  void setParameters(const std::vector<double>& values) override { inner_->setParameters(values); }
  nlohmann::json toJson() const override { return inner_->toJson(); }
  std::unique_ptr<Effect> clone() const override { return std::make_unique<SlopeHidden>(inner_->clone()); }

private:
  std::unique_ptr<Effect> inner_;
};

TEST(PlantMotorSlope, AnalyticSlopeMatchesCentralDifferencesInTheRightHandSide) {
  const JointErrorModel model = loadParameterFile(kParameters, rx170());
  const int te = model.findEffect(TransmissionErrorEffect::kType);
  ASSERT_GE(te, 0);
  // The same model with the transmission error's slope hidden: every effect but that one, then the wrapper.
  std::vector<std::unique_ptr<Effect>> effects;
  for (int i = 0; i < model.effectCount(); ++i) {
    effects.push_back(i == te ? std::make_unique<SlopeHidden>(model.effect(i).clone()) : model.effect(i).clone());
  }
  const JointErrorModel hidden(model.sharedRobot(), model.gears(), std::move(effects));
  const std::vector<DriveParameters> drives = loadDriveParameters(kParameters, *rx170());
  FlexibleJointPlant analytic(model, drives);
  FlexibleJointPlant numeric(hidden, drives);
  const JointVector command = joints({20.0, 45.0, 70.0, 30.0, 50.0, 10.0});
  analytic.reset(command);
  numeric.reset(command);
  std::mt19937 rng(31);
  std::normal_distribution<double> jitter(0.0, 1.0);
  const int size = analytic.stateSize();
  for (int sample = 0; sample < 20; ++sample) {
    std::vector<double> y(analytic.state(), analytic.state() + size);
    for (int i = 0; i < size; ++i) {
      const bool velocity = (i >= 6 && i < 12) || (i >= 18 && i < 24);
      y[static_cast<std::size_t>(i)] += (velocity ? 0.2 : 0.01) * jitter(rng);  // drives and links moving
    }
    std::vector<double> a(static_cast<std::size_t>(size)), b(static_cast<std::size_t>(size));
    analytic.derivative(0.0, y.data(), a.data());
    numeric.derivative(0.0, y.data(), b.data());
    for (int i = 0; i < size; ++i) {
      EXPECT_NEAR(a[static_cast<std::size_t>(i)], b[static_cast<std::size_t>(i)],
                  1e-6 * (1.0 + std::abs(b[static_cast<std::size_t>(i)])))
          << "state " << i << ", sample " << sample;
    }
  }
}

}  // namespace
}  // namespace jointcomp
