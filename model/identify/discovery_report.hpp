// The report of a residual discovery (jointcomp discover, jc_discover): JSON with effect types from the
// fixed vocabulary, a readable summary, and the error per step as CSV for the plot.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "model/identify/discovery.hpp"

namespace jointcomp {

// What the report names: the inputs as the user gave them and, when written, the outputs.
struct DiscoverySources {
  std::string urdf;
  std::string parameters;              // empty: no parameter file
  std::vector<std::string> campaigns;  // fitted
  std::vector<std::string> held_out;
  nlohmann::ordered_json outputs = nlohmann::ordered_json::object();
};

nlohmann::ordered_json discoveryReportJson(const DiscoveryResult& result, const DiscoveryOptions& options,
                                           const DiscoverySources& sources, double seconds);
std::string discoverySummary(const DiscoveryResult& result, const DiscoveryOptions& options,
                             const DiscoverySources& sources);
// step,effect,fitted_rms_mm,heldout_rms_mm,cv_rms_mm: the base model (step 0) and every accepted step.
std::string discoveryStepsCsv(const DiscoveryResult& result);

// "harmonic shoulder_lift_joint stage_2 order 2", "backlash elbow_joint", ...
std::string discoveryStepLabel(const DiscoveryStep& step);

}  // namespace jointcomp
