// Link bending: a long link between two parallel joints (the UR10's upper arm and forearm) bends under the
// shear force it carries, so its far end moves sideways, perpendicular to the link in the plane the joints
// move in, by delta = s * F (s in m/N, F the shear in N). Joint compliance cannot say this: it turns the
// whole distal arm about the joint axis, so the far end moves with the link's slope, whereas a bent link's
// end moves more than its slope carries it (a cantilever: L^3 / 3EI against L^2 / 2EI).
//
// Because the two axes are parallel, the end's sideways move is exactly a turn of the near joint by
// delta / L and the opposite turn of the far joint (the distal arm moves, its orientation does not), so
// the effect is a joint error and reaches the compensator, the plant and the FMU through the registry like
// every other. The shear comes from the load torques the compliance uses: the difference of the two
// joints' torques is the moment the link carries from one axis to the other, tau_a - tau_b = L F (the
// link's own weight counted at its centre of mass, where it bends the link too):
//   dq_a = -s / L^2 (tau_a - tau_b),  dq_b = +s / L^2 (tau_a - tau_b)
// (signs like the compliance's: the link sags the way gravity pulls). s = L^3 / (3 E I) for a tube of
// bending stiffness E I loaded at its end. Parameter file, one value per joint, the link from that joint
// to the next (0 where the next joint is not parallel or there is none):
//   {"type": "link_bending", "deflection_m_per_n": [n values]}
#pragma once

#include "model/effects/discovery_family.hpp"
#include "model/effects/effect.hpp"
#include "model/effects/gear_train.hpp"
#include "model/effects/per_joint_effect.hpp"

namespace jointcomp {

// Per joint, the distance (m) from its axis to the next joint's axis when the two are parallel, else 0:
// the lever over which the link between them bends.
std::vector<double> parallelLinkLevers(const Robot& robot);

class LinkBendingEffect : public PerJointEffect {
public:
  static constexpr const char* kType = "link_bending";
  // Throws ParameterError for the wrong number of values, one not finite, or a nonzero value on a joint
  // whose next joint is not parallel to it (naming the joint).
  LinkBendingEffect(const Robot& robot, const std::vector<double>& deflection_m_per_n);
  static std::unique_ptr<Effect> fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                          const std::string& path);

  static const std::vector<Field>& layout();  // "<joint>.link_bending_deflection_m_per_n"
  static std::unique_ptr<Effect> fromValues(const Robot& robot, const std::vector<double>& values,
                                            const std::vector<double>& scalars);

  std::string type() const override { return kType; }
  EffectRole role() const override { return EffectRole::JointError; }
  void setParameters(const std::vector<double>& values) override;
  void addJointError(const Robot& robot, const JointContext& ctx, JointVector& dq) const override;
  std::unique_ptr<Effect> clone() const override { return std::make_unique<LinkBendingEffect>(*this); }

  const std::vector<double>& levers() const { return lever_; }
  // The error of the near joint per unit deflection coefficient (the far joint's is its negative).
  static double feature(double tau_near, double tau_far, double lever) {
    return -(tau_near - tau_far) / (lever * lever);
  }

private:
  std::vector<double> lever_;  // m, per joint; 0: no parallel next joint
};

// Discovery: "link_bending", one candidate per link between parallel joints, one coefficient (s) moving
// both of its joints (needs the load torque).
class LinkBendingDiscovery : public DiscoveryFamily {
public:
  std::string name() const override { return "link_bending"; }
  void offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const override;
  std::unique_ptr<Effect> makeEffect(const DiscoveryData& data,
                                     const std::vector<FittedCandidate>& accepted) const override;
  std::vector<NamedEstimate> describe(const FittedCandidate& fitted, const JointErrorModel& model) const override;
  // A link bends the way its load pushes it (s = L^3 / (3 E I) > 0) and by little: its joints' turns stay
  // within the shared plausible bound over the fitted rows.
  std::string physicalProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                              const Eigen::VectorXd& theta, const JointVector& compliance) const override;
};

}  // namespace jointcomp
