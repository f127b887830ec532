// `jointcomp import-ipa`: the IPA UR10 laser-tracker files converted into a measurement campaign.
#include <cstdio>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/output_paths.hpp"
#include "model/io/ipa_ur10_import.hpp"

namespace jointcomp::cli {

int runImportIpa(int argc, char** argv) {
  const Options options(argc, argv, {"in", "trafo", "out"});
  if (!options.has("in") || !options.has("out")) {
    throw std::invalid_argument("import-ipa needs --in MEASUREMENTS.csv and --out CAMPAIGN.csv (and --trafo FILE)");
  }
  prepareOutputFile(options.get("out", ""));
  const MeasurementCampaign campaign = importIpaUr10(options.get("in", ""), options.get("trafo", ""));
  writeCampaignFile(campaign, options.get("out", ""));
  std::printf("imported %zu rows from %s into %s (time from %s; %s rows held back in time)\n", campaign.size(),
              options.get("in", "").c_str(), options.get("out", "").c_str(), campaign.metadata.at("time_from").c_str(),
              campaign.metadata.at("time_held_rows").c_str());
  return 0;
}

}  // namespace jointcomp::cli
