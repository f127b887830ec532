// An FMU's variables as any model has them, with nothing of what they mean to the model: what the generic
// FMI core (fmu/core) and modelDescription.xml need. The robot's table (variable_table.hpp) adds the roles.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace jointcomp::fmu {

enum class VariableType : std::uint8_t { Real, Integer, Boolean, Enumeration };
enum class Causality : std::uint8_t { Parameter, Input, Output, Independent };
enum class Variability : std::uint8_t { Fixed, Tunable, Discrete, Continuous };
// What a parameter sets in the model (None: the instance code reads it by its role).
enum class Binding : std::uint8_t { None, Plant, Compensator, Drive, Integrator };

struct Variable {
  std::uint32_t vr = 0;  // == its index in the table
  std::string name;      // FMI structured name, e.g. q_desired.joint_2, plant.joint_1.stiffness
  VariableType type = VariableType::Real;
  Causality causality = Causality::Parameter;
  Variability variability = Variability::Fixed;
  bool has_start = false;                 // parameters and inputs have one, outputs and the time do not
  double start = 0.0;                     // 0 when there is none; Booleans 0 or 1
  bool has_min = false, has_max = false;  // declared in modelDescription.xml
  // What set accepts: the declared bounds, -inf / +inf where none is declared, an enumeration's items' range.
  double min = -std::numeric_limits<double>::infinity(), max = std::numeric_limits<double>::infinity();
  Binding binding = Binding::None;
  std::string key;          // the bound parameter's name in the model ("joint_1.stiffness_nm_per_rad"), "" else
  std::string unit;         // one of VariableTable::units, "" for none
  std::string enumeration;  // the declared type of an Enumeration
  std::string description;
  std::vector<int> depends;  // the inputs an output depends on directly (indices), sorted
};

struct Unit {
  std::string name;
  // Exponents of kg, m, s, A, K, mol, cd, rad (FMI's BaseUnit attributes, in that order).
  std::array<int, 8> exponents{};
  std::string description;
};

struct EnumerationItem {
  std::string name;
  int value = 0;
  std::string description;
};
struct EnumerationType {
  std::string name;
  std::vector<EnumerationItem> items;
};

struct LogCategory {
  std::string name, description;
};

// Model-level attributes of modelDescription.xml.
struct ModelAttributes {
  std::string model_name = "jointcomp";
  std::string model_identifier = "jointcomp";  // the binary's name
  std::string description, author = "jointcomp", copyright = "jointcomp authors", license = "BSD-3-Clause";
  std::string version;  // the project's version
  std::string generation_tool = "jointcomp export-fmu";
  double start_time = 0.0, stop_time = 30.0, step_size = 0.001;  // the default experiment
};

struct ModelVariables {
  ModelAttributes model;
  std::vector<Unit> units;                    // only those the variables use
  std::vector<EnumerationType> enumerations;  // the declared enumeration types
  std::vector<LogCategory> log_categories;    // in the order the instance's categories are numbered
  std::vector<Variable> variables;            // index == value reference
  std::string instantiation_token;            // "{xxxxxxxx-xxxx-...}"

  int size() const { return static_cast<int>(variables.size()); }
  // The index of a value reference, -1 if the table has none.
  int indexOf(std::uint32_t vr) const { return vr < variables.size() ? static_cast<int>(vr) : -1; }
  // -1 if no variable has that name.
  int indexOfName(const std::string& name) const;
};

// "vr N (name)", for messages.
std::string describeVariable(const ModelVariables& table, int index);

}  // namespace jointcomp::fmu
