#include "model/effects/registry.hpp"

#include <functional>
#include <map>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/effects/backlash.hpp"
#include "model/effects/compliance.hpp"
#include "model/effects/hysteresis.hpp"
#include "model/effects/joint_offset.hpp"
#include "model/effects/nonlinear_compliance.hpp"
#include "model/effects/payload.hpp"
#include "model/effects/spring_balancer.hpp"
#include "model/effects/thermal_drift.hpp"
#include "model/effects/transmission_error.hpp"

namespace jointcomp {
namespace {

using Factory = std::function<std::unique_ptr<Effect>(const nlohmann::json&, const Robot&, const GearTrain&,
                                                      const std::string&)>;

const std::map<std::string, Factory>& factories() {
  static const std::map<std::string, Factory> table = {
      {ComplianceEffect::kType,
       [](const nlohmann::json& j, const Robot& r, const GearTrain&, const std::string& p) {
         return ComplianceEffect::fromJson(j, r, p);
       }},
      {SpringBalancerEffect::kType,
       [](const nlohmann::json& j, const Robot& r, const GearTrain&, const std::string& p) {
         return SpringBalancerEffect::fromJson(j, r, p);
       }},
      {TransmissionErrorEffect::kType, &TransmissionErrorEffect::fromJson},
      {JointOffsetEffect::kType, &JointOffsetEffect::fromJson},
      {BacklashEffect::kType, &BacklashEffect::fromJson},
      {NonlinearComplianceEffect::kType, &NonlinearComplianceEffect::fromJson},
      {ThermalDriftEffect::kType, &ThermalDriftEffect::fromJson},
      {HysteresisEffect::kType, &HysteresisEffect::fromJson},
      {PayloadEffect::kType, &PayloadEffect::fromJson},
  };
  return table;
}

}  // namespace

std::unique_ptr<Effect> createEffect(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                     const std::string& path) {
  if (!json.is_object()) throw ParameterError(path + ": expected a JSON object");
  if (!json.contains("type") || !json.at("type").is_string()) throw ParameterError(path + ".type: missing or not a string");
  const std::string type = json.at("type").get<std::string>();
  const auto found = factories().find(type);
  if (found == factories().end()) {
    std::string known;
    for (const auto& entry : factories()) known += (known.empty() ? "" : ", ") + entry.first;
    throw ParameterError(path + ".type: unknown effect type '" + type + "' (known: " + known + ")");
  }
  return found->second(json, robot, gears, path);
}

std::vector<std::string> registeredEffectTypes() {
  std::vector<std::string> types;
  for (const auto& entry : factories()) types.push_back(entry.first);
  return types;
}

}  // namespace jointcomp
