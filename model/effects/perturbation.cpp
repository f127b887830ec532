#include "model/effects/perturbation.hpp"

#include "model/common/random.hpp"

namespace jointcomp {
namespace {
bool endsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}
}  // namespace

JointErrorModel perturbedModel(const JointErrorModel& nominal, const PerturbationSpec& spec) {
  JointErrorModel truth = nominal;
  DeterministicRandom random(spec.seed);
  for (int i = 0; i < truth.effectCount(); ++i) {
    Effect& effect = truth.effect(i);
    const std::vector<std::string> names = effect.parameterNames();
    std::vector<double> values = effect.parameters();
    for (std::size_t k = 0; k < values.size(); ++k) {
      const double draw = random.uniform(-1.0, 1.0);
      if (endsWith(names[k], "stiffness_nm_per_rad") || endsWith(names[k], "stiffness_n_per_m")) {
        values[k] *= 1.0 + spec.stiffness_relative * draw;
      } else if (endsWith(names[k], "amplitude_rad")) {
        values[k] *= 1.0 + spec.amplitude_relative * draw;
      } else if (endsWith(names[k], "phase_rad")) {
        values[k] += spec.phase_absolute_rad * draw;
      } else {
        values[k] *= 1.0 + spec.geometry_relative * draw;
      }
    }
    effect.setParameters(values);
  }
  return truth;
}

}  // namespace jointcomp
