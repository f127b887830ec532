#include "model/effects/perturbation.hpp"

#include "model/common/random.hpp"

namespace jointcomp {
namespace {
bool endsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}
}  // namespace

PerturbationLaw perturbationLaw(const std::string& name, const PerturbationSpec& spec) {
  if (endsWith(name, "stiffness_nm_per_rad") || endsWith(name, "stiffness_n_per_m")) {
    return {spec.stiffness_relative, true};
  }
  if (endsWith(name, "amplitude_rad")) return {spec.amplitude_relative, true};
  if (endsWith(name, "phase_rad")) return {spec.phase_absolute_rad, false};
  return {spec.geometry_relative, true};
}

JointErrorModel perturbedModel(const JointErrorModel& nominal, const PerturbationSpec& spec) {
  JointErrorModel truth = nominal;
  DeterministicRandom random(spec.seed);
  for (int i = 0; i < truth.effectCount(); ++i) {
    Effect& effect = truth.effect(i);
    const std::vector<std::string> names = effect.parameterNames();
    std::vector<double> values = effect.parameters();
    for (std::size_t k = 0; k < values.size(); ++k) {
      const double draw = random.uniform(-1.0, 1.0);
      const PerturbationLaw law = perturbationLaw(names[k], spec);
      if (law.relative) {
        values[k] *= 1.0 + law.scale * draw;
      } else {
        values[k] += law.scale * draw;
      }
    }
    effect.setParameters(values);
  }
  return truth;
}

}  // namespace jointcomp
