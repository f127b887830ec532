#include "model/effects/nonlinear_compliance.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"

namespace jointcomp {

const std::vector<PerJointEffect::Field>& NonlinearComplianceEffect::layout() {
  static const std::vector<Field> fields = {{"cubic_compliance_rad_per_nm3", "cubic_compliance_rad_per_nm3"}};
  return fields;
}

NonlinearComplianceEffect::NonlinearComplianceEffect(const Robot& robot, const std::vector<double>& cubic_rad_per_nm3)
    : PerJointEffect(robot, layout()) {
  setParameters(cubic_rad_per_nm3);
}

std::unique_ptr<Effect> NonlinearComplianceEffect::fromJson(const nlohmann::json& json, const Robot& robot,
                                                            const GearTrain&, const std::string& path) {
  return readAs<NonlinearComplianceEffect>(json, robot, path);
}

std::unique_ptr<Effect> NonlinearComplianceEffect::fromValues(const Robot& robot, const std::vector<double>& values,
                                                              const std::vector<double>&) {
  return std::make_unique<NonlinearComplianceEffect>(robot, values);
}

void NonlinearComplianceEffect::addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const {
  if (ctx.load_torque.size() != dq.size()) return;
  const std::vector<double>& cubic = field(0);
  for (std::size_t i = 0; i < cubic.size(); ++i) {
    const int j = static_cast<int>(i);
    dq[j] += cubic[i] * feature(ctx.load_torque[j]);
  }
}

double NonlinearComplianceDiscovery::feature(const DiscoveryData& data, int row, int joint) const {
  return NonlinearComplianceEffect::feature(data.load_torque[row][joint]);
}

std::unique_ptr<Effect> NonlinearComplianceDiscovery::effectOf(const DiscoveryData& data,
                                                               const std::vector<double>& width) const {
  return std::make_unique<NonlinearComplianceEffect>(*data.robot, width);
}

}  // namespace jointcomp
