#include "model/effects/discovery_family.hpp"

namespace jointcomp {

std::string DiscoveryCandidate::label() const {
  if (through_compliance) return type + " (tool)";
  return type + " joint " + std::to_string(joint + 1) + detail;
}

std::unique_ptr<Effect> DiscoveryFamily::makeEffect(const DiscoveryData&, const std::vector<FittedCandidate>&) const {
  return nullptr;
}

std::vector<NamedEstimate> DiscoveryFamily::describe(const FittedCandidate&, const JointErrorModel&) const {
  return {};
}

const std::string& jointNameOf(const DiscoveryData& data, int joint) {
  return data.robot->joints[static_cast<std::size_t>(joint)].name;
}

}  // namespace jointcomp
