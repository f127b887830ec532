#include "fmu/variable_flags.hpp"

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

VariableFlags::VariableFlags(const VariableTable& table) {
  const std::size_t count = table.variables.size();
  std::vector<unsigned> group(count, 0u);
  desired_input.assign(count, false);
  fixed_parameter.assign(count, false);
  packed.assign(count, 0u);
  const Roles& r = table.roles;
  for (int j = 0; j < table.dof(); ++j) {
    group[r.q_link[j]] = kLinkOutputs;
    group[r.qd_link[j]] = kLinkVelocityOutputs;
    for (int index : {r.q_motor[j], r.qd_motor[j], r.dq_actual[j]}) group[index] = kMotorOutputs;
    group[r.dq_predicted[j]] = kPredictedOutputs;
    group[r.q_ref[j]] = kReferenceOutputs;
    group[r.q_planned[j]] = kReferenceOutputs;
    for (int index : {r.q_desired[j], r.qd_desired[j], r.qdd_desired[j]}) desired_input[index] = true;
  }
  for (int index : r.tool_position) group[index] = kToolOutputs;
  for (std::size_t i = 0; i < count; ++i) {
    const Variable& v = table.variables[i];
    const bool computed = v.causality == Causality::Output || v.causality == Causality::Independent;
    const bool input = v.causality == Causality::Input;
    const bool parameter = v.causality == Causality::Parameter;
    const bool tunable = parameter && v.variability == Variability::Tunable;
    fixed_parameter[i] = parameter && v.variability == Variability::Fixed;
    unsigned settable = 0;
    if (v.type == VariableType::Real) {
      if (input || parameter) settable |= kSettableBeforeSteps;
      if (input || tunable) settable |= kSettableInSteps;
      if ((input && !desired_input[i]) || tunable) settable |= kSettableInDemoSteps;
    }
    packed[i] = typeBit(v.type) | (computed ? kPackedComputed : 0u) | group[i] << kPackedGroupShift |
                settable << kPackedSettableShift;
  }
}

}  // namespace jointcomp::fmu
