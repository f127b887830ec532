// What the stiffness and transmission-error identifications share: checking that a campaign fits the
// nominal model, the torques of each row at the commanded pose, angles of the target about a joint axis,
// and the noise of each row.
#pragma once

#include <string>
#include <vector>

#include "model/effects/joint_error_model.hpp"
#include "model/io/measurement_campaign.hpp"

namespace jointcomp::identify_detail {

// Throws MeasurementError (validate(), non-finite wrench or payload) or InvalidArgument (another robot,
// another joint count). `needs_base_frame`: the method uses positions in the base frame.
void checkCampaign(const Robot& robot, const MeasurementCampaign& campaign, bool needs_base_frame, const char* method);

// The campaign's target in the flange frame (the flange origin when the file names none).
Eigen::Vector3d targetOf(const MeasurementCampaign& campaign);

// The wrench of a campaign row (force at the target, moment) as the model's tool wrench (moment about
// the tool point), at the pose of the last forward kinematics in `ws`.
Vector6 toolWrenchOf(const Vector6& at_target, const RobotWorkspace& ws, const Eigen::Vector3d& target_in_flange);

// The nominal model's prediction for row k: where the links settle at its command under the row's wrench
// and payload with the nominal loads and compliance (settleStatically with loadsAnd({"compliance"})),
// and the torque each joint carries there (gravity, payload, wrench, load effects). Throws SolverError
// naming the row when the model does not settle.
struct RowPrediction {
  JointVector settled;           // link angles
  JointVector torque;            // N m, at the settled pose
  JointVector commanded_torque;  // N m, at the commanded pose (first order: what decides identifiability)
};
RowPrediction predictRow(const JointErrorModel& nominal, const MeasurementCampaign& campaign, std::size_t k,
                         JointErrorWorkspace& ws);

// Signed angle about the unit axis `axis` through `origin` that takes `from` to `to` (both projected on
// the plane normal to the axis). `lever` receives the distance of `from` from the axis.
double angleAboutAxis(const Eigen::Vector3d& axis, const Eigen::Vector3d& origin, const Eigen::Vector3d& from,
                      const Eigen::Vector3d& to, double* lever = nullptr);

// Replaces unknown (NaN) sigmas by the median of the known ones, or all by 1 when none is known.
// Returns true when at least one was known.
bool fillUnknownSigma(std::vector<double>& sigma);

// Consecutive rows with the same command (within 1e-9 rad): [first, last) index pairs.
std::vector<std::pair<std::size_t, std::size_t>> poseGroups(const MeasurementCampaign& campaign);

std::string formatNumber(double value);

}  // namespace jointcomp::identify_detail
