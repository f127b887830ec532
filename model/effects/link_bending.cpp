#include "model/effects/link_bending.hpp"

#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {
namespace {
constexpr double kParallel = 1e-6;  // |z_a x z_b| below this: parallel axes
constexpr double kShortest = 1e-2;  // m: a shorter lever is a joint's offset, not a link that bends
}  // namespace

std::vector<double> parallelLinkLevers(const Robot& robot) {
  const int n = robot.dof();
  std::vector<double> lever(static_cast<std::size_t>(n), 0.0);
  RobotWorkspace ws(robot);
  // Two consecutive axes keep their angle and distance at every pose (the near joint turns both alike):
  // the zero pose tells.
  forwardKinematics(robot, ws, JointVector::Zero(n));
  for (int a = 0; a + 1 < n; ++a) {
    const Eigen::Vector3d& z = ws.axis[a];
    if (z.cross(ws.axis[a + 1]).norm() > kParallel) continue;
    const Eigen::Vector3d span = ws.origin[a + 1] - ws.origin[a];
    const double distance = (span - span.dot(z) * z).norm();
    if (distance >= kShortest) lever[static_cast<std::size_t>(a)] = distance;
  }
  return lever;
}

const std::vector<PerJointEffect::Field>& LinkBendingEffect::layout() {
  static const std::vector<Field> fields = {{"deflection_m_per_n", "link_bending_deflection_m_per_n"}};
  return fields;
}

LinkBendingEffect::LinkBendingEffect(const Robot& robot, const std::vector<double>& deflection_m_per_n)
    : PerJointEffect(robot, layout()), lever_(parallelLinkLevers(robot)) {
  setParameters(deflection_m_per_n);
}

void LinkBendingEffect::setParameters(const std::vector<double>& values) {
  const std::vector<std::string> names = parameterNames();
  for (std::size_t j = 0; j < values.size() && j < lever_.size(); ++j) {
    if (values[j] != 0.0 && lever_[j] == 0.0 && std::isfinite(values[j])) {
      throw ParameterError(std::string(kType) + ": " + names[j] +
                           " must be 0: the next joint's axis is not parallel to this joint's (or there is none), "
                           "so no link between them bends in their plane");
    }
  }
  PerJointEffect::setParameters(values);
}

std::unique_ptr<Effect> LinkBendingEffect::fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain&,
                                                    const std::string& path) {
  return readAs<LinkBendingEffect>(json, robot, path);
}

std::unique_ptr<Effect> LinkBendingEffect::fromValues(const Robot& robot, const std::vector<double>& values,
                                                      const std::vector<double>&) {
  return std::make_unique<LinkBendingEffect>(robot, values);
}

void LinkBendingEffect::addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const {
  if (ctx.load_torque.size() != dq.size()) return;
  const std::vector<double>& deflection = field(0);
  for (std::size_t i = 0; i + 1 < deflection.size(); ++i) {
    if (deflection[i] == 0.0) continue;
    const int a = static_cast<int>(i);
    const double turn = deflection[i] * feature(ctx.load_torque[a], ctx.load_torque[a + 1], lever_[i]);
    dq[a] += turn;
    dq[a + 1] -= turn;
  }
}

void LinkBendingDiscovery::offer(const DiscoveryData& data, int joint,
                                 std::vector<DiscoveryCandidate>& candidates) const {
  if (joint < 0 || !data.torque_known) return;
  const std::vector<double> levers = parallelLinkLevers(*data.robot);
  const double lever = levers[static_cast<std::size_t>(joint)];
  if (lever == 0.0) return;
  const int n = data.robot->dof();
  DiscoveryCandidate candidate;
  candidate.type = name();
  candidate.joint = joint;
  candidate.detail = " (link to " + jointNameOf(data, joint + 1) + ")";
  candidate.report_fields = {{"next_joint", jointNameOf(data, joint + 1)}, {"lever_m", lever}};
  candidate.joint_error_blocks = true;
  candidate.columns = Eigen::MatrixXd::Zero(data.rows(), n);
  for (int i = 0; i < data.rows(); ++i) {
    const JointVector& tau = data.load_torque[static_cast<std::size_t>(i)];
    const double near = LinkBendingEffect::feature(tau[joint], tau[joint + 1], lever);
    candidate.columns(i, joint) = near;
    candidate.columns(i, joint + 1) = -near;
  }
  candidates.push_back(std::move(candidate));
}

std::unique_ptr<Effect> LinkBendingDiscovery::makeEffect(const DiscoveryData& data,
                                                         const std::vector<FittedCandidate>& accepted) const {
  std::vector<double> per_joint(static_cast<std::size_t>(data.robot->dof()), 0.0);
  for (const FittedCandidate& a : accepted) per_joint[static_cast<std::size_t>(a.candidate->joint)] += a.theta[0];
  return std::make_unique<LinkBendingEffect>(*data.robot, per_joint);
}

std::vector<NamedEstimate> LinkBendingDiscovery::describe(const FittedCandidate& fitted,
                                                          const JointErrorModel& model) const {
  const std::size_t joint = static_cast<std::size_t>(fitted.candidate->joint);
  const std::string& name = model.robot().joints[joint].name;
  std::vector<NamedEstimate> out = {{name + ".link_bending_deflection_m_per_n", fitted.theta[0], fitted.sigma[0]}};
  // The bending stiffness a tube loaded at its end would have, E I = L^3 / (3 s), when s says it sags.
  const double lever = parallelLinkLevers(model.robot())[joint];
  if (fitted.theta[0] > 0.0) {
    const double stiffness = lever * lever * lever / (3.0 * fitted.theta[0]);
    out.push_back({name + ".link_bending_stiffness_n_m2", stiffness, stiffness * fitted.sigma[0] / fitted.theta[0]});
  }
  return out;
}

std::string LinkBendingDiscovery::physicalProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                                                  const Eigen::VectorXd& theta, const JointVector& compliance) const {
  if (candidate.joint >= 0 && theta.size() == 1 && theta[0] < 0.0) {
    char text[300];
    std::snprintf(text, sizeof(text),
                  "not physical: the link from %s to the next joint would bend against its load (deflection "
                  "%.3g m/N is negative; a beam's L^3 / (3 E I) is positive)",
                  jointNameOf(data, candidate.joint).c_str(), theta[0]);
    return text;
  }
  return jointErrorBeyondThePlausible(data, candidate, theta, compliance);
}

}  // namespace jointcomp
