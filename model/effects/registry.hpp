// Effect types by name: how each is read from a parameter file's "effects" array, and what residual
// discovery may look for (its families). The names are the one vocabulary of parameter files, reports
// and discovery. The built-in registry is immutable; a user (or a test) who adds an effect type copies it,
// adds the type, and hands the copy to what reads parameter files or runs discovery.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "model/effects/discovery_family.hpp"
#include "model/effects/effect.hpp"
#include "model/effects/gear_train.hpp"

namespace jointcomp {

using EffectFactory = std::function<std::unique_ptr<Effect>(const nlohmann::json& json, const Robot& robot,
                                                            const GearTrain& gears, const std::string& path)>;

class EffectRegistry {
public:
  // Every effect type jointcomp ships, and the discovery families in the order discovery offers their
  // candidates and adds their effects to a model.
  static const EffectRegistry& builtin();

  // Throws InvalidArgument for an empty name or one already registered.
  void addEffectType(const std::string& type, EffectFactory create);
  void addDiscoveryFamily(std::shared_ptr<const DiscoveryFamily> family);

  // Throws ParameterError naming `path` and the field for an unknown type or an invalid effect.
  std::unique_ptr<Effect> create(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                 const std::string& path) const;
  std::vector<std::string> effectTypes() const;  // sorted
  const std::vector<std::shared_ptr<const DiscoveryFamily>>& discoveryFamilies() const { return families_; }
  std::vector<std::string> discoveryVocabulary() const;  // the families' names, in order
  bool hasDiscoveryFamily(const std::string& name) const;

private:
  std::map<std::string, EffectFactory> factories_;
  std::vector<std::shared_ptr<const DiscoveryFamily>> families_;
};

// The built-in registry's create() and effectTypes().
std::unique_ptr<Effect> createEffect(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                     const std::string& path);
std::vector<std::string> registeredEffectTypes();

}  // namespace jointcomp
