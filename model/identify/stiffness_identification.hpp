// Joint stiffness from a measurement campaign of applied loads, by the two methods of the paper (Olabi
// et al. 2012), side by side.
//
// Rows are grouped by pose (consecutive rows with the same command). The torque each joint carries in a
// row is computed from the nominal model at the commanded pose: gravity, payload, the applied wrench
// (columns fx ... mz, force at the target, moment) and the nominal load effects (spring balancer).
//
// Local, axis-by-axis: a group tests joint j when only j's torque varies in it (every other joint's
// torque range is below 1/dominance_ratio of j's), or when it holds level readings qm_j. The deflection
// of j in each row is the level reading minus the command (qm_j - q_j: the two-level difference of the
// paper for joint 3) or, from the tracker, the angle by which the target turned about the nominal axis
// of j (from where the nominal kinematics put it at the command). Linear regression of deflection on
// torque, dq = a_group - c tau, one intercept per group (it takes gravity and every constant error),
// weighted by the noise of each deflection; K = 1/c. The interval of c is Student t with the residual
// variance; K's is its image (1/c_high, 1/c_low), so that it covers at the stated rate.
//
// Global: the groups that are not local tests (all loaded groups when there are none), least squares of
// the target positions p = b_group - J_p(q) C tau over every joint at once, C = K^-1 diagonal: the
// compliance form of F = J^-T K_J J^-1 dX (linear in C, and it needs 3-D positions only). Weighted by the
// tracker noise of each row, with the residual variance.
//
// Errors (all name the campaign): MeasurementError for a campaign that cannot give what is asked (no
// positions where needed, frame instrument, too few points for a joint, no torque variation, a target on
// the tested joint's axis, degenerate poses that leave joints unseparated, naming them); InvalidArgument
// for a campaign of another robot or bad options.
#pragma once

#include <string>
#include <vector>

#include "model/effects/joint_error_model.hpp"
#include "model/io/measurement_campaign.hpp"

namespace jointcomp {

struct StiffnessIdentificationOptions {
  double confidence = 0.95;
  double dominance_ratio = 20.0;
  // Joints whose global estimate's relative standard error exceeds this are reported but not trusted
  // (identified = false).
  double max_relative_error = 0.5;
};

struct StiffnessEstimate {
  bool identified = false;
  std::string method;          // "tracker", "levels", "global" or "" when not identified
  std::string reason;          // why not identified, when not
  double stiffness = 0.0;      // N m / rad, 1 / compliance
  double stiffness_se = 0.0;   // delta method: compliance_se / compliance^2
  double stiffness_low = 0.0;  // interval at `confidence` (upper may be +inf)
  double stiffness_high = 0.0;
  double compliance = 0.0;  // rad / (N m)
  double compliance_se = 0.0;
  int points = 0;
  int groups = 0;
  int dof = 0;                // residual degrees of freedom
  double residual_rms = 0.0;  // rad (local) or m (global)
  double reduced_chi2 = 0.0;  // residual variance over the stated noise (1 when the noise is as stated); 0 if unknown
  // Local only, for the plots: torque, deflection with its group intercept removed, and its sigma.
  std::vector<double> torque, deflection, deflection_sigma;
};

struct StiffnessIdentificationResult {
  std::vector<std::string> joint_names;
  double confidence = 0.95;
  std::vector<StiffnessEstimate> local;   // one per joint
  std::vector<StiffnessEstimate> global;  // one per joint
  // Per joint where both are identified: (K_global - K_local) / K_local, and the z score of the difference
  // of the compliances with both standard errors (independent unless shared_rows).
  std::vector<double> relative_difference, z_score;
  bool global_shares_rows = false;  // the global fit used the local tests' rows too
  int local_groups = 0;             // local tests (load ladders of one joint)
  int global_groups = 0;            // poses with other loads
  int unused_groups = 0;            // poses never loaded
  int rows = 0, rows_without_position = 0;
  std::vector<std::string> notes;
};

// Both methods. Joints a method cannot see get identified = false with the reason; a campaign in which
// neither method finds anything to fit throws MeasurementError.
StiffnessIdentificationResult identifyStiffness(const JointErrorModel& nominal, const MeasurementCampaign& campaign,
                                                const StiffnessIdentificationOptions& options = {});

// The methods alone (one estimate per joint). Local: throws MeasurementError when the campaign holds no
// local test, or a joint's tests have too few points or no torque variation. Global: throws when no pose
// is loaded, or the poses leave compliances unseparated (naming the joints). `use_local_groups`: fit
// every loaded group, local tests included, not only the others.
std::vector<StiffnessEstimate> identifyStiffnessLocal(const JointErrorModel& nominal,
                                                      const MeasurementCampaign& campaign,
                                                      const StiffnessIdentificationOptions& options = {});
std::vector<StiffnessEstimate> identifyStiffnessGlobal(const JointErrorModel& nominal,
                                                       const MeasurementCampaign& campaign,
                                                       const StiffnessIdentificationOptions& options = {},
                                                       bool use_local_groups = false);

// The nominal model with the identified stiffnesses (local, else global when `prefer_global`; the other
// method fills joints the first did not identify; the rest keep their nominal values). Adds a compliance
// effect when the nominal has none (joints without an estimate then get the other joints' median).
JointErrorModel withIdentifiedStiffness(const JointErrorModel& nominal, const StiffnessIdentificationResult& result,
                                        bool prefer_global, const std::string& source_note);

}  // namespace jointcomp
