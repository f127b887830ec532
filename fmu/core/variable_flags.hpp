// What every get and set asks of a variable, by index, looked up once per instance instead of recomputed per
// value: its type's bit, its output group (the model's, 0 for non-outputs), whether the model watches it,
// and which of set's common cases allow setting it; packed in one word per variable for the loops of get and
// set, which read one word per value instead of one entry of each array.
#pragma once

#include <vector>

#include "fmu/core/model.hpp"
#include "fmu/description/variables.hpp"

namespace jointcomp::fmu {

// Accepted variable types for a typed get or set, as bits.
enum TypeMask : unsigned {
  kReal = 1u << 0,
  kInteger = 1u << 1,
  kBoolean = 1u << 2,
  kEnumeration = 1u << 3,
};

// For reals only: set's common cases that allow setting a variable (in steps while the model restricts
// its inputs, held inputs are not settable).
enum SettableReal : unsigned char { kSettableBeforeSteps = 1, kSettableInSteps = 2, kSettableInRestrictedSteps = 4 };

unsigned typeBit(VariableType type);

struct VariableFlags {
  explicit VariableFlags(const Model& model);

  std::vector<bool> watched;
  std::vector<bool> held_when_restricted;
  // The type bits (kReal ... kEnumeration) in bits 0-3, then these.
  static constexpr unsigned kPackedComputed = 1u << 4;                         // an output or the independent variable
  static constexpr unsigned kPackedGroupShift = 8, kPackedSettableShift = 16;  // groups: 8 bits
  std::vector<unsigned> packed;
};

}  // namespace jointcomp::fmu
