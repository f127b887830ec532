// Loading a Robot from URDF with urdfdom.
#pragma once

#include <string>

#include "model/robot/robot.hpp"

namespace jointcomp {

struct UrdfChainOptions {
  std::string root_link;  // empty: the URDF's root link
  std::string tip_link;   // empty: the only leaf of the tree (an error if the tree branches)
};

// Loads the chain root_link -> tip_link. Fixed joints are folded into the neighbouring moving joint
// (their links' inertials merged into the moving body); continuous joints become unlimited revolute
// joints. Moving joints hanging below the last body (beyond the tip) are left out with their links, as
// KDL's getChain does; a moving joint branching off anywhere else is an error. Throws UrdfError naming the file and the
// element for anything the model cannot represent: malformed XML, prismatic/planar/floating joints on the chain, a
// branching tree without a tip, unknown root or tip links, lower > upper limits, non-positive mass, non-finite numbers,
// zero joint axes.
Robot loadRobotFromUrdfFile(const std::string& path, const UrdfChainOptions& options = {});
// The same from URDF text; `source_name` stands in for the file name in messages.
Robot loadRobotFromUrdfString(const std::string& urdf_xml, const std::string& source_name,
                              const UrdfChainOptions& options = {});

}  // namespace jointcomp
