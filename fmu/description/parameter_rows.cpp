#include "fmu/description/parameter_rows.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "fmu/robot/fmu_plant_options.hpp"
#include "model/common/errors.hpp"
#include "model/plant/plant_options_by_name.hpp"
#include "model/robot/drive_parameters.hpp"

namespace jointcomp::fmu {

namespace {

constexpr double kNone = std::numeric_limits<double>::quiet_NaN();

// Unit suffixes of parameter names (longest first) and the FMU's unit for each.
struct UnitSuffix {
  const char* suffix;
  const char* unit;
};
const UnitSuffix kUnitSuffixes[] = {
    {"_rad_per_nm3", "rad/(N.m)3"},
    {"_nm_per_rad_s", "N.m/(rad.s)"},
    {"_nms_per_rad", "N.m.s/rad"},
    {"_nm_per_rad", "N.m/rad"},
    {"_rad_per_nm", "rad/(N.m)"},
    {"_rad_per_degc", "rad/K"},
    {"_rad_per_s", "rad/s"},
    {"_n_per_m", "N/m"},
    {"_m_per_n", "m/N"},
    {"_n_m2", "N.m2"},
    {"_kgm2", "kg.m2"},
    {"_kg", "kg"},
    {"_nm", "N.m"},
    {"_rad", "rad"},
    {"_m", "m"},
    {"_n", "N"},
    {"_s", "s"},
};

bool endsWith(const std::string& text, const std::string& end) {
  return text.size() > end.size() && text.compare(text.size() - end.size(), end.size(), end) == 0;
}

// The name without its unit suffix, and the unit ("" and the whole name when none is known).
std::pair<std::string, std::string> splitUnit(const std::string& key) {
  for (const UnitSuffix& s : kUnitSuffixes) {
    if (endsWith(key, s.suffix)) return {key.substr(0, key.size() - std::string(s.suffix).size()), s.unit};
  }
  return {key, ""};
}

// Every part of a dotted key as a structured-name part.
std::string structuredKey(const std::string& key) {
  std::string out;
  std::size_t begin = 0;
  while (true) {
    const std::size_t dot = key.find('.', begin);
    out += structuredNamePart(key.substr(begin, dot == std::string::npos ? std::string::npos : dot - begin));
    if (dot == std::string::npos) return out;
    out += '.';
    begin = dot + 1;
  }
}

// The least value an effect parameter may take in the FMU (NaN: none declared): what its plant accepts.
double effectParameterMin(const std::string& key) {
  if (endsWith(key, "stiffness_nm_per_rad")) return 1000.0;  // joint compliance: the plant's joint modes
  if (endsWith(key, "anchor_distance_before_m") || endsWith(key, "anchor_distance_after_m")) return 0.001;
  if (endsWith(key, "stiffness_n_per_m") || endsWith(key, "free_length_m") || endsWith(key, "amplitude_rad")) {
    return 0.0;
  }
  return kNone;
}

Variable parameter(const std::string& name, const std::string& unit, double start, double min, double max,
                   const std::string& description) {
  Variable v;
  v.name = name;
  v.causality = Causality::Parameter;
  v.variability = Variability::Fixed;
  v.has_start = true;
  v.start = start;
  v.unit = unit;
  v.has_min = !std::isnan(min);
  v.has_max = !std::isnan(max);
  v.min = v.has_min ? min : -std::numeric_limits<double>::infinity();
  v.max = v.has_max ? max : std::numeric_limits<double>::infinity();
  v.description = description;
  return v;
}

void checkStart(const Variable& v) {
  if (!std::isfinite(v.start)) throw Error("FMU parameter " + v.name + ": its value is not finite");
  if ((v.has_min && v.start < v.min) || (v.has_max && v.start > v.max)) {
    char text[160];
    std::snprintf(text, sizeof text, ": its value %.17g is outside [%.17g, %.17g], what the FMU's plant accepts",
                  v.start, v.has_min ? v.min : -INFINITY, v.has_max ? v.max : INFINITY);
    throw Error("FMU parameter " + v.name + text);
  }
}

void addEffectRows(const ParameterSet& parameters, Binding binding, std::vector<Variable>& rows) {
  const bool plant = binding == Binding::Plant;
  for (int e = 0; e < parameters.model.effectCount(); ++e) {
    const Effect& effect = parameters.model.effect(e);
    const std::vector<std::string> names = effect.parameterNames();
    const std::vector<double> values = effect.parameters();
    for (std::size_t k = 0; k < names.size(); ++k) {
      const auto [stem, unit] = splitUnit(names[k]);
      Variable v =
          parameter(std::string(plant ? "plant." : "compensator.") + structuredKey(stem), unit, values[k],
                    effectParameterMin(names[k]), kNone,
                    effect.type() + " effect, " + names[k] +
                        (plant ? "; in the simulated robot (the truth)" : "; in the compensator's nominal model"));
      v.binding = binding;
      v.key = names[k];
      checkStart(v);
      rows.push_back(std::move(v));
    }
  }
}

void addDriveRows(const Robot& robot, const ParameterSet& parameters, std::vector<Variable>& rows) {
  const std::vector<std::string> names = driveParameterNames(robot);
  const std::vector<double> values = driveParameters(parameters.drives);
  for (std::size_t k = 0; k < names.size(); ++k) {
    const std::size_t dot = names[k].rfind('.');
    const std::string joint = names[k].substr(0, dot), field = names[k].substr(dot + 1);
    const auto [stem, unit] = splitUnit(field);
    const bool gain = stem == "kp" || stem == "ki" || stem == "kd";
    // A gain, friction or damping may be 0; an inertia or velocity scale must be positive, which no FMI
    // bound can say: initialisation refuses 0 with the reason.
    const bool may_be_zero =
        gain || stem.find("friction") != std::string::npos || stem.find("damping") != std::string::npos;
    Variable v = parameter(
        std::string(gain ? "controller." : "drive.") + structuredNamePart(joint) + "." + structuredNamePart(stem), unit,
        values[k], may_be_zero ? 0.0 : kNone, kNone,
        std::string(gain ? "Motor-side PID controller" : "Drive") + " of " + joint + ": " + field);
    v.binding = Binding::Drive;
    v.key = names[k];
    checkStart(v);
    rows.push_back(std::move(v));
  }
}

struct OptionRow {
  const char* option;  // kPlantOptionsByName's name
  const char* name;
  VariableType type;
  const char* unit;
  double min, max;
  const char* description;
};
const OptionRow kOptionRows[] = {
    {"relative_tolerance", "integrator.relative_tolerance", VariableType::Real, "", 1e-12, kNone,
     "CVODE relative tolerance"},
    {"absolute_tolerance", "integrator.absolute_tolerance", VariableType::Real, "rad", 1e-15, kNone,
     "CVODE absolute tolerance on positions and on the controller integral (velocities get this times "
     "velocity_tolerance_factor)"},
    {"velocity_tolerance_factor", "integrator.velocity_tolerance_factor", VariableType::Real, "1/s", 0.001, kNone,
     "Absolute tolerance on velocities, in units of absolute_tolerance, per second"},
    {"max_step", "integrator.max_step", VariableType::Real, "s", 0.0, kNone, "Largest CVODE step; 0: unbounded"},
    {"max_steps_per_advance", "integrator.max_steps", VariableType::Integer, "", 1, kNone,
     "Most CVODE steps in one communication step before the step is discarded"},
    {"max_order", "integrator.max_order", VariableType::Integer, "", 1, 5,
     "Highest BDF order (3 keeps the lightly damped joint modes stable at large steps)"},
    {"tracking_envelope_rad", "watchdog.tracking_envelope", VariableType::Real, "rad", 1e-6, kNone,
     "Largest following error |q_ref - motor position| of any drive; beyond it the step is discarded with the "
     "reason, as a drive's following-error watchdog stops the robot"},
    {"joint_limit_margin_rad", "watchdog.joint_limit_margin", VariableType::Real, "rad", 0.0, kNone,
     "How far a link may go beyond its joint limits before the step is discarded with the reason"},
    {"jacobian_reuse_steps", "integrator.jacobian_reuse_steps", VariableType::Integer, "", 1, 100000,
     "Most CVODE steps between fresh Jacobians of the plant"},
    {"newton_setup_steps", "integrator.newton_setup_steps", VariableType::Integer, "", 1, 100000,
     "Most CVODE steps between new Newton matrices I - gamma J"},
    {"newton_setup_gamma_change", "integrator.newton_setup_gamma_change", VariableType::Real, "", 0.01, 10,
     "Relative change of CVODE's gamma beyond which the Newton matrix is rebuilt"},
    {"even_steps", "integrator.even_steps", VariableType::Boolean, "", kNone, kNone,
     "true: a communication step that CVODE's planned step does not fill ends in two equal CVODE steps "
     "instead of the planned step and a sliver; false: CVODE's own steps up to the communication point"},
    {"step_past_updates_s", "integrator.step_past_updates", VariableType::Real, "s", 0.0, 1.0,
     "How far past a communication point CVODE may step; 0: it stops at every one. New inputs take over from "
     "CVODE's next step when they stay within step_past_tolerance of the reference CVODE already integrated, "
     "and restart it at their time otherwise"},
    {"step_past_tolerance_rad", "integrator.step_past_tolerance", VariableType::Real, "rad", 0.0, 10.0,
     "How far new inputs' reference may depart from the one CVODE already integrated past their "
     "communication point and still take over from CVODE's next step"},
};

void addIntegratorRows(std::vector<Variable>& rows) {
  const PlantOptions options = fmuPlantOptions();
  for (const OptionRow& row : kOptionRows) {
    const PlantOptionByName* option = findPlantOption(row.option);
    if (!option) throw Error(std::string("FMU variables: no plant option '") + row.option + "'");
    Variable v = parameter(row.name, row.unit, option->get(options), row.min, row.max, row.description);
    v.type = row.type;
    v.binding = Binding::Integrator;
    v.key = row.option;
    checkStart(v);
    rows.push_back(std::move(v));
  }
}

}  // namespace

std::vector<Variable> parameterRows(const Robot& robot, const ParameterSet& parameters) {
  std::vector<Variable> rows;
  addEffectRows(parameters, Binding::Plant, rows);
  addEffectRows(parameters, Binding::Compensator, rows);
  addDriveRows(robot, parameters, rows);
  addIntegratorRows(rows);
  return rows;
}

}  // namespace jointcomp::fmu
