// Loading a Robot from URDF with urdfdom.
#pragma once

#include <cstddef>
#include <string>

#include "model/robot/robot.hpp"

namespace jointcomp {

// What a URDF may be: a robot description is a few kilobytes (its meshes are other files) and nests
// elements a few levels deep; beyond these it is refused before it is parsed.
constexpr std::size_t kMaxUrdfBytes = 16u << 20;  // 16 MiB
constexpr int kMaxUrdfDepth = 100;
// What a link of a robot may be: values beyond these are typing errors or attacks (a mass of 1e300 kg
// made `paper` report errors of metres with exit 0).
constexpr double kMaxUrdfMass = 1e5;      // kg
constexpr double kMaxUrdfInertia = 1e5;   // kg m^2, any element of the tensor
constexpr double kMaxUrdfDistance = 1e3;  // m, of any <origin> from its parent's frame

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
// zero joint axes, a file that is not a regular file (a device, a folder) or larger than kMaxUrdfBytes, XML
// nested deeper than kMaxUrdfDepth, a link that is the child of two joints, a mimic joint on the chain, masses,
// inertias and origins beyond kMaxUrdfMass, kMaxUrdfInertia and kMaxUrdfDistance.
Robot loadRobotFromUrdfFile(const std::string& path, const UrdfChainOptions& options = {});
// The same from URDF text; `source_name` stands in for the file name in messages.
Robot loadRobotFromUrdfString(const std::string& urdf_xml, const std::string& source_name,
                              const UrdfChainOptions& options = {});

}  // namespace jointcomp
