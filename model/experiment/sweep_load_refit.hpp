// What the joint sweep reveals beyond the transmission error: the load effects on the swept joint (the
// spring balancer of the RX170's joint 2), refitted to the sweep.
//
// The transmission identification leaves, besides its harmonics, a smooth baseline: the swept joint's angle
// minus the command minus the deflection the model predicts. Over the sweep the joint's gravity and load
// torques change, so a load effect whose values are off (a balancer's spring 3 % stiffer than the
// catalogue says) leaves its torque error divided by the stiffness there, a smooth function of the joint.
// The tracker measures the target in the robot's base frame with the geometry known, so the level of that
// curve counts as well as its shape (no offset is fitted: the truth the simulation gives has none).
//
// Fit: r_k = kinematic_error_k - (identified harmonics)_k against D_k(p) - D_k(p0), D_k the swept joint's
// deflection predicted at row k's command (settleStatically with the loads and the compliance), p the load
// effects' parameters that are not zero and that move D (relative steps of 1e-4 for the finite differences),
// by Gauss-Newton with a Gaussian prior p ~ N(p0, (prior_relative p0)^2) on each (the catalogue's tolerance:
// the directions the sweep cannot see stay at the catalogue values). Noise: the transmission fit's residual
// RMS. Standard errors from the posterior covariance.
#pragma once

#include <string>
#include <vector>

#include "model/effects/joint_error_model.hpp"
#include "model/identify/transmission_identification.hpp"
#include "model/io/measurement_campaign.hpp"

namespace jointcomp {

struct SweepLoadRefitOptions {
  double prior_relative = 0.05;  // the catalogue's tolerance of each load parameter, relative
  int iterations = 3;            // Gauss-Newton steps
};

struct SweepLoadRefit {
  std::vector<std::string> names;  // the refitted parameters, as the effects name them
  std::vector<double> nominal, value, se;
  double rms_before_rad = 0.0;  // of r_k, and of r_k minus the refit's change
  double rms_after_rad = 0.0;
  int rows = 0;
};

// Refits `model`'s load effects in place from `sweep` (the campaign `transmission` was identified from,
// against `model`). Throws InvalidArgument when the two do not belong together (row counts, joint),
// SolverError when the model does not settle or a step leaves the parameters' valid range.
SweepLoadRefit refitSweptJointLoads(JointErrorModel& model, const MeasurementCampaign& sweep,
                                    const TransmissionIdentificationResult& transmission,
                                    const SweepLoadRefitOptions& options = {});

}  // namespace jointcomp
