// jc_spiral_experiment_truth: the paper's spiral compensated with one robot's parameters and followed by
// another robot as the truth (Monte Carlo over a parameter distribution, jointcomp.distributed).
#include "api_support.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "spiral_outputs.hpp"

using namespace jointcomp;
using namespace jointcomp::capi;

extern "C" {

jc_status jc_spiral_experiment_truth(jc_robot* nominal, jc_robot* truth, int32_t use_plant, double* metrics,
                                     int32_t metrics_len, double* errors, int32_t errors_len) {
  return CAPI_ENTRY({
    const jc_robot& model = robotHandle(nominal, "nominal");
    const jc_robot& real = robotHandle(truth, "truth");
    if (use_plant != 0 && use_plant != 1) invalid("use_plant is " + std::to_string(use_plant) + ", must be 0 or 1");
    if (use_plant && real.drives.empty()) {
      invalid("use_plant is 1 but the truth's parameters have no \"plant\" object (drives and controller gains)");
    }
    if (real.robot->dof() != model.robot->dof()) {
      invalid("truth has " + std::to_string(real.robot->dof()) + " joints, nominal " +
              std::to_string(model.robot->dof()));
    }
    requireOutput(metrics, metrics_len, 15, "metrics", "3 runs x Ra, Rz, RMS, max, mean");
    SpiralExperimentSpec spec;
    if (use_plant) spec.drives = real.drives;
    // Planned and compensated first so that the size of `errors` is checked before the (longer) simulation.
    const PreparedSpiral prepared = prepareSpiralRuns(model.model, spec);
    const std::int64_t m = static_cast<std::int64_t>(prepared.planned.size());
    if (m > INT32_MAX / 16) invalid("the spiral has too many samples for int32_t lengths");
    const bool want_errors = optionalOutput(errors, errors_len, 9 * m, "errors", "3 runs x the spiral's samples x 3");
    // Both models are immutable once loaded: no handle lock is needed to read them.
    const SpiralExperimentResult result = followSpiralRuns(prepared, real.model, spec);
    writeSpiralRuns(result, m, metrics, want_errors ? errors : nullptr);
  });
}

}  // extern "C"
