#include "model/effects/joint_placement.hpp"

namespace jointcomp {

void JointPlacementDiscovery::offer(const DiscoveryData&, int joint, std::vector<DiscoveryCandidate>& candidates) const {
  if (joint < 0) return;
  DiscoveryCandidate candidate;
  candidate.type = name();
  candidate.joint = joint;
  candidate.releases = {CalibrationParameter::Placement};
  candidates.push_back(std::move(candidate));
}

}  // namespace jointcomp
