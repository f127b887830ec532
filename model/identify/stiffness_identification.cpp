#include "model/identify/stiffness_identification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/common/errors.hpp"
#include "model/common/median.hpp"
#include "model/effects/compliance.hpp"
#include "model/identify/identification_statistics.hpp"
#include "model/identify/identification_support.hpp"
#include "model/io/instrument_noise.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {
namespace {

using namespace identify_detail;

constexpr double kInfinity = std::numeric_limits<double>::infinity();

enum class GroupKind { Unused, LocalTracker, LocalLevels, Global };

struct Group {
  std::size_t first = 0, last = 0;  // rows [first, last): consecutive, same pose, loads along one direction
  int pose = 0;                     // index of the pose (consecutive rows with the same command)
  GroupKind kind = GroupKind::Unused;
  std::vector<int> level_joints;   // LocalLevels: joints with level readings
  int joint = -1;                  // LocalTracker: the tested joint
  std::vector<RowPrediction> row;  // per row: the nominal model's settled pose and torques there
  const JointVector& torque(std::size_t k) const { return row[k - first].torque; }
};

struct Classified {
  std::vector<Group> groups;
  int poses = 0;
  std::vector<double> sigma;  // per row, position noise (NaN unknown)
};

// The load of a row as one vector: the wrench and the payload.
Eigen::Matrix<double, 7, 1> loadOf(const MeasurementCampaign& campaign, std::size_t k) {
  Eigen::Matrix<double, 7, 1> load;
  load << campaign.wrench[k], campaign.payload[k];
  return load;
}

// Rows of one pose split where the load changes direction: each part is a ladder of loads along one
// direction (unloaded rows go with the part they follow, or the next one at the start).
std::vector<std::pair<std::size_t, std::size_t>> directionParts(const MeasurementCampaign& campaign, std::size_t first,
                                                                std::size_t last) {
  std::vector<std::pair<std::size_t, std::size_t>> parts;
  std::size_t start = first;
  Eigen::Matrix<double, 7, 1> direction = Eigen::Matrix<double, 7, 1>::Zero();
  for (std::size_t k = first; k < last; ++k) {
    const Eigen::Matrix<double, 7, 1> load = loadOf(campaign, k);
    const double norm = load.norm();
    if (norm == 0.0) continue;
    if (direction.isZero(0.0)) {
      direction = load / norm;
    } else if (std::abs(direction.dot(load / norm)) < 1.0 - 1e-9) {
      parts.emplace_back(start, k);
      start = k;
      direction = load / norm;
    }
  }
  parts.emplace_back(start, last);
  return parts;
}

// Distinct non-zero load magnitudes of a part (signed along its direction).
int distinctLoadLevels(const MeasurementCampaign& campaign, std::size_t first, std::size_t last) {
  std::vector<double> levels;
  Eigen::Matrix<double, 7, 1> direction = Eigen::Matrix<double, 7, 1>::Zero();
  for (std::size_t k = first; k < last; ++k) {
    const Eigen::Matrix<double, 7, 1> load = loadOf(campaign, k);
    if (load.isZero(0.0)) continue;
    if (direction.isZero(0.0)) direction = load.normalized();
    const double level = direction.dot(load);
    bool seen = false;
    for (double other : levels)
      seen = seen || std::abs(other - level) <= 1e-9 * std::max(std::abs(level), std::abs(other));
    if (!seen) levels.push_back(level);
  }
  return static_cast<int>(levels.size());
}

Classified classify(const JointErrorModel& nominal, const MeasurementCampaign& campaign,
                    const StiffnessIdentificationOptions& options) {
  const int n = nominal.robot().dof();
  JointErrorWorkspace ws(nominal.robot());
  Classified result;
  result.sigma = positionSigmaPerRow(campaign);
  for (const auto& pose_rows : poseGroups(campaign)) {
    for (const auto& range : directionParts(campaign, pose_rows.first, pose_rows.second)) {
      Group group;
      group.first = range.first;
      group.last = range.second;
      group.pose = result.poses;
      JointVector low = JointVector::Constant(n, kInfinity);
      JointVector high = JointVector::Constant(n, -kInfinity);
      for (std::size_t k = range.first; k < range.second; ++k) {
        group.row.push_back(predictRow(nominal, campaign, k, ws));
        // Which joints a load turns is decided to first order, at the commanded pose.
        low = low.cwiseMin(group.row.back().commanded_torque);
        high = high.cwiseMax(group.row.back().commanded_torque);
      }
      const JointVector spread = high - low;
      if (campaign.has_measured_angles) {
        for (int j = 0; j < n; ++j) {
          int readings = 0;
          for (std::size_t k = range.first; k < range.second; ++k)
            readings += std::isfinite(campaign.measured_angles[k][j]) ? 1 : 0;
          if (readings >= 2 && spread[j] > 0.0) group.level_joints.push_back(j);
        }
      }
      const double scale = std::max(1.0, high.cwiseAbs().maxCoeff());
      if (!group.level_joints.empty()) {
        group.kind = GroupKind::LocalLevels;
      } else if (spread.maxCoeff() > 1e-12 * scale) {
        int j = 0;
        spread.maxCoeff(&j);
        bool dominant = true;
        for (int i = 0; i < n; ++i) dominant = dominant && (i == j || spread[i] * options.dominance_ratio <= spread[j]);
        // A local test is a ladder: at least three load levels along its direction.
        dominant = dominant && distinctLoadLevels(campaign, range.first, range.second) >= 3;
        group.kind = dominant ? GroupKind::LocalTracker : GroupKind::Global;
        group.joint = j;
      }
      result.groups.push_back(std::move(group));
    }
    ++result.poses;
  }
  return result;
}

bool hasPosition(const MeasurementCampaign& campaign, std::size_t k) {
  return campaign.has_position && campaign.position[k].allFinite();
}

void checkOptions(const StiffnessIdentificationOptions& options) {
  if (!(options.confidence > 0.0 && options.confidence < 1.0))
    throw InvalidArgument("stiffness identification: confidence must lie in (0, 1)");
  if (!(options.dominance_ratio > 1.0))
    throw InvalidArgument("stiffness identification: dominance_ratio must exceed 1");
  if (!(options.max_relative_error > 0.0))
    throw InvalidArgument("stiffness identification: max_relative_error must be positive");
}

// K = 1/c with its interval as the image of c's.
void fillStiffness(StiffnessEstimate& e, double c, double se, double t_factor) {
  e.compliance = c;
  e.compliance_se = se;
  if (!(c > 0.0)) {
    e.identified = false;
    e.reason = "the deflection does not grow with the torque (compliance " + formatNumber(c) + " rad/(N m))";
    return;
  }
  e.stiffness = 1.0 / c;
  e.stiffness_se = se / (c * c);
  const double c_low = c - t_factor * se;
  const double c_high = c + t_factor * se;
  e.stiffness_low = 1.0 / c_high;
  e.stiffness_high = c_low > 0.0 ? 1.0 / c_low : kInfinity;
  e.identified = true;
}

}  // namespace

namespace {

// One local test's observation: the pose's intercept, the joint's torque, its deflection (link - command)
// and the deflection's 1-sigma noise.
struct Observation {
  int group;
  double torque, deflection, sigma;
};

// The observations of joint j's local tests: from its levels when the campaign has any for it, else from
// the tracker (the angle about the joint's axis, less what the other joints' deflections add). `groups`:
// the poses, one intercept each.
std::vector<Observation> localObservations(const Robot& robot, const MeasurementCampaign& campaign,
                                           const Classified& classified, int j, bool& by_levels, int& groups) {
  const Eigen::Vector3d target = targetOf(campaign);
  RobotWorkspace ws(robot);
  RobotWorkspace settled(robot);
  std::vector<Observation> observations;
  by_levels = false;
  for (const Group& g : classified.groups)
    by_levels = by_levels || std::count(g.level_joints.begin(), g.level_joints.end(), j) > 0;
  std::vector<int> intercept_of_pose(classified.poses, -1);
  groups = 0;
  for (const Group& g : classified.groups) {
    const bool levels_here = std::count(g.level_joints.begin(), g.level_joints.end(), j) > 0;
    const bool tracker_here = !by_levels && g.kind == GroupKind::LocalTracker && g.joint == j;
    if (!levels_here && !tracker_here) continue;
    const int before = static_cast<int>(observations.size());
    const int intercept = intercept_of_pose[g.pose] >= 0 ? intercept_of_pose[g.pose] : groups;
    for (std::size_t k = g.first; k < g.last; ++k) {
      const double tau = g.torque(k)[j];
      if (levels_here) {
        const double qm = campaign.measured_angles[k][j];
        if (!std::isfinite(qm)) continue;
        observations.push_back(
            {intercept, tau, qm - campaign.command[k][j],
             campaign.angle_noise > 0.0 ? campaign.angle_noise : std::numeric_limits<double>::quiet_NaN()});
      } else {
        if (!hasPosition(campaign, k)) continue;
        const RowPrediction& predicted = g.row[k - g.first];
        forwardKinematics(robot, settled, predicted.settled);
        forwardKinematics(robot, ws, campaign.command[k]);
        const Eigen::Vector3d nominal_target = ws.tool_pose * target;
        double lever = 0.0;
        const double measured = angleAboutAxis(ws.axis[j], ws.origin[j], nominal_target, campaign.position[k], &lever);
        // What the other joints' deflections add to the angle about this axis, as the nominal model
        // predicts it (a few per cent of the signal: the load is designed for the commanded pose, the
        // links sag under gravity, and soft joints pick up the difference).
        const double predicted_angle =
            angleAboutAxis(ws.axis[j], ws.origin[j], nominal_target, settled.tool_pose * target);
        const double cross_talk = predicted_angle - (predicted.settled[j] - campaign.command[k][j]);
        const double angle = measured - cross_talk;
        if (lever < 1e-3) {
          throw MeasurementError(campaign.source + ": local stiffness test of " + robot.joints[j].name + " (rows " +
                                 std::to_string(g.first + 1) + "-" + std::to_string(g.last) +
                                 "): the target is within 1 mm of the joint's axis, so the tracker cannot see it turn");
        }
        observations.push_back({intercept, tau, angle, classified.sigma[k] / lever});
      }
    }
    if (static_cast<int>(observations.size()) > before && intercept_of_pose[g.pose] < 0)
      intercept_of_pose[g.pose] = groups++;
  }
  return observations;
}

// The slope of deflection against torque, one intercept per pose: the joint's compliance and its interval.
void fitLocalCompliance(const std::vector<Observation>& observations, int groups, const Robot& robot, int j,
                        const MeasurementCampaign& campaign, const StiffnessIdentificationOptions& options,
                        StiffnessEstimate& e) {
  const int points = static_cast<int>(observations.size());
  if (points < groups + 2) {
    throw MeasurementError(campaign.source + ": local stiffness test of " + robot.joints[j].name + ": " +
                           std::to_string(points) + " measured points for " + std::to_string(groups + 1) +
                           " unknowns (a slope and one offset per pose); at least " + std::to_string(groups + 2) +
                           " are needed");
  }
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(points, groups + 1);
  Eigen::VectorXd y(points);
  std::vector<double> sigma(points);
  for (int r = 0; r < points; ++r) {
    a(r, observations[r].group) = 1.0;
    a(r, groups) = -observations[r].torque;
    y[r] = observations[r].deflection;
    sigma[r] = observations[r].sigma;
  }
  const bool noise_known = fillUnknownSigma(sigma);
  const LinearFit fit = weightedLeastSquares(a, y, Eigen::Map<const Eigen::VectorXd>(sigma.data(), points));
  if (fit.rank < groups + 1) {
    throw MeasurementError(campaign.source + ": local stiffness test of " + robot.joints[j].name +
                           ": the torque does not vary within any of its poses");
  }
  e.points = points;
  e.groups = groups;
  e.dof = fit.dof;
  e.residual_rms = std::sqrt(fit.residuals.squaredNorm() / points);
  e.reduced_chi2 = noise_known ? fit.scale2 : 0.0;
  fillStiffness(e, fit.coefficients[groups], std::sqrt(fit.covariance(groups, groups)),
                tIntervalFactor(options.confidence, fit.dof));
  for (int r = 0; r < points; ++r) {
    e.torque.push_back(observations[r].torque);
    e.deflection.push_back(fit.coefficients[observations[r].group] - observations[r].deflection);
    e.deflection_sigma.push_back(sigma[r] * std::sqrt(fit.scale2));
  }
}

}  // namespace

std::vector<StiffnessEstimate> identifyStiffnessLocal(const JointErrorModel& nominal,
                                                      const MeasurementCampaign& campaign,
                                                      const StiffnessIdentificationOptions& options) {
  checkOptions(options);
  const Robot& robot = nominal.robot();
  checkCampaign(robot, campaign, campaign.has_position, "local stiffness identification");
  const int n = robot.dof();
  const Classified classified = classify(nominal, campaign, options);
  std::vector<StiffnessEstimate> estimates(n);
  bool any_test = false;
  for (int j = 0; j < n; ++j) {
    StiffnessEstimate& e = estimates[j];
    bool by_levels = false;
    int groups = 0;
    const std::vector<Observation> observations = localObservations(robot, campaign, classified, j, by_levels, groups);
    if (groups == 0) {
      e.reason = "no local test of this joint in the campaign";
      continue;
    }
    any_test = true;
    e.method = by_levels ? "levels" : "tracker";
    fitLocalCompliance(observations, groups, robot, j, campaign, options, e);
  }
  if (!any_test) {
    throw MeasurementError(campaign.source +
                           ": no local stiffness test in the campaign (a pose whose load varies for one joint only, "
                           "or level readings qm under varying load)");
  }
  return estimates;
}

namespace {

// Which groups: the loaded ones that are no local test, or every loaded one when asked or when there are
// no others.
std::vector<const Group*> globalGroups(const Classified& classified, bool use_local_groups) {
  auto loaded = [](const Group& g) { return g.kind != GroupKind::Unused; };
  std::vector<const Group*> selected;
  for (const Group& g : classified.groups) {
    if (g.kind == GroupKind::Global) selected.push_back(&g);
  }
  if (use_local_groups || selected.empty()) {
    selected.clear();
    for (const Group& g : classified.groups) {
      if (loaded(g)) selected.push_back(&g);
    }
  }
  return selected;
}

// The tracker rows of the poses measured under at least two loads (one offset per pose), and how much
// each joint's torque varies over them.
struct GlobalRows {
  std::vector<std::pair<const Group*, std::size_t>> rows;
  std::vector<int> offset_of_row;
  JointVector spread;
  int used_poses = 0;
};

GlobalRows globalRows(const MeasurementCampaign& campaign, const Classified& classified,
                      const std::vector<const Group*>& selected, int n) {
  GlobalRows global;
  auto& rows = global.rows;
  auto& offset_of_row = global.offset_of_row;
  JointVector& spread = global.spread;
  int& used_poses = global.used_poses;
  std::vector<std::vector<std::pair<const Group*, std::size_t>>> pose_rows(classified.poses);
  for (const Group* g : selected) {
    for (std::size_t k = g->first; k < g->last; ++k) {
      if (hasPosition(campaign, k)) pose_rows[g->pose].emplace_back(g, k);
    }
  }
  spread = JointVector::Zero(n);
  for (const auto& members : pose_rows) {
    JointVector low = JointVector::Constant(n, kInfinity);
    JointVector high = JointVector::Constant(n, -kInfinity);
    for (const auto& member : members) {
      low = low.cwiseMin(member.first->row[member.second - member.first->first].commanded_torque);
      high = high.cwiseMax(member.first->row[member.second - member.first->first].commanded_torque);
    }
    if (members.size() < 2 || (high - low).maxCoeff() <= 0.0) continue;
    spread = spread.cwiseMax(high - low);
    for (const auto& member : members) {
      rows.push_back(member);
      offset_of_row.push_back(used_poses);
    }
    ++used_poses;
  }
  if (used_poses == 0) {
    throw MeasurementError(campaign.source +
                           ": global stiffness identification: no pose measured by the tracker under at least two "
                           "different loads");
  }
  return global;
}

// The linear problem: per tracker coordinate, -J_j tau_j per unknown compliance and one offset per pose;
// `first_order` the same with the torques at the commanded poses.
struct GlobalDesign {
  Eigen::MatrixXd a, first_order;
  Eigen::VectorXd y;
  std::vector<double> sigma;
};

GlobalDesign globalDesign(const Robot& robot, const MeasurementCampaign& campaign, const Classified& classified,
                          const GlobalRows& global, const std::vector<int>& unknown_of, int unknowns) {
  const int n = robot.dof();
  const Eigen::Vector3d target = targetOf(campaign);
  const auto& rows = global.rows;
  const auto& offset_of_row = global.offset_of_row;
  const int groups = global.used_poses;
  const int columns = unknowns + 3 * groups;
  const int equations = 3 * static_cast<int>(rows.size());
  GlobalDesign d;
  Eigen::MatrixXd& a = d.a;
  Eigen::MatrixXd& first_order = d.first_order;
  Eigen::VectorXd& y = d.y;
  std::vector<double>& sigma = d.sigma;
  a = Eigen::MatrixXd::Zero(equations, columns);
  first_order = Eigen::MatrixXd::Zero(equations, columns);  // torques at the commanded poses
  y.resize(equations);
  sigma.resize(static_cast<std::size_t>(equations));
  RobotWorkspace ws(robot);
  Jacobian jacobian(6, n);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const Group* g = rows[r].first;
    const std::size_t k = rows[r].second;
    const int group_index = offset_of_row[r];
    forwardKinematics(robot, ws, campaign.command[k]);
    pointJacobian(robot, ws, ws.tool_pose * target, jacobian);
    const JointVector& tau = g->torque(k);
    const JointVector& tau_commanded = g->row[k - g->first].commanded_torque;
    for (int axis = 0; axis < 3; ++axis) {
      const int row = 3 * static_cast<int>(r) + axis;
      for (int j = 0; j < n; ++j) {
        if (unknown_of[j] >= 0) {
          a(row, unknown_of[j]) = -jacobian(axis, j) * tau[j];
          first_order(row, unknown_of[j]) = -jacobian(axis, j) * tau_commanded[j];
        }
      }
      a(row, unknowns + 3 * group_index + axis) = 1.0;
      first_order(row, unknowns + 3 * group_index + axis) = 1.0;
      y[row] = campaign.position[k][axis];
      sigma[row] = classified.sigma[k];
    }
  }
  return d;
}

}  // namespace

std::vector<StiffnessEstimate> identifyStiffnessGlobal(const JointErrorModel& nominal,
                                                       const MeasurementCampaign& campaign,
                                                       const StiffnessIdentificationOptions& options,
                                                       bool use_local_groups) {
  checkOptions(options);
  const Robot& robot = nominal.robot();
  checkCampaign(robot, campaign, true, "global stiffness identification");
  if (!campaign.has_position) {
    throw MeasurementError(campaign.source + ": global stiffness identification needs measured positions (x, y, z)");
  }
  const int n = robot.dof();
  const Classified classified = classify(nominal, campaign, options);
  const std::vector<const Group*> selected = globalGroups(classified, use_local_groups);
  const GlobalRows global = globalRows(campaign, classified, selected, n);
  const auto& rows = global.rows;
  const JointVector& spread = global.spread;
  const int used_poses = global.used_poses;
  std::vector<StiffnessEstimate> estimates(n);
  std::vector<int> unknown_of(n, -1);
  int unknowns = 0;
  const double spread_scale = std::max(1.0, spread.maxCoeff());
  for (int j = 0; j < n; ++j) {
    if (spread[j] > 1e-9 * spread_scale) {
      unknown_of[j] = unknowns++;
    } else {
      estimates[j].reason = "its torque does not vary in the loaded poses";
    }
  }
  const int groups = used_poses;
  const int columns = unknowns + 3 * groups;
  const int equations = 3 * static_cast<int>(rows.size());
  if (equations <= columns) {
    throw MeasurementError(campaign.source + ": global stiffness identification: " + std::to_string(equations) +
                           " measured coordinates for " + std::to_string(columns) +
                           " unknowns (compliances and one offset per pose); more rows are needed");
  }
  GlobalDesign design = globalDesign(robot, campaign, classified, global, unknown_of, unknowns);
  std::vector<double>& sigma = design.sigma;
  const Eigen::MatrixXd& a = design.a;
  const Eigen::MatrixXd& first_order = design.first_order;
  const Eigen::VectorXd& y = design.y;
  const bool noise_known = fillUnknownSigma(sigma);
  const Eigen::Map<const Eigen::VectorXd> sigma_vector(sigma.data(), equations);
  // Identifiability is decided on the first-order design (torques at the commanded poses): the settled
  // torques differ from it by the deflections, which would make any design look barely full rank.
  const LinearFit first_order_fit = weightedLeastSquares(first_order, y, sigma_vector, 1e-9);
  const LinearFit fit = first_order_fit.rank < columns ? first_order_fit : weightedLeastSquares(a, y, sigma_vector);
  if (fit.rank < columns) {
    std::string named;
    const double largest = fit.null_direction.head(unknowns).cwiseAbs().maxCoeff();
    for (int j = 0; j < n; ++j) {
      if (unknown_of[j] >= 0 && std::abs(fit.null_direction[unknown_of[j]]) > 0.2 * largest && largest > 1e-6) {
        named += (named.empty() ? "" : ", ") + robot.joints[j].name;
      }
    }
    throw MeasurementError(
        campaign.source + ": global stiffness identification: degenerate poses, the loads and poses " +
        "do not separate the compliances of " + (named.empty() ? std::string("some joints") : named) +
        " (use more poses, or loads in more directions)");
  }
  const double t_factor = tIntervalFactor(options.confidence, fit.dof);
  const double rms = std::sqrt(fit.residuals.squaredNorm() / equations);
  for (int j = 0; j < n; ++j) {
    if (unknown_of[j] < 0) continue;
    StiffnessEstimate& e = estimates[j];
    e.method = "global";
    e.points = static_cast<int>(rows.size());
    e.groups = groups;
    e.dof = fit.dof;
    e.residual_rms = rms;
    e.reduced_chi2 = noise_known ? fit.scale2 : 0.0;
    const int u = unknown_of[j];
    fillStiffness(e, fit.coefficients[u], std::sqrt(fit.covariance(u, u)), t_factor);
    if (e.identified && e.compliance_se > options.max_relative_error * e.compliance) {
      e.identified = false;
      e.reason = "too uncertain: the loaded poses barely deflect it (relative standard error " +
                 formatNumber(e.compliance_se / e.compliance) + ")";
    }
  }
  return estimates;
}

StiffnessIdentificationResult identifyStiffness(const JointErrorModel& nominal, const MeasurementCampaign& campaign,
                                                const StiffnessIdentificationOptions& options) {
  checkOptions(options);
  const Robot& robot = nominal.robot();
  checkCampaign(robot, campaign, campaign.has_position, "stiffness identification");
  const int n = robot.dof();
  StiffnessIdentificationResult result;
  result.confidence = options.confidence;
  for (const Joint& joint : robot.joints) result.joint_names.push_back(joint.name);
  result.rows = static_cast<int>(campaign.size());
  for (std::size_t k = 0; k < campaign.size(); ++k) result.rows_without_position += hasPosition(campaign, k) ? 0 : 1;
  const Classified classified = classify(nominal, campaign, options);
  bool any_loaded = false;
  std::vector<int> pose_kind(classified.poses, 0);  // bit 0: unloaded part, 1: local test, 2: global loads
  for (const Group& g : classified.groups) {
    switch (g.kind) {
      case GroupKind::LocalLevels:
      case GroupKind::LocalTracker:
        ++result.local_groups;
        any_loaded = true;
        break;
      case GroupKind::Global:
        pose_kind[g.pose] |= 4;
        any_loaded = true;
        break;
      case GroupKind::Unused: pose_kind[g.pose] |= 1; break;
    }
  }
  for (int kind : pose_kind) {
    result.global_groups += (kind & 4) ? 1 : 0;
    result.unused_groups += kind == 1 ? 1 : 0;
  }
  if (!any_loaded) {
    throw MeasurementError(campaign.source +
                           ": no pose of the campaign is measured under different loads "
                           "(wrench or payload columns): nothing to identify stiffness from");
  }
  if (result.local_groups > 0) {
    result.local = identifyStiffnessLocal(nominal, campaign, options);
  } else {
    result.local.assign(n, StiffnessEstimate());
    for (StiffnessEstimate& e : result.local) e.reason = "no local test in the campaign";
  }
  if (campaign.has_position && campaign.frame == MeasurementFrame::Base) {
    result.global_shares_rows = result.global_groups == 0;
    result.global = identifyStiffnessGlobal(nominal, campaign, options, false);
    if (result.global_shares_rows) {
      result.notes.emplace_back(
          "the campaign has no poses besides the local tests: the global fit uses the local tests' "
          "rows, so the two methods are not independent");
    }
  } else {
    result.global.assign(n, StiffnessEstimate());
    for (StiffnessEstimate& e : result.global) e.reason = "no tracker positions in the base frame";
  }
  result.relative_difference.assign(n, std::numeric_limits<double>::quiet_NaN());
  result.z_score.assign(n, std::numeric_limits<double>::quiet_NaN());
  for (int j = 0; j < n; ++j) {
    const StiffnessEstimate& l = result.local[j];
    const StiffnessEstimate& g = result.global[j];
    if (l.identified && g.identified) {
      result.relative_difference[j] = (g.stiffness - l.stiffness) / l.stiffness;
      result.z_score[j] = (g.compliance - l.compliance) / std::hypot(g.compliance_se, l.compliance_se);
    }
  }
  if (result.rows_without_position > 0 && campaign.has_position) {
    result.notes.push_back(std::to_string(result.rows_without_position) +
                           " rows without a measured position were left out");
  }
  return result;
}

JointErrorModel withIdentifiedStiffness(const JointErrorModel& nominal, const StiffnessIdentificationResult& result,
                                        bool prefer_global, const std::string& source_note) {
  const Robot& robot = nominal.robot();
  const int n = robot.dof();
  if (static_cast<int>(result.local.size()) != n || static_cast<int>(result.global.size()) != n) {
    throw InvalidArgument("stiffness update: the result is for another robot");
  }
  JointErrorModel updated = nominal;
  const int index = updated.jointSprings();
  std::vector<double> values(n, std::numeric_limits<double>::quiet_NaN());
  if (index >= 0) values = updated.effect(index).parameters();
  std::vector<std::string> kept;
  std::vector<double> identified_values;
  for (int j = 0; j < n; ++j) {
    const StiffnessEstimate& first = prefer_global ? result.global[j] : result.local[j];
    const StiffnessEstimate& second = prefer_global ? result.local[j] : result.global[j];
    if (first.identified) {
      values[j] = first.stiffness;
    } else if (second.identified) {
      values[j] = second.stiffness;
    } else {
      kept.push_back(robot.joints[j].name);
      continue;
    }
    identified_values.push_back(values[j]);
  }
  if (identified_values.empty()) throw InvalidArgument("stiffness update: no joint was identified");
  std::string note;
  if (!kept.empty()) {
    std::string list;
    for (const std::string& name : kept) list += (list.empty() ? "" : ", ") + name;
    note = "not identified by " + source_note + ": " + list +
           (index >= 0 ? " (nominal values kept)" : " (median of the others)");
  }
  if (index >= 0) {
    updated.effect(index).setParameters(values);
    if (!kept.empty() && !updated.effect(index).estimate_note.empty())
      note += "; before: " + updated.effect(index).estimate_note;
    updated.effect(index).estimate_note = note;
  } else {
    const double typical = median(std::move(identified_values));
    for (double& v : values) {
      if (!std::isfinite(v)) v = typical;
    }
    auto effect = std::make_unique<ComplianceEffect>(robot, values);
    effect->estimate_note = note;
    updated.addEffect(std::move(effect));
  }
  updated.notes +=
      (updated.notes.empty() ? "" : " ") + std::string("Joint stiffness identified from ") + source_note + ".";
  return updated;
}

}  // namespace jointcomp
