#include "model/identify/identification_support.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "model/common/errors.hpp"
#include "model/common/median.hpp"
#include "model/effects/compliance.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp::identify_detail {

std::string formatNumber(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

void checkCampaign(const Robot& robot, const MeasurementCampaign& campaign, bool needs_base_frame, const char* method) {
  campaign.validate();
  if (campaign.dof != robot.dof()) {
    throw InvalidArgument(campaign.source + ": the campaign has " + std::to_string(campaign.dof) + " joints, robot '" +
                          robot.name + "' has " + std::to_string(robot.dof()));
  }
  if (!campaign.robot.empty() && campaign.robot != robot.name) {
    throw InvalidArgument(campaign.source + ": the campaign is of robot '" + campaign.robot + "', the model of '" +
                          robot.name + "'");
  }
  if (needs_base_frame && campaign.frame != MeasurementFrame::Base) {
    throw MeasurementError(campaign.source + ": " + method +
                           " needs positions in the robot base frame (frame: base); this campaign is in the "
                           "instrument's frame: calibrate the frame first");
  }
  for (std::size_t k = 0; k < campaign.size(); ++k) {
    if (!campaign.wrench[k].allFinite()) {
      throw MeasurementError(campaign.source + ": row " + std::to_string(k + 1) + ": the wrench is not finite");
    }
    if (!std::isfinite(campaign.payload[k]) || campaign.payload[k] < 0.0) {
      throw MeasurementError(campaign.source + ": row " + std::to_string(k + 1) + ": the payload is not a finite mass");
    }
    if (campaign.has_position) {
      const Eigen::Vector3d& p = campaign.position[k];
      if (std::isinf(p.x()) || std::isinf(p.y()) || std::isinf(p.z()) || std::isnan(p.x()) != std::isnan(p.y()) ||
          std::isnan(p.x()) != std::isnan(p.z())) {
        throw MeasurementError(campaign.source + ": row " + std::to_string(k + 1) +
                               ": x, y, z must be finite, or all three not measured");
      }
    }
  }
}

Eigen::Vector3d targetOf(const MeasurementCampaign& campaign) {
  return campaign.has_target ? campaign.target_in_flange : Eigen::Vector3d::Zero();
}

Vector6 toolWrenchOf(const Vector6& at_target, const RobotWorkspace& ws, const Eigen::Vector3d& target_in_flange) {
  Vector6 tool = at_target;
  const Eigen::Vector3d offset = ws.tool_pose.linear() * target_in_flange;
  tool.tail<3>() += offset.cross(at_target.head<3>());
  return tool;
}

RowPrediction predictRow(const JointErrorModel& nominal, const MeasurementCampaign& campaign, std::size_t k,
                         JointErrorWorkspace& ws) {
  const Robot& robot = nominal.robot();
  const Eigen::Vector3d target = targetOf(campaign);
  JointContext ctx(robot.dof());
  ctx.command = campaign.command[k];
  ctx.velocity = JointVector::Zero(robot.dof());
  ctx.time = campaign.time[k];
  ctx.payload_mass = campaign.payload[k];
  ctx.payload_com = target;
  const EffectMask mask = nominal.loadsAnd({ComplianceEffect::kType});
  RowPrediction prediction;
  ctx.q = ctx.command;
  forwardKinematics(robot, ws.robot, ctx.command);
  ctx.tool_wrench = toolWrenchOf(campaign.wrench[k], ws.robot, target);
  updateMotorAngles(nominal, ctx);
  computeLoadTorque(nominal, mask, ws, ctx);
  prediction.commanded_torque = ctx.load_torque;
  // Two passes: the moment of the force about the tool point is taken where the target settles.
  const int passes = campaign.wrench[k].isZero(0.0) ? 1 : 2;
  for (int pass = 0; pass < passes; ++pass) {
    ctx.tool_wrench = toolWrenchOf(campaign.wrench[k], ws.robot, target);
    const FixedPointReport report = settleStatically(nominal, mask, ws, ctx);
    if (!report.converged) {
      throw SolverError(campaign.source + ": row " + std::to_string(k + 1) +
                        ": the nominal model does not settle under the row's load");
    }
    forwardKinematics(robot, ws.robot, ctx.q);
  }
  prediction.settled = ctx.q;
  computeLoadTorque(nominal, mask, ws, ctx);
  prediction.torque = ctx.load_torque;
  return prediction;
}

double angleAboutAxis(const Eigen::Vector3d& axis, const Eigen::Vector3d& origin, const Eigen::Vector3d& from,
                      const Eigen::Vector3d& to, double* lever) {
  Eigen::Vector3d a = from - origin;
  Eigen::Vector3d b = to - origin;
  a -= axis * axis.dot(a);
  b -= axis * axis.dot(b);
  if (lever) *lever = a.norm();
  return std::atan2(axis.dot(a.cross(b)), a.dot(b));
}

bool fillUnknownSigma(std::vector<double>& sigma) {
  std::vector<double> known;
  for (double s : sigma) {
    if (std::isfinite(s) && s > 0.0) known.push_back(s);
  }
  const double fill = known.empty() ? 1.0 : median(known);
  for (double& s : sigma) {
    if (!(std::isfinite(s) && s > 0.0)) s = fill;
  }
  return !known.empty();
}

std::vector<std::pair<std::size_t, std::size_t>> poseGroups(const MeasurementCampaign& campaign) {
  std::vector<std::pair<std::size_t, std::size_t>> groups;
  std::size_t first = 0;
  for (std::size_t k = 1; k <= campaign.size(); ++k) {
    if (k == campaign.size() || (campaign.command[k] - campaign.command[first]).cwiseAbs().maxCoeff() > 1e-9) {
      groups.emplace_back(first, k);
      first = k;
    }
  }
  return groups;
}

}  // namespace jointcomp::identify_detail
