// `jointcomp export-fmu`: an FMI 2.0 or 3.0 co-simulation FMU of any robot the project loads, from its URDF
// and parameter file. One binary serves every robot: the robot travels in the FMU's resources (robot.json,
// parameters.json), and modelDescription.xml is written here from the same variable table the binary builds
// again from those resources at instantiation (fmu/description). Everything the FMU will need is proved
// here first (the robot reads back from robot.json bit for bit, the parameter file fits the robot and has
// drives, the plant builds), so that an FMU that was written instantiates.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <sys/stat.h>
#include <nlohmann/json.hpp>

#include "cli/commands.hpp"
#include "cli/file_locations.hpp"
#include "cli/options.hpp"
#include "cli/output_paths.hpp"
#include "cli/robot_setup.hpp"
#include "fmu/description/fmu_archive.hpp"
#include "fmu/description/model_description_xml.hpp"
#include "fmu/description/variable_table.hpp"
#include "fmu/robot/fmu_plant_options.hpp"
#include "model/common/errors.hpp"
#include "model/effects/registry.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/parameter_file.hpp"
#include "model/io/robot_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp::cli {
namespace {

bool isRegularFile(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode);
}

std::string baseName(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// A path as a shell word for a printed command: as it is when plain, else in single quotes.
std::string shellWord(const std::string& text) {
  bool plain = !text.empty();
  for (const char c : text) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    std::string("_./-=+,:@%").find(c) != std::string::npos;
    plain = plain && ok;
  }
  if (plain) return text;
  std::string quoted = "'";
  for (const char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

// The shipped parameter file of the robot of that name, if there is one with drives ("" otherwise).
std::string shippedDrivesFile(const std::string& robot_name) {
  const std::string path = parameterFile(plainFileName(robot_name));
  if (!isRegularFile(path)) return "";
  try {
    const nlohmann::json file = nlohmann::json::parse(readTextFile(path, "parameter file", kMaxJsonFileBytes));
    return file.is_object() && file.contains("plant") ? path : "";
  } catch (const std::exception&) {
    return "";
  }
}

nlohmann::ordered_json readJsonObject(const std::string& path, const std::string& option) {
  const std::string text = readTextFile(path, "parameter file", kMaxJsonFileBytes);
  nlohmann::ordered_json json;
  try {
    json = nlohmann::ordered_json::parse(text);
  } catch (const nlohmann::json::exception& error) {
    throw ParameterError(path + " (" + option + "): not JSON: " + error.what());
  }
  if (!json.is_object()) throw ParameterError(path + " (" + option + "): not a JSON object");
  return json;
}

// The parameter file the FMU carries: --params as given when it has drives (its "plant" object), else
// with the "plant" object of --drives, or of the shipped parameter file of the robot's name. Refused,
// with the reason and what to do, when there are none. The caller reads the text as a parameter set.
struct FmuParameters {
  std::string text;  // resources/parameters.json
  std::string source;
  std::string note = "";  // what export-fmu changed, for the user
};

// The FMU's plant is a flexible-joint model: every joint needs a finite spring. A joint the parameter file
// calls rigid (a null stiffness, as calibrate writes for a compliance it could not see in the data, or no
// compliance effect at all) gets --rigid-stiffness, by default ten times the file's stiffest joint (1e6
// N m/rad when it has none): stiff enough that its deflection is negligible, soft enough for the
// integrator. The file carried in the FMU says so, and so does the command.
FmuParameters withRigidJointsStiffened(FmuParameters parameters, const Options& options, const Robot& robot) {
  nlohmann::ordered_json json = nlohmann::ordered_json::parse(parameters.text);
  nlohmann::ordered_json* compliance = nullptr;
  for (auto& effect : json["effects"]) {
    if (effect.is_object() && effect.value("type", "") == "compliance") compliance = &effect;
  }
  double stiffest = 0.0;
  if (compliance) {
    for (const auto& k : (*compliance)["stiffness_nm_per_rad"]) {
      if (k.is_number()) stiffest = std::max(stiffest, k.get<double>());
    }
  }
  const double fill = options.has("rigid-stiffness") ? options.number("rigid-stiffness", 0.0, {1000.0, 1e12})
                                                     : (stiffest > 0.0 ? 10.0 * stiffest : 1e6);
  std::vector<std::string> stiffened;
  if (!compliance) {
    json["effects"].push_back(
        {{"type", "compliance"}, {"stiffness_nm_per_rad", std::vector<double>(robot.joints.size(), fill)}});
    for (const Joint& joint : robot.joints) stiffened.push_back(joint.name);
  } else {
    auto& values = (*compliance)["stiffness_nm_per_rad"];
    for (std::size_t j = 0; j < values.size() && j < robot.joints.size(); ++j) {
      if (values[j].is_null()) {
        values[j] = fill;
        stiffened.push_back(robot.joints[j].name);
      }
    }
  }
  if (stiffened.empty()) return parameters;
  std::string joints;
  for (const std::string& name : stiffened) joints += (joints.empty() ? "" : ", ") + name;
  char value[64];
  std::snprintf(value, sizeof value, "%g N m/rad", fill);
  parameters.note = "rigid in the parameter file, given the stiffness " + std::string(value) +
                    " in the FMU (its plant needs a spring in every joint; --rigid-stiffness sets it): " + joints;
  json["notes"] =
      json.value("notes", std::string()) + (json.contains("notes") ? " " : "") + "export-fmu: " + parameters.note;
  parameters.text = json.dump(2) + "\n";
  return parameters;
}

FmuParameters fmuParameters(const Options& options, const std::shared_ptr<const Robot>& robot) {
  const std::string params = options.get("params", "");
  const std::string text = readTextFile(params, "parameter file", kMaxJsonFileBytes);
  if (parseParameterSet(text, params, robot, EffectRegistry::builtin()).hasDrives()) {
    if (options.has("drives"))
      throw std::invalid_argument("--drives: " + params +
                                  " has drives of its own (its \"plant\" object); give --drives "
                                  "only for a parameter file without them");
    return {text, params};
  }
  const std::string drives = options.has("drives") ? options.get("drives", "") : shippedDrivesFile(robot->name);
  if (drives.empty()) {
    throw Error(params +
                " has no drives (no \"plant\" object: each joint's motor inertia, friction and controller "
                "gains), which the FMU's flexible-joint plant needs, and jointcomp ships no parameter file for "
                "the robot '" +
                robot->name +
                "' that has them. Give --drives PARAMS.json, a parameter file whose "
                "\"plant\" object has one entry per joint of " +
                robot->name + " (" + parameterFile("rx170") + " shows the format)");
  }
  const nlohmann::ordered_json drives_json = readJsonObject(drives, "--drives");
  if (!drives_json.contains("plant"))
    throw ParameterError(drives + " (--drives): has no \"plant\" object (the drives and their controllers)");
  nlohmann::ordered_json merged = readJsonObject(params, "--params");
  merged["plant"] = drives_json["plant"];
  return {merged.dump(2) + "\n", params + " with the drives of " + drives};
}

// The robot of --urdf and its JSON form, which must read back bit for bit (the FMU's binary reads that).
std::string robotJson(const Options& options, std::shared_ptr<const Robot>& robot) {
  const std::string urdf = options.get("urdf", "");
  const Robot loaded = loadRobotFromUrdfFile(urdf, chainOptions(options));
  const std::string text = robotToJson(loaded);
  robot = std::make_shared<const Robot>(robotFromJson(text, "robot.json"));
  if (!sameRobot(loaded, *robot))
    throw Error(urdf +
                ": the robot does not read back bit for bit from its JSON form (robot.json), which the FMU reads");
  return text;
}

fmu::ModelAttributes modelAttributes(const Robot& robot) {
  fmu::ModelAttributes model;
  model.version = JOINTCOMP_VERSION;
  model.description =
      "Flexible-joint robot plant (integrated by SUNDIALS CVODE) with offline joint-error "
      "compensation in front of it (Olabi et al., IEEE ICIT 2012), for the robot " +
      robot.name + " and its parameters under resources/";
  return model;
}

// --fmi and --out, checked before any work: the version, a .fmu name, a folder that takes it, the binary.
int checkedVersion(const Options& options, const std::string& out) {
  const int version = static_cast<int>(options.integer("fmi", 2, 2, 3));
  if (out.size() < 5 || out.compare(out.size() - 4, 4, ".fmu") != 0)
    throw UsageError("--out: '" + out + "' does not end in .fmu (the file importers take)");
  prepareOutputFile(out);
  const FmuParts parts = fmuParts(version);
  for (const std::string& path : {parts.binary, parts.documentation, parts.license}) {
    if (!isRegularFile(path))
      throw Error("the FMI " + std::to_string(version) + " FMU's " + baseName(path) + " is not at " + path +
                  (fileLocations().installed ? " (install the fmu component)" : " (build the target jointcomp_fmus)"));
  }
  return version;
}

std::vector<fmu::ArchiveEntry> archiveEntries(const fmu::VariableTable& table, int version,
                                              const std::string& robot_json, const std::string& parameters_json,
                                              const std::string& urdf) {
  const FmuParts parts = fmuParts(version);
  std::string urdf_name = plainFileName(baseName(urdf), "robot.urdf");
  if (urdf_name == "robot.json" || urdf_name == "parameters.json") urdf_name = "robot.urdf";
  return {
      {"modelDescription.xml", fmu::modelDescriptionXml(table, version), false},
      {"binaries/" + parts.platform + "/jointcomp.so", readTextFile(parts.binary, "FMU binary"), true},
      {"resources/robot.json", robot_json, false},
      {"resources/parameters.json", parameters_json, false},
      {"resources/" + urdf_name, readTextFile(urdf, "URDF", kMaxJsonFileBytes), false},
      {"documentation/index.html", readTextFile(parts.documentation, "FMU documentation", kMaxJsonFileBytes), false},
      {"documentation/variables.html", fmu::variablesHtml(table), false},
      {"documentation/licenses/LICENSE.txt", readTextFile(parts.license, "licence", kMaxJsonFileBytes), false}};
}

}  // namespace

std::string exportFmuCommand(const std::string& urdf, const std::string& parameters, bool has_drives,
                             const std::string& robot_name, const std::string& fmu) {
  std::string command = "jointcomp export-fmu --urdf " + shellWord(urdf) + " --params " + shellWord(parameters);
  if (!has_drives && shippedDrivesFile(robot_name).empty()) {
    return command + " --drives DRIVES.json --out " + shellWord(fmu) + "\n  (" + parameters +
           " has no drives, its \"plant\" object, and jointcomp ships none for " + robot_name +
           ": DRIVES.json is a parameter file whose \"plant\" object has them)";
  }
  return command + " --out " + shellWord(fmu);
}

int runExportFmu(int argc, char** argv) {
  const Options options(argc, argv,
                        {"urdf", "params", "drives", "base-link", "tip-link", "fmi", "out", "rigid-stiffness"}, {},
                        "export-fmu");
  if (!options.has("urdf") || !options.has("params") || !options.has("out"))
    throw UsageError("export-fmu needs --urdf FILE, --params FILE and --out ROBOT.fmu (and --fmi 2|3, --drives FILE)");
  const std::string out = options.get("out", "");
  const int version = checkedVersion(options, out);

  std::shared_ptr<const Robot> robot;
  const std::string robot_json = robotJson(options, robot);
  const FmuParameters parameters = withRigidJointsStiffened(fmuParameters(options, robot), options, *robot);
  const ParameterSet set = parseParameterSet(parameters.text, parameters.source, robot, EffectRegistry::builtin());
  FlexibleJointPlant plant(set.model, set.drives, fmuPlantOptions());  // what the FMU builds must build
  const std::string token = fmu::instantiationToken(robot_json, parameters.text, JOINTCOMP_VERSION);
  const fmu::VariableTable table = fmu::buildVariableTable(*robot, set, modelAttributes(*robot), token);
  const std::vector<fmu::ArchiveEntry> entries =
      archiveEntries(table, version, robot_json, parameters.text, options.get("urdf", ""));
  fmu::writeZipArchive(out, entries);

  std::printf("jointcomp export-fmu: robot %s, %d joints (%s), parameters %s\n", robot->name.c_str(), robot->dof(),
              options.get("urdf", "").c_str(), parameters.source.c_str());
  if (!parameters.note.empty()) std::printf("note: %s\n", parameters.note.c_str());
  std::printf("wrote %s: FMI %d.0 co-simulation, %d variables, instantiation token %s\n", out.c_str(), version,
              table.size(), token.c_str());
  for (const fmu::ArchiveEntry& entry : entries)
    std::printf("  %-40s %9zu bytes\n", entry.path.c_str(), entry.contents.size());
  std::printf(
      "next: load %s into an FMI %d.0 co-simulation importer (FMPy, fmusim, your simulator); a plain run "
      "follows the built-in demo move, documentation/index.html inside says how to drive it\n",
      out.c_str(), version);
  return 0;
}

}  // namespace jointcomp::cli
