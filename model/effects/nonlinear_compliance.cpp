#include "model/effects/nonlinear_compliance.hpp"

#include <cstdio>

#include <algorithm>

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

std::string NonlinearComplianceDiscovery::physicalProblem(const DiscoveryData& data,
                                                          const DiscoveryCandidate& candidate,
                                                          const Eigen::VectorXd& theta,
                                                          const JointVector& compliance) const {
  const int j = candidate.joint;
  if (j < 0 || theta.size() != 1) return {};
  const double most = largestTorque(data, j);  // N m, the largest torque the joint carried in the fitted rows
  const double linear = j < compliance.size() ? std::max(0.0, compliance[j]) : 0.0;
  char text[240];
  const double deflection = std::abs(linear * most + theta[0] * most * most * most);
  if (deflection > kMaxPlausibleJointError) {
    std::snprintf(text, sizeof(text),
                  "not physical: %s deflects by %.3g rad at %.4g N m (compliance %.4g rad/(N m), cubic %.4g "
                  "rad/(N m)^3), beyond the plausible %.3g rad",
                  jointNameOf(data, j).c_str(), deflection, most, linear, theta[0], kMaxPlausibleJointError);
    return text;
  }
  if (theta[0] >= 0.0 || linear + 3.0 * theta[0] * most * most > 0.0) return {};
  std::snprintf(text, sizeof(text),
                "not physical: %s's deflection turns back at %.4g N m, inside the fitted torques (up to %.4g N m): "
                "compliance %.4g rad/(N m), cubic %.4g rad/(N m)^3",
                jointNameOf(data, j).c_str(), std::sqrt(linear / (-3.0 * theta[0])), most, linear, theta[0]);
  return text;
}

std::unique_ptr<Effect> NonlinearComplianceDiscovery::effectOf(const DiscoveryData& data,
                                                               const std::vector<double>& width) const {
  return std::make_unique<NonlinearComplianceEffect>(*data.robot, width);
}

}  // namespace jointcomp
