// What every get and set asks of a variable, by index, looked up once per instance instead of recomputed per
// value: its output group (0 for non-outputs), its type's bit, whether it is a desired input (q_desired,
// qd_desired or qdd_desired: the inputs the robot follows unless it follows the demo move), and which of
// set's common cases allow setting it; packed in one word per variable for the loops of get and set, which
// read one word per value instead of one entry of each array.
#pragma once

#include <vector>

#include "fmu/description/variable_table.hpp"

namespace jointcomp::fmu {

// Accepted variable types for a typed get or set, as bits.
enum TypeMask : unsigned {
  kReal = 1u << 0,
  kInteger = 1u << 1,
  kBoolean = 1u << 2,
  kEnumeration = 1u << 3,
};

// For reals only: set's common cases that allow setting a variable.
enum SettableReal : unsigned char { kSettableBeforeSteps = 1, kSettableInSteps = 2, kSettableInDemoSteps = 4 };

// Groups of outputs computed together, lazily, as bits (a get computes only the groups it reads).
enum OutputGroup : unsigned {
  kLinkOutputs = 1u,
  kToolOutputs = 2u,
  kPredictedOutputs = 4u,
  kReferenceOutputs = 8u,
  kMotorOutputs = 16u,
  kLinkVelocityOutputs = 32u,
};

unsigned typeBit(VariableType type);

struct VariableFlags {
  explicit VariableFlags(const VariableTable& table);

  std::vector<bool> desired_input;
  std::vector<bool> fixed_parameter;
  // The type bits (kReal ... kEnumeration) in bits 0-3, then these.
  static constexpr unsigned kPackedComputed = 1u << 4;  // an output or the independent variable
  static constexpr unsigned kPackedGroupShift = 8, kPackedSettableShift = 16;
  std::vector<unsigned> packed;
};

}  // namespace jointcomp::fmu
