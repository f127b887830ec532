// The plant's options by name (the integrator's and the watchdog's), as numbers: one table for the FMU's
// "integrator:" parameters (its build-time tool lists their defaults as start values, the instance sets
// them) and the C API's plant options (jc_plant_create_with_options), so that both know the same names.
#pragma once

#include <cstring>

#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp {

struct PlantOptionByName {
  enum class Kind { Number, Integer, Switch };  // a switch is 0 or 1 as a number
  const char* name;
  double (*get)(const PlantOptions& options);
  void (*set)(PlantOptions& options, double value);
  Kind kind = Kind::Number;
};

inline constexpr PlantOptionByName kPlantOptionsByName[] = {
    {"relative_tolerance", [](const PlantOptions& o) { return o.relative_tolerance; },
     [](PlantOptions& o, double v) { o.relative_tolerance = v; }},
    {"absolute_tolerance", [](const PlantOptions& o) { return o.absolute_tolerance; },
     [](PlantOptions& o, double v) { o.absolute_tolerance = v; }},
    {"velocity_tolerance_factor", [](const PlantOptions& o) { return o.velocity_tolerance_factor; },
     [](PlantOptions& o, double v) { o.velocity_tolerance_factor = v; }},
    {"max_step", [](const PlantOptions& o) { return o.max_step; }, [](PlantOptions& o, double v) { o.max_step = v; }},
    {"max_steps_per_advance", [](const PlantOptions& o) { return static_cast<double>(o.max_steps_per_advance); },
     [](PlantOptions& o, double v) { o.max_steps_per_advance = static_cast<long>(v); },
     PlantOptionByName::Kind::Integer},
    {"max_order", [](const PlantOptions& o) { return static_cast<double>(o.max_order); },
     [](PlantOptions& o, double v) { o.max_order = static_cast<int>(v); }, PlantOptionByName::Kind::Integer},
    {"jacobian_reuse_steps", [](const PlantOptions& o) { return static_cast<double>(o.jacobian_reuse_steps); },
     [](PlantOptions& o, double v) { o.jacobian_reuse_steps = static_cast<long>(v); },
     PlantOptionByName::Kind::Integer},
    {"newton_setup_steps", [](const PlantOptions& o) { return static_cast<double>(o.newton_setup_steps); },
     [](PlantOptions& o, double v) { o.newton_setup_steps = static_cast<long>(v); }, PlantOptionByName::Kind::Integer},
    {"newton_setup_gamma_change", [](const PlantOptions& o) { return o.newton_setup_gamma_change; },
     [](PlantOptions& o, double v) { o.newton_setup_gamma_change = v; }},
    {"even_steps", [](const PlantOptions& o) { return o.even_steps ? 1.0 : 0.0; },
     [](PlantOptions& o, double v) { o.even_steps = v != 0.0; }, PlantOptionByName::Kind::Switch},
    {"step_past_updates_s", [](const PlantOptions& o) { return o.step_past_updates_s; },
     [](PlantOptions& o, double v) { o.step_past_updates_s = v; }},
    {"step_past_tolerance_rad", [](const PlantOptions& o) { return o.step_past_tolerance_rad; },
     [](PlantOptions& o, double v) { o.step_past_tolerance_rad = v; }},
    {"tracking_envelope_rad", [](const PlantOptions& o) { return o.tracking_envelope_rad; },
     [](PlantOptions& o, double v) { o.tracking_envelope_rad = v; }},
    {"joint_limit_margin_rad", [](const PlantOptions& o) { return o.joint_limit_margin_rad; },
     [](PlantOptions& o, double v) { o.joint_limit_margin_rad = v; }},
};

// The option of that name, nullptr if there is none.
inline const PlantOptionByName* findPlantOption(const char* name) {
  for (const PlantOptionByName& option : kPlantOptionsByName) {
    if (std::strcmp(option.name, name) == 0) return &option;
  }
  return nullptr;
}

}  // namespace jointcomp
