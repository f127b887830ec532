#include "model/io/parameter_file.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"
#include "model/common/strict_json.hpp"
#include "model/effects/registry.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/urdf_writer.hpp"

namespace jointcomp {
namespace {

constexpr const char* kFormat = "jointcomp-parameters/1";

nlohmann::json parseDocument(const std::string& json_text, const std::string& source_name) {
  return parseStrictJson(json_text, source_name);
}

std::string readParameterText(const std::string& path) {
  try {
    return readTextFile(path, "parameter file", kMaxJsonFileBytes);
  } catch (const Error& error) {
    throw ParameterError(error.what());
  }
}

// Every number of a document about to be written is finite: nlohmann writes NaN and infinities as null,
// which would read back as "rigid" or fail later, far from the fit that produced them. A rigid joint's
// null is written as null on purpose and is not a number here.
void requireFiniteNumbers(const nlohmann::ordered_json& node, const std::string& path) {
  if (node.is_number_float() && !std::isfinite(node.get<double>())) {
    throw ParameterError("refusing to write a parameter file: " + path + " is " + std::to_string(node.get<double>()) +
                         " (a result that is not finite)");
  }
  if (node.is_object()) {
    for (const auto& item : node.items()) requireFiniteNumbers(item.value(), path + "." + item.key());
  } else if (node.is_array()) {
    for (std::size_t k = 0; k < node.size(); ++k) requireFiniteNumbers(node[k], path + "[" + std::to_string(k) + "]");
  }
}

ToolTarget toolFromJson(const nlohmann::json& node, const std::string& path) {
  JsonFields fields(node, path);
  ToolTarget tool;
  tool.flange_link = fields.text("flange_link");
  tool.link = fields.text("link");
  const std::vector<double> target = fields.numbers("target_in_flange_m", 3);
  for (int a = 0; a < 3; ++a) {
    if (!(std::abs(target[static_cast<std::size_t>(a)]) <= 10.0)) {
      fields.fail("target_in_flange_m", "a target more than 10 m from the flange");
    }
    tool.in_flange[a] = target[static_cast<std::size_t>(a)];
  }
  fields.rejectUnknownKeys();
  return tool;
}

// One quantity stated twice (a compliance effect listed twice, two tables of one joint's gear stage) would be
// summed silently: every parameter name may come from one entry only.
void refuseRepeatedParameters(const std::vector<std::unique_ptr<Effect>>& effects, const JsonFields& fields) {
  std::map<std::string, std::size_t> giver;
  for (std::size_t i = 0; i < effects.size(); ++i) {
    for (const std::string& name : effects[i]->parameterNames()) {
      const auto [first, inserted] = giver.emplace(name, i);
      if (!inserted) {
        fields.fail("effects[" + std::to_string(i) + "]",
                    effects[i]->type() + " states " + name + ", which effects[" + std::to_string(first->second) +
                        "] (" + effects[first->second]->type() +
                        ") states already; list each effect of a joint once (they would be summed)");
      }
    }
  }
}

// What is written reads back: the document goes through the reader (the built-in effect types; one of
// another registry is left to that registry's reader), so that a command never writes a file it refuses.
void requireReadable(const nlohmann::ordered_json& document, const JointErrorModel& model) {
  const std::vector<std::string> known = EffectRegistry::builtin().effectTypes();
  nlohmann::ordered_json checked = document;
  nlohmann::ordered_json& effects = checked["effects"];
  nlohmann::ordered_json kept = nlohmann::ordered_json::array();
  for (const auto& effect : effects) {
    if (std::find(known.begin(), known.end(), effect.value("type", "")) != known.end()) kept.push_back(effect);
  }
  effects = kept;
  try {
    parseParameterSet(checked.dump(), "the parameter file to be written", model.sharedRobot(),
                      EffectRegistry::builtin());
  } catch (const ParameterError& error) {
    throw ParameterError(std::string("refusing to write a parameter file its own reader refuses: ") + error.what());
  }
}

BaseFrame baseFrameFromJson(const nlohmann::json& node, const std::string& path) {
  JsonFields fields(node, path);
  BaseFrame frame;
  frame.base_link = fields.text("base_link");
  frame.link = fields.text("link");
  const std::vector<double> xyz = fields.numbers("base_xyz_m", 3);
  const std::vector<double> rpy = fields.numbers("base_rpy_rad", 3);
  for (int a = 0; a < 3; ++a) {
    if (!(std::abs(xyz[static_cast<std::size_t>(a)]) <= 100.0)) fields.fail("base_xyz_m", "more than 100 m away");
    if (!(std::abs(rpy[static_cast<std::size_t>(a)]) <= 10.0)) fields.fail("base_rpy_rad", "an angle beyond 10 rad");
  }
  frame.base_in_frame.translation() = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
  frame.base_in_frame.linear() = rpyToRotation(Eigen::Vector3d(rpy[0], rpy[1], rpy[2]));
  fields.rejectUnknownKeys();
  return frame;
}

}  // namespace

ParameterSet parseParameterSet(const std::string& json_text, const std::string& source_name,
                               std::shared_ptr<const Robot> robot, const EffectRegistry& registry) {
  if (!robot) throw InvalidArgument("parameters need a robot");
  const nlohmann::json document = parseDocument(json_text, source_name);
  JsonFields fields(document, source_name + ": ");
  const std::string format = fields.text("format");
  if (format != kFormat) fields.fail("format", "expected \"" + std::string(kFormat) + "\", found \"" + format + "\"");
  const std::string robot_name = fields.text("robot");
  if (robot_name != robot->name) {
    fields.fail("robot", "the file is for robot '" + robot_name + "' but the URDF describes '" + robot->name + "'");
  }
  const std::string notes = fields.textOr("notes", "");
  std::vector<DriveParameters> drives;
  if (fields.has("plant")) drives = drivesFromJson(fields.object("plant"), *robot, source_name + ": plant");
  GearTrain gears = fields.has("gears") ? GearTrain::fromJson(fields.object("gears"), *robot, fields.pathOf("gears"))
                                        : GearTrain::direct(robot->dof());
  std::optional<ToolTarget> tool;
  if (fields.has("tool")) tool = toolFromJson(fields.object("tool"), source_name + ": tool");
  std::optional<BaseFrame> base_frame;
  if (fields.has("base_frame")) {
    base_frame = baseFrameFromJson(fields.object("base_frame"), source_name + ": base_frame");
    if (base_frame->base_link != robot->root_link) {
      fields.fail("base_frame", "its base_link '" + base_frame->base_link + "' is not the URDF's root link '" +
                                    robot->root_link + "'");
    }
  }
  std::vector<std::unique_ptr<Effect>> effects;
  const nlohmann::json& list = fields.array("effects");
  for (std::size_t i = 0; i < list.size(); ++i) {
    effects.push_back(registry.create(list[i], *robot, gears, fields.pathOf("effects[" + std::to_string(i) + "]")));
  }
  fields.rejectUnknownKeys();
  refuseRepeatedParameters(effects, fields);
  JointErrorModel model(std::move(robot), std::move(gears), std::move(effects));
  model.notes = notes;
  return ParameterSet{std::move(model), std::move(drives), std::move(tool), std::move(base_frame)};
}

ParameterSet loadParameterSet(const std::string& path, std::shared_ptr<const Robot> robot,
                              const EffectRegistry& registry) {
  return parseParameterSet(readParameterText(path), path, std::move(robot), registry);
}

ParameterSet loadParameterSet(const std::string& path, std::shared_ptr<const Robot> robot) {
  return loadParameterSet(path, std::move(robot), EffectRegistry::builtin());
}

JointErrorModel parseParameters(const std::string& json_text, const std::string& source_name,
                                std::shared_ptr<const Robot> robot) {
  return parseParameterSet(json_text, source_name, std::move(robot), EffectRegistry::builtin()).model;
}

JointErrorModel loadParameterFile(const std::string& path, std::shared_ptr<const Robot> robot) {
  return loadParameterSet(path, std::move(robot)).model;
}

std::vector<DriveParameters> parseDriveParameters(const std::string& json_text, const std::string& source_name,
                                                  const Robot& robot) {
  const nlohmann::json document = parseDocument(json_text, source_name);
  if (!document.is_object() || !document.contains("plant")) {
    throw ParameterError(source_name + ": no \"plant\" object (drives and controller gains) for the plant");
  }
  return drivesFromJson(document.at("plant"), robot, source_name + ": plant");
}

std::vector<DriveParameters> loadDriveParameters(const std::string& path, const Robot& robot) {
  return parseDriveParameters(readParameterText(path), path, robot);
}

std::string parametersToJson(const JointErrorModel& model, const std::vector<DriveParameters>& drives,
                             const ToolTarget* tool, const BaseFrame* base_frame) {
  nlohmann::ordered_json document;
  document["format"] = kFormat;
  document["robot"] = model.robot().name;
  if (!model.notes.empty()) document["notes"] = model.notes;
  document["gears"] = model.gears().toJson(model.robot());
  nlohmann::json effects = nlohmann::json::array();
  for (int i = 0; i < model.effectCount(); ++i) effects.push_back(model.effect(i).toJson());
  document["effects"] = effects;
  if (!drives.empty()) document["plant"] = drivesToJson(drives, model.robot());
  if (tool) {
    document["tool"] = {{"flange_link", tool->flange_link},
                        {"link", tool->link},
                        {"target_in_flange_m", {tool->in_flange.x(), tool->in_flange.y(), tool->in_flange.z()}}};
  }
  if (base_frame) {
    const Eigen::Vector3d t = base_frame->base_in_frame.translation();
    const Eigen::Vector3d rpy = rotationToRpy(base_frame->base_in_frame.linear());
    document["base_frame"] = {{"base_link", base_frame->base_link},
                              {"link", base_frame->link},
                              {"base_xyz_m", {t.x(), t.y(), t.z()}},
                              {"base_rpy_rad", {rpy.x(), rpy.y(), rpy.z()}}};
  }
  requireFiniteNumbers(document, "parameters");
  std::string text = document.dump(2) + "\n";
  requireReadable(document, model);
  return text;
}

void saveParameterFile(const JointErrorModel& model, const std::string& path,
                       const std::vector<DriveParameters>& drives, const ToolTarget* tool,
                       const BaseFrame* base_frame) {
  writeFileAtomically(path, parametersToJson(model, drives, tool, base_frame));
}

void saveCalibratedRobot(const JointErrorModel& model, const std::vector<DriveParameters>& drives,
                         const ToolTarget* tool, const BaseFrame* base_frame, const std::string& urdf_path,
                         const std::string& urdf_comment, const std::string& parameter_path) {
  const Robot& robot = model.robot();
  if (!urdf_path.empty()) {
    std::optional<UrdfToolLink> tool_link;
    if (tool && tool->flange_link == robot.tip_link) tool_link = UrdfToolLink{tool->link, tool->in_flange};
    std::optional<UrdfFrameLink> frame_link;
    if (base_frame && base_frame->base_link == robot.root_link) {
      frame_link = UrdfFrameLink{base_frame->link, base_frame->base_in_frame};
    }
    saveRobotUrdf(robot, urdf_path, urdf_comment, tool_link ? &*tool_link : nullptr,
                  frame_link ? &*frame_link : nullptr);
  }
  if (!parameter_path.empty()) saveParameterFile(model, parameter_path, drives, tool, base_frame);
}

}  // namespace jointcomp
