// Build-time tool of the FMU: converts the robot's URDF into resources/robot.json (so that the FMU's
// binary needs no URDF parser) and lists the named parameters of the shipped parameter file with their
// values, from which modelDescription/generate.py takes the start values of the FMU's parameters.
//   jointcomp_fmu_resources <robot.urdf> <parameters.json> <out robot.json> <out parameter-values.json>
//                           [--base-link=LINK] [--tip-link=LINK]
// The links choose the URDF's chain (empty or absent: its root, and the end of its longest moving chain).
// Fails (exit 1, with the reason) when the robot does not survive the round trip through JSON bit for
// bit, when the parameter file does not fit the robot, or when a plant cannot be built from them.
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <set>

#include <nlohmann/json.hpp>

#include "fmu/fmu_plant_options.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/parameter_file.hpp"
#include "model/io/robot_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"
#include "model/plant/plant_options_by_name.hpp"
#include "model/robot/load_urdf.hpp"

namespace {

int run(const std::string& urdf, const std::string& parameters, const std::string& robot_out,
        const std::string& values_out, const jointcomp::UrdfChainOptions& chain) {
  using namespace jointcomp;
  const Robot loaded = loadRobotFromUrdfFile(urdf, chain);
  const std::string text = robotToJson(loaded);
  auto robot = std::make_shared<const Robot>(robotFromJson(text, "robot.json"));
  if (!sameRobot(loaded, *robot)) {
    std::fprintf(stderr, "%s: the robot does not read back bit for bit from its JSON form\n", urdf.c_str());
    return 1;
  }
  const ParameterSet loaded_parameters = loadParameterSet(parameters, robot);
  const JointErrorModel& model = loaded_parameters.model;
  const std::vector<DriveParameters>& drives = loaded_parameters.drives;
  const PlantOptions options = fmuPlantOptions();
  FlexibleJointPlant plant(model, drives, options);  // what the FMU will build must build

  nlohmann::ordered_json values;
  values["robot"] = robot->name;
  values["dof"] = robot->dof();
  for (const Joint& joint : robot->joints) {
    values["joints"].push_back(joint.name);
    // null for a continuous joint (no limit)
    values["joint_limits"]["lower"].push_back(std::isfinite(joint.lower) ? nlohmann::ordered_json(joint.lower)
                                                                         : nullptr);
    values["joint_limits"]["upper"].push_back(std::isfinite(joint.upper) ? nlohmann::ordered_json(joint.upper)
                                                                         : nullptr);
  }
  std::set<std::string> seen;
  for (int i = 0; i < model.effectCount(); ++i) {
    const Effect& effect = model.effect(i);
    const std::vector<std::string> names = effect.parameterNames();
    const std::vector<double> numbers = effect.parameters();
    for (std::size_t k = 0; k < names.size(); ++k) {
      if (!seen.insert(names[k]).second) {
        std::fprintf(stderr, "%s: parameter name '%s' appears twice\n", parameters.c_str(), names[k].c_str());
        return 1;
      }
      values["effects"][names[k]] = numbers[k];
    }
  }
  const nlohmann::json drive_json = drivesToJson(drives, *robot);
  for (const nlohmann::json& joint : drive_json.at("joints")) {
    const std::string joint_name = joint.at("joint").get<std::string>();
    for (const auto& item : joint.items()) {
      if (item.value().is_number()) values["drives"][joint_name + "." + item.key()] = item.value();
    }
  }
  for (const PlantOptionByName& option : kPlantOptionsByName) {
    values["integrator"][option.name] = option.get(options);
  }

  writeFileAtomically(robot_out, text);
  writeFileAtomically(values_out, values.dump(2) + "\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  jointcomp::UrdfChainOptions chain;
  bool usage = argc < 5;
  for (int i = 5; i < argc && !usage; ++i) {
    const std::string option = argv[i];
    if (option.rfind("--base-link=", 0) == 0) {
      chain.root_link = option.substr(12);
    } else if (option.rfind("--tip-link=", 0) == 0) {
      chain.tip_link = option.substr(11);
    } else {
      usage = true;
    }
  }
  if (usage) {
    std::fprintf(stderr,
                 "usage: %s <robot.urdf> <parameters.json> <out robot.json> <out parameter-values.json> "
                 "[--base-link=LINK] [--tip-link=LINK]\n",
                 argc > 0 ? argv[0] : "jointcomp_fmu_resources");
    return 2;
  }
  try {
    return run(argv[1], argv[2], argv[3], argv[4], chain);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "jointcomp_fmu_resources: %s\n", error.what());
    return 1;
  }
}
