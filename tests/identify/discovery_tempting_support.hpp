// Helpers of the tempting-campaign tests (test_discovery_tempting*.cpp): the fitted and held-out campaigns
// of a truth, discovery restricted to one family, what it accepted (each step's values and the final model's)
// and the check that it refused the family's fit naming the constraint and the joint.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/experiment/campaign_simulation.hpp"
#include "model/identify/discovery.hpp"
#include "tests/identify/identify_test_support.hpp"

namespace jointcomp {
namespace tempting {

struct Campaigns {
  MeasurementCampaign fit, held;
};

// 200 fitted and 100 held-out random poses measured on `truth` (seeded), with the robot warming up by
// 10 degC (time constant 400 s) when `warm_up`, the temperature in the campaign's column.
inline Campaigns simulatedCampaigns(const JointErrorModel& truth, std::uint64_t seed, bool warm_up) {
  CampaignSimulationSpec spec;
  spec.protocol = CampaignProtocol::RandomPoses;
  spec.seed = seed;
  spec.random.count = 200;
  spec.temperature.enabled = warm_up;
  spec.temperature.time_constant_s = 400.0;
  Campaigns c;
  c.fit = simulateCampaign(truth, spec);
  spec.seed += 1000;
  spec.random.count = 100;
  c.held = simulateCampaign(truth, spec);
  return c;
}
inline Campaigns plainCampaigns(const JointErrorModel& truth, std::uint64_t seed) {
  return simulatedCampaigns(truth, seed, false);
}
inline Campaigns warmUpCampaigns(const JointErrorModel& truth, std::uint64_t seed) {
  return simulatedCampaigns(truth, seed, true);
}

// Discovery from the nominal RX170 offered only `types`, in two steps at most.
inline DiscoveryResult discoverOnly(const Campaigns& c, const std::vector<std::string>& types) {
  DiscoveryOptions options;
  options.types = types;
  options.max_steps = 2;
  options.max_harmonic_order = 2;
  options.table_knots = {16};
  return discoverEffects(identify_test::rx170Model(), {c.fit}, {c.held}, options);
}

// Every refusal discovery reported (the stop's and each step's), one per element.
inline std::vector<std::string> refusals(const DiscoveryResult& r) {
  std::string all = r.rejected_at_stop;
  for (const DiscoveryStep& s : r.steps) all += "; " + s.rejected;
  std::vector<std::string> parts;
  std::size_t from = 0;
  while (from <= all.size()) {
    const std::size_t to = std::min(all.find("; ", from), all.size());
    if (to > from) parts.push_back(all.substr(from, to - from));
    from = to + 2;
  }
  return parts;
}

// "<what> <value>", for the printed outcome of a case.
inline std::string caseName(const std::string& what, double value) {
  char text[32];
  std::snprintf(text, sizeof(text), " %.4g", value);
  return what + text;
}

inline void printOutcome(const std::string& name, const DiscoveryResult& r) {
  std::printf("[ tempting ] %s: %zu step(s)", name.c_str(), r.steps.size());
  for (const DiscoveryStep& s : r.steps) std::printf(" %s%s", s.type.c_str(), s.detail.c_str());
  std::printf("\n");
  for (const DiscoveryStep& s : r.steps)
    for (const DiscoveredParameter& p : s.parameters)
      std::printf("[ tempting ]   %s = %.4g\n", p.name.c_str(), p.value);
  for (const std::string& refusal : refusals(r)) std::printf("[ tempting ]   refused: %s\n", refusal.c_str());
}

// One refusal names the family, the joint and the constraint (`constraint`, e.g. "beyond the plausible").
inline void expectRefused(const DiscoveryResult& r, const std::string& family, const std::string& joint,
                          const std::string& constraint) {
  bool named = false;
  for (const std::string& refusal : refusals(r)) {
    named = named || (refusal.find("not physical") != std::string::npos && refusal.find(family) != std::string::npos &&
                      refusal.find(joint) != std::string::npos && refusal.find(constraint) != std::string::npos);
  }
  std::string all;
  for (const std::string& refusal : refusals(r)) all += "\n  " + refusal;
  EXPECT_TRUE(named) << "no refusal names " << family << ", " << joint << " and '" << constraint << "':" << all;
}

struct NamedValue {
  std::string where;  // "step 1" or "final model"
  std::string name;
  double value = 0.0;
};

// The values discovery accepted of `family`: every step's estimates and the final model's effect of `type`.
inline std::vector<NamedValue> acceptedValues(const DiscoveryResult& r, const std::string& family,
                                              const std::string& type) {
  std::vector<NamedValue> values;
  for (std::size_t k = 0; k < r.steps.size(); ++k) {
    if (r.steps[k].type != family) continue;
    for (const DiscoveredParameter& p : r.steps[k].parameters)
      values.push_back({"step " + std::to_string(k + 1), p.name, p.value});
  }
  const int index = r.model.findEffect(type);
  if (index >= 0) {
    const Effect& effect = r.model.effect(index);
    const std::vector<std::string> names = effect.parameterNames();
    const std::vector<double> parameters = effect.parameters();
    for (std::size_t i = 0; i < names.size() && i < parameters.size(); ++i)
      values.push_back({"final model", names[i], parameters[i]});
  }
  return values;
}

// The final model's value of the parameter `name` (a failure and NaN when it has none).
inline double acceptedValue(const DiscoveryResult& r, const std::string& name) {
  for (int i = 0; i < r.model.effectCount(); ++i) {
    const std::vector<std::string> names = r.model.effect(i).parameterNames();
    const std::vector<double> values = r.model.effect(i).parameters();
    for (std::size_t k = 0; k < names.size(); ++k)
      if (names[k] == name) return values[k];
  }
  ADD_FAILURE() << "the final model has no " << name;
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace tempting
}  // namespace jointcomp
