#include "model/effects/discovery_family.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "model/effects/joint_error_model.hpp"

namespace jointcomp {

std::string DiscoveryCandidate::label() const {
  if (joint < 0) return type + (detail.empty() ? std::string(" (robot)") : detail);
  return type + " joint " + std::to_string(joint + 1) + detail;
}

std::unique_ptr<Effect> DiscoveryFamily::makeEffect(const DiscoveryData&, const std::vector<FittedCandidate>&) const {
  return nullptr;
}

std::vector<NamedEstimate> DiscoveryFamily::describe(const FittedCandidate&, const JointErrorModel&) const {
  return {};
}

std::string DiscoveryFamily::physicalProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                                             const Eigen::VectorXd& theta, const JointVector& compliance) const {
  return jointErrorBeyondThePlausible(data, candidate, theta, compliance);
}

LargestJointError largestJointError(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                                    const Eigen::VectorXd& theta, const JointVector& compliance) {
  LargestJointError most;
  const int dof = data.robot->dof();
  if (candidate.columns.size() == 0 || theta.size() != candidate.coefficients(dof)) return most;
  auto consider = [&most](double dq, int joint, int row) {
    if (!(std::abs(dq) <= most.value) && !std::isnan(most.value)) most = {std::abs(dq), joint, row};
  };
  const int rows = static_cast<int>(candidate.columns.rows());
  if (!candidate.through_compliance && !candidate.joint_error_blocks) {
    if (candidate.joint < 0) return most;
    const Eigen::VectorXd dq = candidate.columns * theta;
    for (int i = 0; i < rows; ++i) consider(dq[i], candidate.joint, i);
    return most;
  }
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < dof && j < compliance.size(); ++j) {
      double sum = 0.0;
      for (int k = 0; k < theta.size(); ++k) sum += candidate.columns(i, k * dof + j) * theta[k];
      consider(candidate.through_compliance ? compliance[j] * sum : sum, j, i);
    }
  }
  return most;
}

std::string jointErrorBeyondThePlausible(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                                         const Eigen::VectorXd& theta, const JointVector& compliance) {
  const LargestJointError most = largestJointError(data, candidate, theta, compliance);
  if (most.value <= kMaxPlausibleJointError) return {};
  char text[300];
  std::snprintf(text, sizeof(text),
                "not physical: %s turns %s by %.3g rad at fitted row %d, beyond the plausible %.3g rad",
                candidate.label().c_str(), jointNameOf(data, most.joint).c_str(), most.value, most.row + 1,
                kMaxPlausibleJointError);
  return text;
}

const std::string& jointNameOf(const DiscoveryData& data, int joint) {
  return data.robot->joints[static_cast<std::size_t>(joint)].name;
}

double largestTorque(const DiscoveryData& data, int joint) {
  double most = 0.0;
  for (const JointVector& torque : data.load_torque) {
    if (joint < torque.size()) most = std::max(most, std::abs(torque[joint]));
  }
  return most;
}

double partAnglePerJointAngle(const DiscoveryData& data, int joint, int stage) {
  const int n = data.robot->dof();
  JointVector unit = JointVector::Zero(n), unit_motor(n);
  unit[joint] = 1.0;
  data.gears->motorAngles(unit, unit_motor);
  return data.gears->stageInputAngle(joint, stage, unit_motor);
}

std::string transmissionProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate, double largest_error,
                                double largest_part_slope) {
  const int j = candidate.joint;
  const double slope = std::abs(largest_part_slope * partAnglePerJointAngle(data, j, candidate.stage));
  char text[300];
  if (!(largest_error <= kMaxPlausibleJointError)) {
    std::snprintf(text, sizeof(text),
                  "not physical: %s's %s%s turns the joint by %.3g rad, beyond the plausible %.3g rad",
                  jointNameOf(data, j).c_str(), candidate.type.c_str(), candidate.detail.c_str(), largest_error,
                  kMaxPlausibleJointError);
  } else if (!(slope < kMaxTransmissionSlope)) {
    std::snprintf(text, sizeof(text),
                  "not physical: %s's %s%s changes by %.3g rad per rad of the joint: the link would turn against "
                  "the motor (the most a transmission error may is %.3g)",
                  jointNameOf(data, j).c_str(), candidate.type.c_str(), candidate.detail.c_str(), slope,
                  kMaxTransmissionSlope);
  } else {
    return {};
  }
  return text;
}

void CalibrationParameterDiscovery::offer(const DiscoveryData& data, int joint,
                                          std::vector<DiscoveryCandidate>& candidates) const {
  if (joint < 0 || (needs_torque_ && !data.torque_known)) return;
  DiscoveryCandidate candidate;
  candidate.type = name_;
  candidate.joint = joint;
  candidate.releases = {parameter_};
  candidates.push_back(std::move(candidate));
}

void InstrumentScaleDiscovery::offer(const DiscoveryData&, int joint,
                                     std::vector<DiscoveryCandidate>& candidates) const {
  if (joint >= 0) return;
  DiscoveryCandidate candidate;
  candidate.type = name();
  candidate.detail = " of the fitted campaigns' set-up";
  candidate.releases = {CalibrationParameter::InstrumentScale};
  candidates.push_back(std::move(candidate));
}

void PerJointFeatureDiscovery::offer(const DiscoveryData& data, int joint,
                                     std::vector<DiscoveryCandidate>& candidates) const {
  if (joint < 0 || (needs_torque_ && !data.torque_known)) return;
  DiscoveryCandidate candidate;
  candidate.type = name_;
  candidate.joint = joint;
  candidate.columns = featureColumn(data, [&](int i) { return feature(data, i, joint); });
  candidates.push_back(std::move(candidate));
}

std::unique_ptr<Effect> PerJointFeatureDiscovery::makeEffect(const DiscoveryData& data,
                                                             const std::vector<FittedCandidate>& accepted) const {
  std::vector<double> per_joint(static_cast<std::size_t>(data.robot->dof()), 0.0);
  for (const FittedCandidate& a : accepted) per_joint[static_cast<std::size_t>(a.candidate->joint)] += a.theta[0];
  return effectOf(data, per_joint);
}

std::vector<NamedEstimate> PerJointFeatureDiscovery::describe(const FittedCandidate& fitted,
                                                              const JointErrorModel& model) const {
  const std::string& joint = model.robot().joints[static_cast<std::size_t>(fitted.candidate->joint)].name;
  return {{joint + "." + parameter_, fitted.theta[0], fitted.sigma[0]}};
}

}  // namespace jointcomp
