#include "model/io/parameter_file.hpp"

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"
#include "model/effects/registry.hpp"
#include "model/io/atomic_file.hpp"

namespace jointcomp {
namespace {
constexpr const char* kFormat = "jointcomp-parameters/1";
}

JointErrorModel parseParameters(const std::string& json_text, const std::string& source_name,
                                std::shared_ptr<const Robot> robot) {
  if (!robot) throw InvalidArgument("parameters need a robot");
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::parse_error& error) {
    throw ParameterError(source_name + ": not valid JSON (byte " + std::to_string(error.byte) + "): " + error.what());
  } catch (const nlohmann::json::exception& error) {  // e.g. a number too large for a double
    throw ParameterError(source_name + ": not valid JSON: " + error.what());
  }
  JsonFields fields(document, source_name + ": ");
  const std::string format = fields.text("format");
  if (format != kFormat) fields.fail("format", "expected \"" + std::string(kFormat) + "\", found \"" + format + "\"");
  const std::string robot_name = fields.text("robot");
  if (robot_name != robot->name) {
    fields.fail("robot", "the file is for robot '" + robot_name + "' but the URDF describes '" + robot->name + "'");
  }
  const std::string notes = fields.textOr("notes", "");
  if (fields.has("plant")) fields.object("plant");  // read by parseDriveParameters
  GearTrain gears = fields.has("gears") ? GearTrain::fromJson(fields.object("gears"), *robot, fields.pathOf("gears"))
                                        : GearTrain::direct(robot->dof());
  std::vector<std::unique_ptr<Effect>> effects;
  const nlohmann::json& list = fields.array("effects");
  for (std::size_t i = 0; i < list.size(); ++i) {
    effects.push_back(createEffect(list[i], *robot, gears, fields.pathOf("effects[" + std::to_string(i) + "]")));
  }
  fields.rejectUnknownKeys();
  JointErrorModel model(std::move(robot), std::move(gears), std::move(effects));
  model.notes = notes;
  return model;
}

JointErrorModel loadParameterFile(const std::string& path, std::shared_ptr<const Robot> robot) {
  std::string text;
  try {
    text = readTextFile(path, "parameter file");
  } catch (const Error& error) {
    throw ParameterError(error.what());
  }
  return parseParameters(text, path, std::move(robot));
}

std::vector<DriveParameters> parseDriveParameters(const std::string& json_text, const std::string& source_name,
                                                  const Robot& robot) {
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::parse_error& error) {
    throw ParameterError(source_name + ": not valid JSON (byte " + std::to_string(error.byte) + "): " + error.what());
  } catch (const nlohmann::json::exception& error) {  // e.g. a number too large for a double
    throw ParameterError(source_name + ": not valid JSON: " + error.what());
  }
  if (!document.is_object() || !document.contains("plant")) {
    throw ParameterError(source_name + ": no \"plant\" object (drives and controller gains) for the plant");
  }
  return drivesFromJson(document.at("plant"), robot, source_name + ": plant");
}

std::vector<DriveParameters> loadDriveParameters(const std::string& path, const Robot& robot) {
  std::string text;
  try {
    text = readTextFile(path, "parameter file");
  } catch (const Error& error) {
    throw ParameterError(error.what());
  }
  return parseDriveParameters(text, path, robot);
}

std::string parametersToJson(const JointErrorModel& model, const std::vector<DriveParameters>& drives) {
  nlohmann::ordered_json document;
  document["format"] = kFormat;
  document["robot"] = model.robot().name;
  if (!model.notes.empty()) document["notes"] = model.notes;
  document["gears"] = model.gears().toJson(model.robot());
  nlohmann::json effects = nlohmann::json::array();
  for (int i = 0; i < model.effectCount(); ++i) effects.push_back(model.effect(i).toJson());
  document["effects"] = effects;
  if (!drives.empty()) document["plant"] = drivesToJson(drives, model.robot());
  return document.dump(2) + "\n";
}

void saveParameterFile(const JointErrorModel& model, const std::string& path,
                       const std::vector<DriveParameters>& drives) {
  writeFileAtomically(path, parametersToJson(model, drives));
}

}  // namespace jointcomp
