// Joint-error parameter files (JSON, one per robot): the gear train and the list of effects, every value
// with its unit in the key name, estimates marked with an "estimate" note. Format:
//   {"format": "jointcomp-parameters/1", "robot": "<URDF robot name>", "notes": "...",
//    "gears": {"joints": [{"joint": "joint_1", "stage_ratios": [..]}, ..], "coupling": [..]},
//    "effects": [{"type": "compliance", ..}, {"type": "spring_balancer", ..}, ..]}
#pragma once

#include <memory>
#include <string>

#include "model/effects/joint_error_model.hpp"

namespace jointcomp {

// Reads and fully validates a parameter file for `robot`. Throws ParameterError naming the file and the
// JSON path of the offending field (unknown keys, missing values, wrong types, out-of-range values).
JointErrorModel loadParameterFile(const std::string& path, std::shared_ptr<const Robot> robot);
JointErrorModel parseParameters(const std::string& json_text, const std::string& source_name,
                                std::shared_ptr<const Robot> robot);

std::string parametersToJson(const JointErrorModel& model);
// Writes whole or not at all (temporary file, then rename).
void saveParameterFile(const JointErrorModel& model, const std::string& path);

}  // namespace jointcomp
