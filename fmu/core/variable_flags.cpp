#include "fmu/core/variable_flags.hpp"

#include "model/common/errors.hpp"

namespace jointcomp::fmu {

unsigned typeBit(VariableType type) {
  switch (type) {
    case VariableType::Real: return kReal;
    case VariableType::Integer: return kInteger;
    case VariableType::Boolean: return kBoolean;
    case VariableType::Enumeration: return kEnumeration;
  }
  return 0;
}

VariableFlags::VariableFlags(const Model& model) {
  const ModelVariables& table = model.table();
  const std::size_t count = table.variables.size();
  watched.assign(count, false);
  held_when_restricted.assign(count, false);
  packed.assign(count, 0u);
  for (std::size_t i = 0; i < count; ++i) {
    const Variable& v = table.variables[i];
    const VariableTraits traits = model.traits(static_cast<int>(i));
    if (traits.output_group > 0xFFu) throw Error("FMU variables: output groups are 8 bits");
    watched[i] = traits.watched;
    held_when_restricted[i] = traits.held_when_restricted;
    const bool computed = v.causality == Causality::Output || v.causality == Causality::Independent;
    const bool input = v.causality == Causality::Input;
    const bool parameter = v.causality == Causality::Parameter;
    const bool tunable = parameter && v.variability == Variability::Tunable;
    unsigned settable = 0;
    if (v.type == VariableType::Real) {
      if (input || parameter) settable |= kSettableBeforeSteps;
      if (input || tunable) settable |= kSettableInSteps;
      if ((input && !traits.held_when_restricted) || tunable) settable |= kSettableInRestrictedSteps;
    }
    packed[i] = typeBit(v.type) | (computed ? kPackedComputed : 0u) | traits.output_group << kPackedGroupShift |
                settable << kPackedSettableShift;
  }
}

}  // namespace jointcomp::fmu
