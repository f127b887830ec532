// Nonlinear (stiffening or softening) compliance: the cubic term of the joint spring beyond the linear
// "compliance" effect, dq_j = -c3_j * tau_j^3 with tau_j the joint's load torque (N m). c3 > 0 softens
// the joint under load, c3 < 0 stiffens it. Parameter file:
//   {"type": "nonlinear_compliance", "cubic_compliance_rad_per_nm3": [n values]}
#pragma once

#include "model/effects/discovery_family.hpp"
#include "model/effects/effect.hpp"
#include "model/effects/gear_train.hpp"
#include "model/effects/per_joint_effect.hpp"

namespace jointcomp {

class NonlinearComplianceEffect : public PerJointEffect {
public:
  static constexpr const char* kType = "nonlinear_compliance";
  // Throws ParameterError for the wrong number of coefficients or one that is not finite.
  NonlinearComplianceEffect(const Robot& robot, const std::vector<double>& cubic_rad_per_nm3);
  static std::unique_ptr<Effect> fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                          const std::string& path);

  // The file format: the fields (and scalars) the parameter file holds.
  static const std::vector<Field>& layout();  // "<joint>.cubic_compliance_rad_per_nm3"
  static std::unique_ptr<Effect> fromValues(const Robot& robot, const std::vector<double>& values,
                                            const std::vector<double>& scalars);

  std::string type() const override { return kType; }
  EffectRole role() const override { return EffectRole::JointError; }
  void addJointError(const Robot& robot, const JointContext& ctx, JointVector& dq) const override;
  std::unique_ptr<Effect> clone() const override { return std::make_unique<NonlinearComplianceEffect>(*this); }

  static double feature(double torque) { return -torque * torque * torque; }
};

// Discovery: "nonlinear_compliance", one column per joint, tau_j^3 (needs the load torque). Physical only when
// the joint's whole deflection c1 tau + c3 tau^3 grows with the torque over the fitted rows' torques
// (c1 + 3 c3 tau^2 > 0): a softening that turns the deflection back is refused; and that deflection stays
// within kMaxPlausibleJointError at the largest torque.
class NonlinearComplianceDiscovery : public PerJointFeatureDiscovery {
public:
  NonlinearComplianceDiscovery()
      : PerJointFeatureDiscovery("nonlinear_compliance", "cubic_compliance_rad_per_nm3", true) {}
  std::string physicalProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                              const Eigen::VectorXd& theta, const JointVector& compliance) const override;

protected:
  double feature(const DiscoveryData& data, int row, int joint) const override;
  std::unique_ptr<Effect> effectOf(const DiscoveryData& data, const std::vector<double>& width) const override;
};

}  // namespace jointcomp
