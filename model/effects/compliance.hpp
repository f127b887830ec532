// Joint compliance: each joint's transmission twists under the torque it carries, dq = -tau / K
// (the link lags the motor by the deflection of the joint spring). The default stiffnesses of the RX170
// are the paper's Table I. A joint may be rigid (stiffness +infinity inside, null in the file) when its
// compliance is not known or cannot be identified.
#pragma once

#include "model/effects/discovery_family.hpp"
#include "model/effects/effect.hpp"
#include "model/effects/per_joint_effect.hpp"

namespace jointcomp {

class ComplianceEffect : public PerJointEffect {
public:
  static constexpr const char* kType = "compliance";
  // Throws ParameterError for the wrong number of stiffnesses or one that is not positive.
  ComplianceEffect(const Robot& robot, const std::vector<double>& stiffness_nm_per_rad);
  static std::unique_ptr<Effect> fromJson(const nlohmann::json& json, const Robot& robot, const std::string& path);

  // The file format: the fields (and scalars) the parameter file holds.
  static const std::vector<Field>& layout();  // "<joint>.stiffness_nm_per_rad"
  static std::unique_ptr<Effect> fromValues(const Robot& robot, const std::vector<double>& values,
                                            const std::vector<double>& scalars);

  std::string type() const override { return kType; }
  EffectRole role() const override { return EffectRole::JointError; }
  void addJointError(const Robot& robot, const JointContext& ctx, JointVector& dq) const override;
  std::unique_ptr<Effect> clone() const override { return std::make_unique<ComplianceEffect>(*this); }

  double stiffness(int joint) const { return field(0)[static_cast<std::size_t>(joint)]; }
  bool isJointSpring() const override { return true; }
  double jointStiffness(int joint) const override { return stiffness(joint); }

  // The physical constraint of a joint's compliance c (rad/(N m)), which the calibration and discovery
  // respect: positive, a stiffness 1/c of at least kMinPlausibleStiffness, and a deflection c |tau| of at
  // most kMaxPlausibleDeflection at the largest torque the joint carried in the data. Empty when `c` meets
  // it, else why not (naming `joint`).
  static constexpr double kMinPlausibleStiffness = 100.0;  // N m/rad: 1 N m turns such a joint by 0.57 deg
  static constexpr double kMaxPlausibleDeflection = 0.01;  // rad
  static std::string implausibility(double compliance, double largest_torque, const std::string& joint);
  std::optional<CalibrationParameter> calibrationParameter() const override { return CalibrationParameter::Compliance; }
  double calibrationValue(int joint) const override { return compliance_[joint]; }

private:
  void parametersChanged() override;
  JointVector compliance_;  // rad / (N m), 1 / stiffness
};

// Discovery: "compliance", a joint's linear compliance under its load torque, freed in the kinematic
// calibration (offered when the robot has inertials, so that the torque is known).
class ComplianceDiscovery : public CalibrationParameterDiscovery {
public:
  ComplianceDiscovery() : CalibrationParameterDiscovery("compliance", CalibrationParameter::Compliance, true) {}
};

}  // namespace jointcomp
