// `jointcomp import-ipa` and `import-csv`: other files converted into a measurement campaign.
#include <cstdio>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/output_paths.hpp"
#include "model/io/csv_import.hpp"
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

int runImportCsv(int argc, char** argv) {
  const Options options(
      argc, argv,
      {"in", "out", "columns", "angles", "lengths", "separator", "decimal", "robot", "frame", "joints", "target"});
  if (!options.has("in") || !options.has("out")) {
    throw std::invalid_argument(
        "import-csv needs --in EXPORT.csv and --out CAMPAIGN.csv (and --columns t=NAME,q1=NAME,..,x=NAME,..)");
  }
  prepareOutputFile(options.get("out", ""));
  CsvImportOptions csv;
  csv.columns = parseColumnMapping(options.get("columns", ""));
  const std::string angles = options.get("angles", "deg");
  if (angles != "deg" && angles != "rad")
    throw std::invalid_argument("--angles takes deg or rad, not '" + angles + "'");
  csv.angles_in_radians = angles == "rad";
  const std::string lengths = options.get("lengths", "mm");
  if (lengths != "mm" && lengths != "m") throw std::invalid_argument("--lengths takes mm or m, not '" + lengths + "'");
  csv.lengths_in_metres = lengths == "m";
  const auto character = [&](const char* name, const std::string& value) -> char {
    if (value.empty()) return 0;
    if (value == "tab") return '\t';
    if (value.size() == 1 && (value == "," || value == ";" || value == "." || value == "|" || value == " "))
      return value[0];
    throw std::invalid_argument(std::string("--") + name + " takes one of , ; . | tab, not '" + value + "'");
  };
  csv.separator = character("separator", options.get("separator", ""));
  csv.decimal_mark = character("decimal", options.get("decimal", ""));
  csv.robot = options.get("robot", "");
  const std::string frame = options.get("frame", "base");
  if (frame != "base" && frame != "instrument") throw std::invalid_argument("--frame takes base or instrument");
  csv.frame = frame == "base" ? MeasurementFrame::Base : MeasurementFrame::Instrument;
  csv.joints = static_cast<int>(options.integer("joints", 0, 1, kMaxJoints));
  if (options.has("target")) {
    const std::vector<double> target = numberList(options.get("target", ""), "target", {-1e4, 1e4});
    if (target.size() != 3) throw std::invalid_argument("--target takes x,y,z in mm");
    csv.has_target = true;
    csv.target_in_flange = Eigen::Vector3d(target[0], target[1], target[2]) * 1e-3;
  }
  const MeasurementCampaign campaign = importCsvFile(options.get("in", ""), csv);
  writeCampaignFile(campaign, options.get("out", ""));
  std::printf(
      "imported %zu rows of %d joints from %s into %s (separator %s, decimal mark '%s', %s lines of "
      "preamble skipped%s%s)\n",
      campaign.size(), campaign.dof, options.get("in", "").c_str(), options.get("out", "").c_str(),
      campaign.metadata.at("separator").c_str(), campaign.metadata.at("decimal_mark").c_str(),
      campaign.metadata.at("imported_preamble_lines").c_str(),
      campaign.metadata.count("time_from") ? "; time from the row index" : "",
      campaign.has_target ? "; target from --target" : "; no target: the flange point unless calibrate --target says");
  return 0;
}

}  // namespace jointcomp::cli
