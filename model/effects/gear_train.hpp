// The gear stages between each motor and its joint, and the coupling between axes (the Staubli wrist
// drives joint 6 from motor 5 too): motor angles = G * joint angles, G = diag(total ratios) + coupling.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "model/robot/robot.hpp"

namespace jointcomp {

class JsonFields;

class GearTrain {
public:
  // Every joint driven directly (ratio 1, one stage), no coupling.
  static GearTrain direct(int dof);
  // Reads the "gears" object of a parameter file; `path` names it in messages.
  static GearTrain fromJson(const nlohmann::json& gears, const Robot& robot, const std::string& path);
  nlohmann::json toJson(const Robot& robot) const;

  int dof() const { return static_cast<int>(stage_ratios_.size()); }
  int stageCount(int joint) const { return static_cast<int>(stage_ratios_[joint].size()); }
  const std::vector<double>& stageRatios(int joint) const { return stage_ratios_[joint]; }
  // Teeth of the gear on each stage's input shaft (the gear-mesh order per revolution of that shaft), from
  // the optional "stage_input_teeth"; 0 where not given.
  int stageInputTeeth(int joint, int stage) const { return stage_input_teeth_[joint][stage - 1]; }
  double totalRatio(int joint) const { return motor_from_joint_(joint, joint); }
  const JointMatrix& motorFromJoint() const { return motor_from_joint_; }

  // motor = G * joint angles.
  void motorAngles(const JointVector& joint_angles, JointVector& motor) const;
  // Angle of the input shaft of stage `stage` (1 = the motor, stageCount + 1 = the output) of a joint.
  double stageInputAngle(int joint, int stage, const JointVector& motor) const {
    return motor[joint] / ratio_before_[joint][stage - 1];  // inline: compensation's fixed point calls it per harmonic
  }
  // d(stage input angle)/d(motor angle) of a joint: 1 over the ratios of the stages before it.
  double stageInputPerMotor(int joint, int stage) const { return 1.0 / ratio_before_[joint][stage - 1]; }

  // The parts of a joint's train by name, as parameter files and reports write them: "motor" (stage 1),
  // "stage_K" (the input of stage K) and "output" (stageCount + 1).
  std::string partName(int joint, int stage) const;
  // The stage of a part's name ("stage_1" is the motor too), 0 when the joint has no such part.
  int stageOfPart(int joint, const std::string& part) const;
  // The stages of a joint whose parts turn at different speeds (a stage of ratio 1 repeats the part
  // before it; of parts that turn alike the last, so a directly driven joint's is its output): the parts a
  // periodic error of the joint may be a function of, each once.
  std::vector<int> distinctParts(int joint) const;

private:
  std::vector<std::vector<double>> stage_ratios_;    // per joint, motor side first
  std::vector<std::vector<int>> stage_input_teeth_;  // per joint and stage; 0: not known
  std::vector<std::vector<double>> ratio_before_;    // product of the ratios before each stage input
  JointMatrix motor_from_joint_;
  void updateDerived();
};

// The stage of the part a parameter file's entry names in "of" ("motor", "stage_K", "output"); fails
// naming the entry and the parts the joint has.
int readPart(JsonFields& entry, const GearTrain& gears, int joint, const std::string& joint_name);

}  // namespace jointcomp
