#include "model/effects/registry.hpp"

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/effects/backlash.hpp"
#include "model/effects/compliance.hpp"
#include "model/effects/hysteresis.hpp"
#include "model/effects/joint_offset.hpp"
#include "model/effects/joint_placement.hpp"
#include "model/effects/link_bending.hpp"
#include "model/effects/nonlinear_compliance.hpp"
#include "model/effects/payload.hpp"
#include "model/effects/periodic_table.hpp"
#include "model/effects/spring_balancer.hpp"
#include "model/effects/thermal_drift.hpp"
#include "model/effects/transmission_error.hpp"

namespace jointcomp {
namespace {

EffectRegistry makeBuiltin() {
  EffectRegistry registry;
  // Compliance and the balancer do not depend on the gear train.
  registry.addEffectType(ComplianceEffect::kType,
                         [](const nlohmann::json& j, const Robot& r, const GearTrain&, const std::string& p) {
                           return ComplianceEffect::fromJson(j, r, p);
                         });
  registry.addEffectType(SpringBalancerEffect::kType,
                         [](const nlohmann::json& j, const Robot& r, const GearTrain&, const std::string& p) {
                           return SpringBalancerEffect::fromJson(j, r, p);
                         });
  registry.addEffectType(TransmissionErrorEffect::kType, &TransmissionErrorEffect::fromJson);
  registry.addEffectType(JointOffsetEffect::kType, &JointOffsetEffect::fromJson);
  registry.addEffectType(BacklashEffect::kType, &BacklashEffect::fromJson);
  registry.addEffectType(NonlinearComplianceEffect::kType, &NonlinearComplianceEffect::fromJson);
  registry.addEffectType(ThermalDriftEffect::kType, &ThermalDriftEffect::fromJson);
  registry.addEffectType(HysteresisEffect::kType, &HysteresisEffect::fromJson);
  registry.addEffectType(PayloadEffect::kType, &PayloadEffect::fromJson);
  registry.addEffectType(PeriodicTableEffect::kType, &PeriodicTableEffect::fromJson);
  registry.addEffectType(LinkBendingEffect::kType, &LinkBendingEffect::fromJson);
  // Discovery: the calibration's own parameters first, then the effects in the order they join a model.
  registry.addDiscoveryFamily(std::make_shared<JointOffsetDiscovery>());
  registry.addDiscoveryFamily(std::make_shared<ComplianceDiscovery>());
  registry.addDiscoveryFamily(std::make_shared<JointPlacementDiscovery>());
  registry.addDiscoveryFamily(std::make_shared<InstrumentScaleDiscovery>());
  registry.addDiscoveryFamily(std::make_shared<BacklashDiscovery>());
  registry.addDiscoveryFamily(std::make_shared<HysteresisDiscovery>());
  registry.addDiscoveryFamily(std::make_shared<PayloadDiscovery>());
  registry.addDiscoveryFamily(std::make_shared<NonlinearComplianceDiscovery>());
  registry.addDiscoveryFamily(std::make_shared<LinkBendingDiscovery>());
  registry.addDiscoveryFamily(std::make_shared<ThermalDriftDiscovery>());
  registry.addDiscoveryFamily(std::make_shared<HarmonicDiscovery>());
  registry.addDiscoveryFamily(std::make_shared<PeriodicTableDiscovery>());
  return registry;
}

}  // namespace

const EffectRegistry& EffectRegistry::builtin() {
  static const EffectRegistry registry = makeBuiltin();
  return registry;
}

void EffectRegistry::addEffectType(const std::string& type, EffectFactory create) {
  if (type.empty()) throw InvalidArgument("effect registry: an effect type needs a name");
  if (!create) throw InvalidArgument("effect registry: effect type '" + type + "' needs a factory");
  if (!factories_.emplace(type, std::move(create)).second) {
    throw InvalidArgument("effect registry: effect type '" + type + "' is already registered");
  }
}

void EffectRegistry::addDiscoveryFamily(std::shared_ptr<const DiscoveryFamily> family) {
  if (!family || family->name().empty()) throw InvalidArgument("effect registry: a discovery family needs a name");
  if (hasDiscoveryFamily(family->name())) {
    throw InvalidArgument("effect registry: discovery family '" + family->name() + "' is already registered");
  }
  families_.push_back(std::move(family));
}

std::unique_ptr<Effect> EffectRegistry::create(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                               const std::string& path) const {
  if (!json.is_object()) throw ParameterError(path + ": expected a JSON object");
  if (!json.contains("type") || !json.at("type").is_string())
    throw ParameterError(path + ".type: missing or not a string");
  const std::string type = json.at("type").get<std::string>();
  const auto found = factories_.find(type);
  if (found == factories_.end()) {
    std::string known;
    for (const auto& entry : factories_) known += (known.empty() ? "" : ", ") + entry.first;
    throw ParameterError(path + ".type: unknown effect type '" + type + "' (known: " + known + ")");
  }
  return found->second(json, robot, gears, path);
}

std::vector<std::string> EffectRegistry::effectTypes() const {
  std::vector<std::string> types;
  for (const auto& entry : factories_) types.push_back(entry.first);
  return types;
}

std::vector<std::string> EffectRegistry::discoveryVocabulary() const {
  std::vector<std::string> names;
  for (const auto& family : families_) names.push_back(family->name());
  return names;
}

bool EffectRegistry::hasDiscoveryFamily(const std::string& name) const {
  for (const auto& family : families_) {
    if (family->name() == name) return true;
  }
  return false;
}

std::unique_ptr<Effect> createEffect(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                     const std::string& path) {
  return EffectRegistry::builtin().create(json, robot, gears, path);
}

std::vector<std::string> registeredEffectTypes() { return EffectRegistry::builtin().effectTypes(); }

}  // namespace jointcomp
