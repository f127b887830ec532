// The binding of the FMU's variables to the model (Variable::binding and key, fmu/description): each
// parameter of the table is a named parameter of an effect of the plant's truth ("plant") or of the
// compensator's nominal model ("compensator"), a named drive parameter ("drive", model/plant), or an
// integrator option ("integrator"). Found once, by name, in the parameter set the FMU ships; applied to a
// copy of that set whenever the fixed parameters change.
#pragma once

#include <string>
#include <vector>

#include "fmu/description/variable_table.hpp"
#include "model/io/parameter_file.hpp"
#include "model/plant/plant_options_by_name.hpp"

namespace jointcomp::fmu {

class VariableBinding {
public:
  // Throws ParameterError naming the parameter and the FMU variable when the set lacks a parameter the table
  // binds (the table is built from the same set, so only a table and set that do not belong together).
  VariableBinding(const ParameterSet& base, const Robot& robot, const VariableTable& table);

  struct BoundModels {
    JointErrorModel truth;    // the plant's joint-error model
    JointErrorModel nominal;  // the compensator's
    std::vector<DriveParameters> drives;
    PlantOptions options;
  };
  // The base set with every bound variable's value (`values`: every variable, in table order) in its place.
  // Throws ParameterError naming the parameter ("plant parameters: ...", "compensator parameters: ...",
  // "controller parameters: ...") for a value the model refuses.
  BoundModels apply(const ParameterSet& base, const Robot& robot, const std::vector<double>& values) const;

  // The integrator option a variable binds, nullptr for the others.
  const PlantOptionByName* option(int index) const { return option_[static_cast<std::size_t>(index)]; }

private:
  struct EffectSlot {
    int effect = -1;     // index in the parameter set's model
    int parameter = -1;  // index among that effect's parameters
  };
  std::vector<Binding> binding_;  // per variable
  std::vector<EffectSlot> effect_slot_;
  std::vector<int> drive_slot_;  // index among driveParameters(), -1 for the others
  std::vector<const PlantOptionByName*> option_;
};

}  // namespace jointcomp::fmu
