#include "model/effects/joint_placement.hpp"

namespace jointcomp {}  // namespace jointcomp
