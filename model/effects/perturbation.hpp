// A "true" robot for simulations: the nominal joint-error model with every parameter moved by a stated,
// seeded amount, so that compensation with the nominal model meets a robot it does not know exactly.
#pragma once

#include <cstdint>
#include <string>

#include "model/effects/joint_error_model.hpp"

namespace jointcomp {

struct PerturbationSpec {
  double stiffness_relative = 0.05;  // joint and spring stiffnesses: x (1 + U(-r, r))
  double amplitude_relative = 0.10;  // harmonic amplitudes: x (1 + U(-r, r))
  double phase_absolute_rad = 0.10;  // harmonic phases: + U(-p, p)
  double geometry_relative = 0.02;   // other spring-balancer values: x (1 + U(-r, r))
  std::uint64_t seed = 2012;
};

// A parameter's law under the perturbation: value * (1 + scale * U(-1, 1)) when relative, else
// value + scale * U(-1, 1). Parameters are classed by the unit in their name (stiffness, amplitude,
// phase, other): the one rule, which jc_spiral_job_parameters hands to Monte Carlo as the main job's law.
struct PerturbationLaw {
  double scale = 0.0;
  bool relative = true;
};
PerturbationLaw perturbationLaw(const std::string& parameter_name, const PerturbationSpec& spec);

JointErrorModel perturbedModel(const JointErrorModel& nominal, const PerturbationSpec& spec);

}  // namespace jointcomp
