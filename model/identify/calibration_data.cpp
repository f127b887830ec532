// The rows a kinematic calibration works on (geometric_calibration.hpp): campaigns prepared into commands,
// load torques and the prior's other joint errors; campaigns joined; each row's residual; the calibrated
// joint-error model written from a result; simulated campaigns for tests.
#include "model/identify/geometric_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "model/common/errors.hpp"
#include "model/common/random.hpp"
#include "model/effects/backlash.hpp"
#include "model/effects/compliance.hpp"
#include "model/effects/joint_offset.hpp"
#include "model/robot/dynamics.hpp"

namespace jointcomp {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

int findCalibrationEffect(const JointErrorModel& model, CalibrationParameter parameter) {
  for (int i = 0; i < model.effectCount(); ++i) {
    if (model.effect(i).calibrationParameter() == parameter) return i;
  }
  return -1;
}

// Room for every row at once: grown by doubling, the rows' vectors held up to twice their memory.
void reserveRows(CalibrationData& data, std::size_t rows) {
  for (auto* joints : {&data.command, &data.load_torque, &data.approach, &data.other_error}) joints->reserve(rows);
  data.row.reserve(rows);
  data.measured.reserve(rows);
  data.setup.reserve(rows);
  data.campaign.reserve(rows);
}

}  // namespace

// ---- data and model -------------------------------------------------------------------------------------

CalibrationData prepareCalibrationData(const JointErrorModel& prior, const MeasurementCampaign& campaign) {
  const Robot& robot = prior.robot();
  if (!campaign.has_position) {
    throw MeasurementError(campaign.source +
                           ": the campaign has no measured positions (columns x, y, z); the "
                           "kinematic calibration needs them");
  }
  if (campaign.dof != robot.dof()) {
    throw MeasurementError(campaign.source + ": the campaign has " + std::to_string(campaign.dof) +
                           " joint columns, robot '" + robot.name + "' has " + std::to_string(robot.dof()) + " joints");
  }
  if (!campaign.robot.empty() && campaign.robot != robot.name) {  // as parameter files are checked
    throw MeasurementError(campaign.source + ": the campaign is of robot '" + campaign.robot + "', the model of '" +
                           robot.name + "'; a campaign calibrates only the robot it was measured on");
  }
  const std::size_t rows = campaign.command.size();
  if (campaign.position.size() != rows) {
    throw MeasurementError(campaign.source + ": " + std::to_string(campaign.position.size()) + " positions for " +
                           std::to_string(rows) + " commands");
  }
  CalibrationData data;
  data.source = campaign.source;
  data.torque_known = robot.hasInertials();
  // The prior's other joint-error effects (offset and compliance are what is fitted) and all its loads.
  EffectMask loads = 0, others = 0;
  for (int i = 0; i < prior.effectCount(); ++i) {
    const Effect& effect = prior.effect(i);
    if (effect.role() == EffectRole::Load)
      loads |= EffectMask(1) << i;
    else if (!effect.calibrationParameter())
      others |= EffectMask(1) << i;
  }
  reserveRows(data, rows);
  JointErrorWorkspace ws(robot);
  JointContext ctx(robot.dof());
  // The robot rests at each row: the side of each joint's lost motion is the one its last move set,
  // remembered along every row with a finite command (used or not), not known before the first move.
  LostMotionMemory memory(robot.dof());
  const JointVector* previous = nullptr;
  for (std::size_t k = 0; k < rows; ++k) {
    const JointVector& command = campaign.command[k];
    const bool command_known = command.size() == robot.dof() && command.allFinite();
    if (command_known) {
      if (previous) memory.move(command - *previous);
      previous = &command;
    }
    const Eigen::Vector3d& position = campaign.position[k];
    if (!command_known || !position.allFinite()) {
      ++data.skipped_rows;
      continue;
    }
    ctx.q = command;
    ctx.command = command;
    ctx.velocity.setZero();
    ctx.approach = memory.sides();
    ctx.time = k < campaign.time.size() ? campaign.time[k] : 0.0;
    const double temperature = k < campaign.temperature.size() ? campaign.temperature[k] : kNaN;
    ctx.temperature = std::isfinite(temperature) ? temperature : 20.0;
    ctx.tool_wrench =
        k < campaign.wrench.size() && campaign.wrench[k].allFinite() ? campaign.wrench[k] : Vector6::Zero();
    ctx.payload_mass = k < campaign.payload.size() && std::isfinite(campaign.payload[k]) ? campaign.payload[k] : 0.0;
    ctx.payload_com = campaign.target_in_flange;
    updateMotorAngles(prior, ctx);
    if (data.torque_known) {
      computeLoadTorque(prior, loads, ws, ctx);
    } else {
      ctx.load_torque.setZero();
    }
    JointVector other = JointVector::Zero(robot.dof());
    if (others != 0) addSelectedJointErrors(prior, others, ctx, other);
    data.row.push_back(static_cast<int>(k));
    data.command.push_back(command);
    data.load_torque.push_back(ctx.load_torque);
    data.approach.push_back(ctx.approach);
    data.other_error.push_back(other);
    data.measured.push_back(position);
    data.setup.push_back(0);
    data.campaign.push_back(0);
  }
  return data;
}

GeometricParameters nominalParameters(const JointErrorModel& prior, const MeasurementCampaign& campaign) {
  const int n = prior.robot().dof();
  GeometricParameters p = GeometricParameters::zero(n);
  if (campaign.has_target) p.target = campaign.target_in_flange;
  if (campaign.has_base_frame) p.setInstrumentFromBase(campaign.base_frame);
  // The first effect holding each of the calibration's own per-joint parameters is where it starts.
  const int offset = findCalibrationEffect(prior, CalibrationParameter::Offset);
  if (offset >= 0) {
    for (int j = 0; j < n; ++j) p.offset[j] = prior.effect(offset).calibrationValue(j);
  }
  const int compliance = findCalibrationEffect(prior, CalibrationParameter::Compliance);
  if (compliance >= 0) {
    for (int j = 0; j < n; ++j) p.compliance[j] = prior.effect(compliance).calibrationValue(j);
  }
  return p;
}

void checkCampaignsAgree(const std::vector<MeasurementCampaign>& campaigns) {
  if (campaigns.empty()) throw InvalidArgument("no campaign given");
  const MeasurementCampaign& first = campaigns.front();
  for (const MeasurementCampaign& m : campaigns) {
    if (m.dof != first.dof || m.frame != first.frame || m.has_position != first.has_position) {
      throw InvalidArgument("campaign '" + m.source + "' differs from '" + first.source +
                            "' in joints, frame (base or instrument) or positions; campaigns used together must "
                            "agree in all three");
    }
    if (!m.robot.empty() && !first.robot.empty() && m.robot != first.robot) {
      throw InvalidArgument("campaign '" + m.source + "' is of robot '" + m.robot + "', '" + first.source +
                            "' of robot '" + first.robot + "'; campaigns used together must be of one robot");
    }
  }
}

MeasurementCampaign concatenateCampaigns(const std::vector<MeasurementCampaign>& campaigns) {
  checkCampaignsAgree(campaigns);
  MeasurementCampaign all = campaigns.front();
  for (std::size_t c = 1; c < campaigns.size(); ++c) {
    const MeasurementCampaign& m = campaigns[c];
    const double shift = (all.time.empty() ? 0.0 : all.time.back() + 1.0) - (m.time.empty() ? 0.0 : m.time.front());
    for (std::size_t k = 0; k < m.size(); ++k) {
      all.time.push_back(m.time[k] + shift);
      all.command.push_back(m.command[k]);
      all.position.push_back(m.position[k]);
      all.temperature.push_back(k < m.temperature.size() ? m.temperature[k] : kNaN);
      all.wrench.push_back(k < m.wrench.size() ? m.wrench[k] : Vector6::Zero());
      all.payload.push_back(k < m.payload.size() ? m.payload[k] : 0.0);
      if (all.has_measured_angles) {
        all.measured_angles.push_back(k < m.measured_angles.size() ? m.measured_angles[k]
                                                                   : JointVector::Constant(all.dof, kNaN));
      }
    }
    all.source += "+" + m.source;
  }
  return all;
}

void assignCampaigns(CalibrationData& data, const std::vector<MeasurementCampaign>& campaigns,
                     const std::vector<int>& setup_of_campaign) {
  if (campaigns.empty() || setup_of_campaign.size() != campaigns.size()) {
    throw InvalidArgument(data.source + ": " + std::to_string(setup_of_campaign.size()) + " set-ups given for " +
                          std::to_string(campaigns.size()) + " campaigns");
  }
  std::vector<bool> used(campaigns.size(), false);
  for (int s : setup_of_campaign) {
    if (s < 0 || s >= static_cast<int>(campaigns.size())) {
      throw InvalidArgument(data.source + ": instrument set-up " + std::to_string(s) + " of " +
                            std::to_string(campaigns.size()) + " campaigns");
    }
    used[static_cast<std::size_t>(s)] = true;
  }
  data.setups = 1 + *std::max_element(setup_of_campaign.begin(), setup_of_campaign.end());
  if (std::find(used.begin(), used.begin() + data.setups, false) != used.begin() + data.setups) {
    throw InvalidArgument(data.source + ": instrument set-ups must be numbered 0, 1, ... without gaps");
  }
  std::size_t campaign = 0, end = campaigns.front().size();
  for (std::size_t k = 0; k < data.size(); ++k) {
    while (static_cast<std::size_t>(data.row[k]) >= end) {
      if (++campaign == campaigns.size()) throw InvalidArgument(data.source + ": a row beyond the campaigns given");
      end += campaigns[campaign].size();
    }
    data.setup[k] = setup_of_campaign[campaign];
    data.campaign[k] = static_cast<int>(campaign);
  }
}

CalibrationData prepareCalibrationData(const JointErrorModel& prior, const std::vector<MeasurementCampaign>& campaigns,
                                       const std::vector<int>& setup_of_campaign) {
  CalibrationData data = prepareCalibrationData(prior, concatenateCampaigns(campaigns));
  assignCampaigns(data, campaigns, setup_of_campaign);
  return data;
}

namespace {

// Each prepared row's residual in its set-up's frame, and mapped to the joints.
std::vector<RowResidual> residualsOf(const Robot& robot, const GeometricParameters& used, const CalibrationData& data) {
  const int n = robot.dof();
  const GeometricParameterLayout layout(n, used.setUpCount());
  std::vector<RowResidual> out(data.size());
  constexpr double kDamping = 1e-3;  // m per rad
  Eigen::MatrixXd jacobian;
  Eigen::Matrix<double, 3, Eigen::Dynamic> joint_columns(3, n);
  for (std::size_t k = 0; k < data.size(); ++k) {
    const Eigen::Vector3d predicted = predictMeasurement(robot, used, data.command[k], data.load_torque[k],
                                                         data.other_error[k], &jacobian, data.setup[k]);
    RowResidual& r = out[k];
    r.row = data.row[k];
    r.error = data.measured[k] - predicted;
    for (int j = 0; j < n; ++j) joint_columns.col(j) = jacobian.col(layout.offset(j));
    // Damped least squares (minimum norm, damping 1 mm per rad): near a singular pose the plain
    // pseudo-inverse would blow the mapping up; away from one the damping changes it by ~1e-6.
    const Eigen::Matrix3d gram =
        joint_columns * joint_columns.transpose() + kDamping * kDamping * Eigen::Matrix3d::Identity();
    r.joint_error = joint_columns.transpose() * gram.ldlt().solve(r.error);
  }
  return out;
}

// In the base frame there is no frame: whatever the parameters hold, the rows are predicted without one.
GeometricParameters withoutFrames(GeometricParameters used) {
  used.frame_translation.setZero();
  used.frame_rotation.setZero();
  for (GeometricParameters::SetUp& other : used.other_setups) {
    other.frame_translation.setZero();
    other.frame_rotation.setZero();
  }
  return used;
}

}  // namespace

std::vector<RowResidual> rowResiduals(const JointErrorModel& model, const GeometricParameters& parameters,
                                      const MeasurementCampaign& campaign) {
  const CalibrationData data = prepareCalibrationData(model, campaign);
  const GeometricParameters used = parameters.ofSetUp(0);
  return residualsOf(model.robot(), campaign.frame == MeasurementFrame::Base ? withoutFrames(used) : used, data);
}

std::vector<RowResidual> rowResiduals(const JointErrorModel& model, const GeometricParameters& parameters,
                                      const std::vector<MeasurementCampaign>& campaigns,
                                      const std::vector<int>& setup_of_campaign) {
  const CalibrationData data = prepareCalibrationData(model, campaigns, setup_of_campaign);
  if (parameters.setUpCount() < data.setups) {
    throw InvalidArgument(data.source + ": parameters of " + std::to_string(parameters.setUpCount()) +
                          " instrument set-ups for campaigns from " + std::to_string(data.setups));
  }
  const bool base = campaigns.front().frame == MeasurementFrame::Base;
  return residualsOf(model.robot(), base ? withoutFrames(parameters) : parameters, data);
}

JointErrorModel calibratedJointErrorModel(const JointErrorModel& prior, std::shared_ptr<const Robot> calibrated_robot,
                                          const GeometricCalibrationResult& result,
                                          std::vector<std::string>& left_out) {
  const Robot& robot = *calibrated_robot;
  const int n = robot.dof();
  if (n != prior.robot().dof()) throw InvalidArgument("calibratedJointErrorModel: robots differ in joint count");
  left_out.clear();
  std::vector<std::unique_ptr<Effect>> effects;
  for (int i = 0; i < prior.effectCount(); ++i) {
    if (prior.effect(i).calibrationParameter()) continue;  // replaced by the calibration's values below
    effects.push_back(prior.effect(i).clone());
  }
  std::vector<double> offsets(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) offsets[static_cast<std::size_t>(j)] = result.estimate.offset[j];
  auto offset = std::make_unique<JointOffsetEffect>(robot, offsets);
  offset->estimate_note = "kinematic calibration on " + std::to_string(result.used_rows) + " rows";
  effects.push_back(std::move(offset));

  const GeometricParameterLayout layout(n);
  const int prior_compliance = findCalibrationEffect(prior, CalibrationParameter::Compliance);
  std::vector<double> stiffness(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) {
    const ParameterEstimate& c = result.parameters[static_cast<std::size_t>(layout.compliance(j))];
    const std::string& joint = robot.joints[static_cast<std::size_t>(j)].name;
    if (!c.identified && prior_compliance >= 0 && c.value == c.nominal) {
      stiffness[static_cast<std::size_t>(j)] = prior.effect(prior_compliance).parameters()[static_cast<std::size_t>(j)];
    } else if (c.value > 0.0) {
      stiffness[static_cast<std::size_t>(j)] = 1.0 / c.value;
    } else {
      // Rigid in the file: nothing known to compensate on this joint.
      stiffness[static_cast<std::size_t>(j)] = std::numeric_limits<double>::infinity();
      left_out.push_back(joint + ": " + (c.identified ? "fitted compliance not positive" : c.fixed_because) +
                         (c.value == 0.0 ? " (no prior stiffness; written as rigid)" : " (written as rigid)"));
    }
  }
  {
    auto compliance = std::make_unique<ComplianceEffect>(robot, stiffness);
    compliance->estimate_note = "kinematic calibration: 1 / fitted compliance under the load torque";
    effects.push_back(std::move(compliance));
  }
  JointErrorModel model(std::move(calibrated_robot), prior.gears(), std::move(effects));
  model.notes = prior.notes;
  return model;
}

MeasurementCampaign simulateGeometricCampaign(const JointErrorModel& prior, const GeometricParameters& truth,
                                              const std::vector<JointVector>& commands, double noise,
                                              std::uint64_t seed, const Eigen::Vector3d& nominal_target) {
  const Robot& robot = prior.robot();
  MeasurementCampaign campaign;
  campaign.source = "simulated campaign (seed " + std::to_string(seed) + ")";
  campaign.robot = robot.name;
  campaign.frame = MeasurementFrame::Instrument;
  campaign.has_target = true;
  campaign.target_in_flange = nominal_target;
  campaign.position_noise = noise;
  campaign.dof = robot.dof();
  campaign.has_position = true;
  for (std::size_t k = 0; k < commands.size(); ++k) {
    campaign.time.push_back(static_cast<double>(k));
    campaign.command.push_back(commands[k]);
    campaign.position.emplace_back(Eigen::Vector3d::Zero());
    campaign.temperature.push_back(kNaN);
    campaign.wrench.emplace_back(Vector6::Zero());
    campaign.payload.push_back(0.0);
  }
  const CalibrationData data = prepareCalibrationData(prior, campaign);
  DeterministicRandom random(seed);
  for (std::size_t k = 0; k < data.size(); ++k) {
    Eigen::Vector3d p = predictMeasurement(robot, truth, data.command[k], data.load_torque[k], data.other_error[k]);
    for (int a = 0; a < 3; ++a) p[a] += noise * random.normal();
    campaign.position[static_cast<std::size_t>(data.row[k])] = p;
  }
  campaign.validate();
  return campaign;
}

CalibratedView asWritten(const JointErrorModel& prior, const GeometricParameters& estimate) {
  std::vector<std::unique_ptr<Effect>> effects;
  for (int i = 0; i < prior.effectCount(); ++i) effects.push_back(prior.effect(i).clone());
  CalibratedView view{JointErrorModel(std::make_shared<const Robot>(correctedRobot(prior.robot(), estimate)),
                                      prior.gears(), std::move(effects)),
                      estimate};
  view.model.notes = prior.notes;
  for (Vector6& placement : view.parameters.placement) placement.setZero();
  return view;
}

}  // namespace jointcomp
