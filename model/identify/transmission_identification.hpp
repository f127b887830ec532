// Transmission (kinematic) error of one joint from a sweep of that joint measured by a tracker, as in the
// paper (Olabi et al. 2012: joint 2 from -50 to +50 deg in 0.05 deg steps).
//
// 1. The joint angle: the angle by which the measured target turned about the nominal axis of the joint
//    from where the nominal kinematics put it at the command (q_measured = q_command + that angle). When
//    the campaign has no positions, the level column qm_j is used instead.
// 2. Minus the predicted stiffness error: the same angle for the target where the nominal model puts it
//    under its loads and compliance (settleStatically with the loads and "compliance").
// 3. What remains is fitted by weighted linear least squares as a smooth baseline (a polynomial of the
//    joint angle, which takes offsets and what the stiffness prediction missed) plus harmonics of the
//    chosen stage's input angle (GearTrain::stageInputAngle of the nominal gears):
//      e = sum_i b_i x^i + sum_n (s_n sin(n theta) + c_n cos(n theta)),
//    A_n sin(n theta + phi_n) with A_n = hypot(s_n, c_n), phi_n = atan2(c_n, s_n) (the convention of
//    TransmissionErrorEffect), standard errors by the delta method from the coefficients' covariance
//    (scaled by the residual variance), intervals from Student t.
// 4. Significance of each candidate order: the F test of dropping its sin and cos from the full model,
//    p = P(F(2, dof) > F), significant when p < significance / (number of candidates) (Bonferroni). The
//    final harmonics are refitted with the significant orders only.
// 5. Spectrum: for each order on a grid, the amplitude of the single harmonic fitted with the baseline
//    (a least-squares periodogram over orders).
//
// Errors: MeasurementError naming the campaign for too few points, a campaign that is not a sweep of
// that joint (another joint's command moves, naming the row and joint), no position or level readings,
// a target on the joint's axis, a sweep too short for every candidate order; InvalidArgument for options
// (joint or stage out of range, no candidates, non-positive orders).
#pragma once

#include <string>
#include <vector>

#include "model/effects/joint_error_model.hpp"
#include "model/effects/transmission_error.hpp"
#include "model/io/measurement_campaign.hpp"

namespace jointcomp {

struct TransmissionIdentificationOptions {
  int joint = 1;                                           // 0-based: joint 2
  int stage = 2;                                           // 1 = motor, k = input of stage k, stageCount + 1 = output
  std::vector<double> candidate_orders{1, 2, 3, 4, 5, 6};  // cycles per revolution of that stage
  int baseline_degree = 3;
  double significance = 1e-3;  // family-wise, over the candidates
  double confidence = 0.95;
  double min_periods = 2.0;  // a candidate needs this many periods in the sweep
  double spectrum_min_order = 0.1;
  double spectrum_max_order = 8.0;
  double spectrum_step = 0.02;
};

struct HarmonicEstimate {
  double order = 0.0;  // cycles per revolution of the stage
  double amplitude_rad = 0.0;
  double amplitude_se_rad = 0.0;
  double amplitude_low_rad = 0.0;  // interval at `confidence` (low clamped at 0)
  double amplitude_high_rad = 0.0;
  double phase_rad = 0.0;  // in (-pi, pi]
  double phase_se_rad = 0.0;
  double phase_low_rad = 0.0;  // phase +- t * se (not wrapped)
  double phase_high_rad = 0.0;
  double f_statistic = 0.0;  // of dropping this order from the full model
  double p_value = 1.0;
  double amplitude_to_se = 0.0;
  bool significant = false;
};

struct TransmissionIdentificationResult {
  std::string joint_name;
  int joint = 0;
  int stage = 0;
  std::string part;          // "motor", "stage_K" or "output"
  std::string angle_source;  // "tracker" or "levels"
  int samples = 0;
  double stage_revolutions = 0.0;  // how far the stage turned over the sweep
  double confidence = 0.95;
  double significance = 1e-3;
  int dof = 0;
  double residual_rms_rad = 0.0;
  double noise_rms_rad = 0.0;  // the stated noise of the angles, RMS (0 when unknown)
  double reduced_chi2 = 0.0;   // 0 when the noise is unknown
  // Per sample (SI): command, recovered joint angle, predicted stiffness error, kinematic error (angle
  // minus command minus stiffness error), the fit, the stage angle.
  std::vector<double> command, measured, stiffness_error, kinematic_error, fitted, stage_angle;
  std::vector<double> baseline;  // polynomial coefficients in x = (q - centre) / half-range
  double baseline_centre = 0.0, baseline_half_range = 1.0;
  std::vector<double> spectrum_orders, spectrum_amplitude_rad;
  std::vector<HarmonicEstimate> candidates;  // the full-model fit and tests
  std::vector<HarmonicEstimate> harmonics;   // the significant ones, refitted
  std::vector<double> excluded_orders;       // candidates the sweep is too short for
};

TransmissionIdentificationResult identifyTransmissionError(const JointErrorModel& nominal,
                                                           const MeasurementCampaign& campaign,
                                                           const TransmissionIdentificationOptions& options = {});

// The nominal model with the identified harmonics of that joint and stage in its transmission_error
// effect (replacing the ones it had for them; the effect is added when missing).
JointErrorModel withIdentifiedHarmonics(const JointErrorModel& nominal, const TransmissionIdentificationResult& result,
                                        const std::string& source_note);

}  // namespace jointcomp
