// Effects created by type name, from the objects of a parameter file's "effects" array. The names are
// the one vocabulary used by parameter files, reports and discovery.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "model/effects/effect.hpp"
#include "model/effects/gear_train.hpp"

namespace jointcomp {

// Throws ParameterError naming `path` and the field for an unknown type or an invalid effect.
std::unique_ptr<Effect> createEffect(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                     const std::string& path);
std::vector<std::string> registeredEffectTypes();

}  // namespace jointcomp
