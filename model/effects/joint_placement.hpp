// A joint's placement: the six corrections of where the joint's axis sits in its parent link (three
// translations, three rotations). Not an effect of its own: the kinematic calibration fits it and writes it
// into the corrected URDF. Discovery offers it as "geometric", the six freed together (the calibration
// keeps the identifiable subset).
#pragma once

#include "model/effects/discovery_family.hpp"

namespace jointcomp {

class JointPlacementDiscovery : public CalibrationParameterDiscovery {
public:
  JointPlacementDiscovery() : CalibrationParameterDiscovery("geometric", CalibrationParameter::Placement, false) {}
};

}  // namespace jointcomp
