#include "model/effects/compliance.hpp"

#include <cstdio>

#include <cmath>
#include <limits>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"

namespace jointcomp {

const std::vector<PerJointEffect::Field>& ComplianceEffect::layout() {
  static const std::vector<Field> fields = {{"stiffness_nm_per_rad", "stiffness_nm_per_rad", Check::PositiveOrRigid}};
  return fields;
}

ComplianceEffect::ComplianceEffect(const Robot& robot, const std::vector<double>& stiffness_nm_per_rad)
    : PerJointEffect(robot, layout()) {
  setParameters(stiffness_nm_per_rad);
}

std::unique_ptr<Effect> ComplianceEffect::fromJson(const nlohmann::json& json, const Robot& robot,
                                                   const std::string& path) {
  return readAs<ComplianceEffect>(json, robot, path);
}

std::unique_ptr<Effect> ComplianceEffect::fromValues(const Robot& robot, const std::vector<double>& values,
                                                     const std::vector<double>&) {
  return std::make_unique<ComplianceEffect>(robot, values);
}

std::string ComplianceEffect::implausibility(double compliance, double largest_torque, const std::string& joint) {
  char text[240];
  if (!(compliance > 0.0)) {
    std::snprintf(text, sizeof(text), "%s: compliance %.3g rad/(N m) is not positive", joint.c_str(), compliance);
  } else if (1.0 / compliance < kMinPlausibleStiffness) {
    std::snprintf(text, sizeof(text), "%s: stiffness %.3g N m/rad is below the plausible %.0f N m/rad", joint.c_str(),
                  1.0 / compliance, kMinPlausibleStiffness);
  } else if (compliance * largest_torque > kMaxPlausibleDeflection) {
    std::snprintf(
        text, sizeof(text),
        "%s: stiffness %.3g N m/rad deflects the joint by %.3g rad at %.3g N m, beyond the plausible %.3g rad",
        joint.c_str(), 1.0 / compliance, compliance * largest_torque, largest_torque, kMaxPlausibleDeflection);
  } else {
    return {};
  }
  return text;
}

void ComplianceEffect::parametersChanged() {
  const std::vector<double>& stiffness = field(0);
  compliance_.resize(static_cast<int>(stiffness.size()));
  for (std::size_t i = 0; i < stiffness.size(); ++i) compliance_[static_cast<int>(i)] = 1.0 / stiffness[i];
}

void ComplianceEffect::addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const {
  dq -= ctx.load_torque.cwiseProduct(compliance_);
}

}  // namespace jointcomp
