#include "fmu/robot/variable_binding.hpp"

#include <algorithm>
#include <cstdio>

#include "fmu/robot/fmu_plant_options.hpp"
#include "model/common/errors.hpp"

namespace jointcomp::fmu {

VariableBinding::VariableBinding(const ParameterSet& base, const Robot& robot, const VariableTable& table)
    : binding_(table.variables.size(), Binding::None),
      effect_slot_(table.variables.size()),
      drive_slot_(table.variables.size(), -1),
      option_(table.variables.size(), nullptr) {
  const std::string parameter_path = "the FMU's parameter file";
  const std::vector<std::string> drive_names = driveParameterNames(robot);
  for (std::size_t i = 0; i < table.variables.size(); ++i) {
    const Variable& v = table.variables[i];
    binding_[i] = v.binding;
    switch (v.binding) {
      case Binding::None: break;
      case Binding::Plant:
      case Binding::Compensator: {
        EffectSlot& slot = effect_slot_[static_cast<std::size_t>(i)];
        for (int e = 0; e < base.model.effectCount() && slot.effect < 0; ++e) {
          const std::vector<std::string> names = base.model.effect(e).parameterNames();
          const auto found = std::find(names.begin(), names.end(), v.key);
          if (found != names.end()) slot = {e, static_cast<int>(found - names.begin())};
        }
        if (slot.effect < 0) {
          throw ParameterError(parameter_path + ": no effect parameter '" + v.key + "' (FMU variable '" + v.name +
                               "')");
        }
        break;
      }
      case Binding::Drive: {
        const auto found = std::find(drive_names.begin(), drive_names.end(), v.key);
        if (found == drive_names.end() || !base.hasDrives()) {
          throw ParameterError(parameter_path + ": no drive parameter '" + v.key + "' (FMU variable '" + v.name + "')");
        }
        drive_slot_[static_cast<std::size_t>(i)] = static_cast<int>(found - drive_names.begin());
        break;
      }
      case Binding::Integrator:
        option_[static_cast<std::size_t>(i)] = findPlantOption(v.key.c_str());
        if (!option_[static_cast<std::size_t>(i)]) {
          throw Error(std::string("no integrator option '") + v.key + "' (FMU variable '" + v.name + "')");
        }
        break;
    }
  }
}

VariableBinding::BoundModels VariableBinding::apply(const ParameterSet& base, const Robot& robot,
                                                    const std::vector<double>& values) const {
  BoundModels built{base.model, base.model, base.drives, fmuPlantOptions()};
  for (int e = 0; e < base.model.effectCount(); ++e) {
    std::vector<double> truth_values = built.truth.effect(e).parameters();
    std::vector<double> nominal_values = built.nominal.effect(e).parameters();
    bool touched = false;
    for (std::size_t i = 0; i < effect_slot_.size(); ++i) {
      const EffectSlot& slot = effect_slot_[i];
      if (slot.effect != e) continue;
      touched = true;
      auto& target = binding_[i] == Binding::Plant ? truth_values : nominal_values;
      target[static_cast<std::size_t>(slot.parameter)] = values[static_cast<std::size_t>(i)];
    }
    if (!touched) continue;
    try {
      built.truth.effect(e).setParameters(truth_values);
    } catch (const Error& error) {
      throw ParameterError(std::string("plant parameters: ") + error.what());
    }
    try {
      built.nominal.effect(e).setParameters(nominal_values);
    } catch (const Error& error) {
      throw ParameterError(std::string("compensator parameters: ") + error.what());
    }
  }
  std::vector<double> drive_values = driveParameters(base.drives);
  for (std::size_t i = 0; i < drive_slot_.size(); ++i) {
    const int slot = drive_slot_[i];
    if (slot >= 0) drive_values[static_cast<std::size_t>(slot)] = values[static_cast<std::size_t>(i)];
  }
  try {
    setDriveParameters(built.drives, robot, drive_values);
  } catch (const Error& error) {
    throw ParameterError(std::string("controller parameters: ") + error.what());
  }
  for (int i = 0; i < static_cast<int>(option_.size()); ++i) {
    if (const PlantOptionByName* o = option(i)) o->set(built.options, values[static_cast<std::size_t>(i)]);
  }
  return built;
}

}  // namespace jointcomp::fmu
