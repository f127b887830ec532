// The plant options the FMU starts from: the library's, except that CVODE steps past communication points.
// At 1 ms communication steps stopping at each costs a whole CVODE step per step (CVODE's own is about 3 ms on
// the paper's spiral); stepping past them is twice as fast, and an input that departs from the reference
// CVODE already integrated by more than step_past_tolerance_rad still takes effect at its time. The library
// keeps stopping by default, so that its runs (Table II, the stored regressions) stay bit for bit.
#pragma once

#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp {

inline PlantOptions fmuPlantOptions() {
  PlantOptions options;
  options.step_past_updates_s = 0.01;
  return options;
}

}  // namespace jointcomp
