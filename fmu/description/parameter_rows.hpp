// The FMU's parameters for a robot's parameter set: every named parameter of every effect twice (plant.*:
// the simulated robot, the truth; compensator.*: the compensator's nominal model), every drive parameter
// (controller.<joint>.kp/ki/kd, drive.<joint>.*) and the plant's integrator and watchdog options. A name
// is the parameter's name without its unit suffix (joint_1.stiffness_nm_per_rad -> joint_1.stiffness,
// unit N.m/rad); a suffix the FMU has no unit for stays in the name.
#pragma once

#include <vector>

#include "fmu/description/variable_table.hpp"

namespace jointcomp::fmu {

// Start values from the set (drives: its "plant" object; integrator: the FMU's plant options). Throws
// jointcomp::Error naming the parameter whose value lies outside the bounds the FMU declares for it.
std::vector<Variable> parameterRows(const Robot& robot, const ParameterSet& parameters);

}  // namespace jointcomp::fmu
