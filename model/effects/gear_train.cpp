#include "model/effects/gear_train.hpp"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"

namespace jointcomp {

GearTrain GearTrain::direct(int dof) {
  GearTrain gears;
  gears.stage_ratios_.assign(dof, std::vector<double>{1.0});
  gears.stage_input_teeth_.assign(dof, std::vector<int>{0});
  gears.motor_from_joint_ = JointMatrix::Identity(dof, dof);
  gears.updateDerived();
  return gears;
}

void GearTrain::updateDerived() {
  ratio_before_.clear();
  for (const auto& stages : stage_ratios_) {
    std::vector<double> before{1.0};
    for (double ratio : stages) before.push_back(before.back() * ratio);
    ratio_before_.push_back(before);
  }
}

GearTrain GearTrain::fromJson(const nlohmann::json& gears_json, const Robot& robot, const std::string& path) {
  GearTrain gears = direct(robot.dof());
  JsonFields fields(gears_json, path);
  const nlohmann::json& joints = fields.array("joints");
  if (static_cast<int>(joints.size()) != robot.dof()) {
    fields.fail("joints", "expected one entry per joint (" + std::to_string(robot.dof()) + "), found " +
                              std::to_string(joints.size()));
  }
  for (int j = 0; j < robot.dof(); ++j) {
    JsonFields joint(joints[j], fields.pathOf("joints[" + std::to_string(j) + "]"));
    const std::string name = joint.text("joint");
    if (name != robot.joints[j].name) joint.fail("joint", "expected '" + robot.joints[j].name + "' at this position");
    std::vector<double> ratios = joint.numbers("stage_ratios");
    if (ratios.empty()) joint.fail("stage_ratios", "needs at least one stage");
    double total = 1.0;
    for (std::size_t k = 0; k < ratios.size(); ++k) {
      if (ratios[k] == 0.0) joint.fail("stage_ratios[" + std::to_string(k) + "]", "must not be zero");
      total *= ratios[k];
    }
    gears.stage_ratios_[j] = ratios;
    gears.stage_input_teeth_[j].assign(ratios.size(), 0);
    if (joint.has("stage_input_teeth")) {
      const std::vector<double> teeth = joint.numbers("stage_input_teeth");
      if (teeth.size() != ratios.size()) {
        joint.fail("stage_input_teeth", "expected one tooth count per stage (" + std::to_string(ratios.size()) +
                                            "), found " + std::to_string(teeth.size()));
      }
      for (std::size_t k = 0; k < teeth.size(); ++k) {
        if (!(teeth[k] >= 0.0 && teeth[k] <= 10000.0) || teeth[k] != std::floor(teeth[k]))
          joint.fail("stage_input_teeth[" + std::to_string(k) + "]",
                     "must be a whole number from 0 (not known) to 10000");
        gears.stage_input_teeth_[j][k] = static_cast<int>(teeth[k]);
      }
    }
    gears.motor_from_joint_(j, j) = total;
    joint.rejectUnknownKeys();
  }
  if (fields.has("coupling")) {
    const nlohmann::json& coupling = fields.array("coupling");
    for (std::size_t c = 0; c < coupling.size(); ++c) {
      JsonFields entry(coupling[c], fields.pathOf("coupling[" + std::to_string(c) + "]"));
      const std::string motor_name = entry.text("motor_of");
      const std::string joint_name = entry.text("joint");
      int motor = -1;
      int joint = -1;
      for (int j = 0; j < robot.dof(); ++j) {
        if (robot.joints[j].name == motor_name) motor = j;
        if (robot.joints[j].name == joint_name) joint = j;
      }
      if (motor < 0) entry.fail("motor_of", "no joint named '" + motor_name + "'");
      if (joint < 0) entry.fail("joint", "no joint named '" + joint_name + "'");
      if (motor == joint) entry.fail("joint", "coupling must be between two different joints");
      gears.motor_from_joint_(motor, joint) = entry.number("motor_rad_per_joint_rad");
      entry.rejectUnknownKeys();
    }
  }
  fields.rejectUnknownKeys();
  gears.updateDerived();
  return gears;
}

nlohmann::json GearTrain::toJson(const Robot& robot) const {
  nlohmann::json joints = nlohmann::json::array();
  for (int j = 0; j < dof(); ++j) {
    nlohmann::json entry = {{"joint", robot.joints[j].name}, {"stage_ratios", stage_ratios_[j]}};
    const auto& teeth = stage_input_teeth_[j];
    if (std::any_of(teeth.begin(), teeth.end(), [](int t) { return t > 0; })) entry["stage_input_teeth"] = teeth;
    joints.push_back(entry);
  }
  nlohmann::json coupling = nlohmann::json::array();
  for (int m = 0; m < dof(); ++m) {
    for (int j = 0; j < dof(); ++j) {
      if (m != j && motor_from_joint_(m, j) != 0.0) {
        coupling.push_back({{"motor_of", robot.joints[m].name},
                            {"joint", robot.joints[j].name},
                            {"motor_rad_per_joint_rad", motor_from_joint_(m, j)}});
      }
    }
  }
  nlohmann::json result = {{"joints", joints}};
  if (!coupling.empty()) result["coupling"] = coupling;
  return result;
}

void GearTrain::motorAngles(const JointVector& joint_angles, JointVector& motor) const {
  motor.noalias() = motor_from_joint_ * joint_angles;
}

std::string GearTrain::partName(int joint, int stage) const {
  if (stage == 1) return "motor";
  if (stage == stageCount(joint) + 1) return "output";
  return "stage_" + std::to_string(stage);
}

int GearTrain::stageOfPart(int joint, const std::string& part) const {
  for (int stage = 1; stage <= stageCount(joint) + 1; ++stage) {
    // "stage_1", the input of stage 1, is the motor by another name.
    if (partName(joint, stage) == part || (stage <= stageCount(joint) && part == "stage_" + std::to_string(stage)))
      return stage;
  }
  return 0;
}

std::vector<int> GearTrain::distinctParts(int joint) const {
  // The angle of a part per unit joint angle, from a unit joint move through G (coupling included).
  const int n = dof();
  JointVector unit = JointVector::Zero(n), motor(n);
  unit[joint] = 1.0;
  motorAngles(unit, motor);
  std::vector<int> stages;
  std::vector<double> ratios;
  for (int stage = 1; stage <= stageCount(joint) + 1; ++stage) {
    const double ratio = stageInputAngle(joint, stage, motor);
    // Of parts that turn alike the last is named: a directly driven joint's one part is its output.
    bool seen = false;
    for (std::size_t k = 0; k < ratios.size(); ++k) {
      if (std::abs(ratios[k] - ratio) > 1e-9 * std::max(1.0, std::abs(ratios[k]))) continue;
      stages[k] = stage;
      seen = true;
    }
    if (seen) continue;
    ratios.push_back(ratio);
    stages.push_back(stage);
  }
  return stages;
}

int readPart(JsonFields& entry, const GearTrain& gears, int joint, const std::string& joint_name) {
  const std::string part = entry.text("of");
  const int stage = gears.stageOfPart(joint, part);
  if (stage == 0) {
    entry.fail("of", "expected \"motor\", \"stage_K\" (K = 1 .. " + std::to_string(gears.stageCount(joint)) +
                         ", the input of stage K) or \"output\" for " + joint_name + ", found \"" + part.substr(0, 40) +
                         "\"");
  }
  return stage;
}

}  // namespace jointcomp
