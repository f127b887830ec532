// Joint offsets: each joint's zero is off by a constant, dq = offset (link angle minus commanded angle).
// The kinematic calibration (model/identify) fits them together with the link geometry. Parameter file:
//   {"type": "offset", "offset_rad": [n values]}
#pragma once

#include "model/effects/discovery_family.hpp"
#include "model/effects/effect.hpp"
#include "model/effects/gear_train.hpp"
#include "model/effects/per_joint_effect.hpp"

namespace jointcomp {

class JointOffsetEffect : public PerJointEffect {
public:
  static constexpr const char* kType = "offset";
  // Throws ParameterError for the wrong number of offsets or a value that is not finite.
  JointOffsetEffect(const Robot& robot, const std::vector<double>& offsets_rad);
  // The gear train is not used; the signature is the registry's.
  static std::unique_ptr<Effect> fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                          const std::string& path);

  // The file format: the fields (and scalars) the parameter file holds.
  static const std::vector<Field>& layout();  // "<joint>.offset_rad"
  static std::unique_ptr<Effect> fromValues(const Robot& robot, const std::vector<double>& values,
                                            const std::vector<double>& scalars);

  std::string type() const override { return kType; }
  EffectRole role() const override { return EffectRole::JointError; }
  void addJointError(const Robot& robot, const JointContext& ctx, JointVector& dq) const override;
  std::unique_ptr<Effect> clone() const override { return std::make_unique<JointOffsetEffect>(*this); }

  double offset(int joint) const { return field(0)[static_cast<std::size_t>(joint)]; }
  std::optional<CalibrationParameter> calibrationParameter() const override { return CalibrationParameter::Offset; }
  double calibrationValue(int joint) const override { return offset(joint); }
};

// Discovery: "offset", a joint's zero, freed in the kinematic calibration.
class JointOffsetDiscovery : public CalibrationParameterDiscovery {
public:
  JointOffsetDiscovery() : CalibrationParameterDiscovery("offset", CalibrationParameter::Offset, false) {}
};

}  // namespace jointcomp
