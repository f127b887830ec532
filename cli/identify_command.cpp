// `jointcomp identify stiffness|transmission`: joint stiffness or transmission-error harmonics from a
// measurement campaign, written as an updated parameter file, a JSON report, a short summary and a plot.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/output_paths.hpp"
#include "cli/plot.hpp"
#include "cli/robot_setup.hpp"
#include "model/identify/identification_report.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp::cli {

int runIdentify(int argc, char** argv) {
  if (argc >= 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::printf(
        "jointcomp identify stiffness|transmission --campaign FILE --out DIR [OPTIONS]\n"
        "  jointcomp identify stiffness --help (or transmission --help) lists the options\n");
    throw HelpShown();
  }
  if (argc < 2 || std::string(argv[1]).rfind("--", 0) == 0) {
    throw std::invalid_argument(
        "identify needs a kind: jointcomp identify stiffness|transmission --campaign FILE --out DIR");
  }
  const std::string kind = argv[1];
  if (kind != "stiffness" && kind != "transmission") {
    throw std::invalid_argument("identify: unknown kind '" + kind + "' (stiffness or transmission)");
  }
  const Options options(argc - 1, argv + 1,
                        {"campaign", "urdf", "base-link", "tip-link", "params", "joint", "stage", "out", "truth", "use",
                         "orders", "no-plot"},
                        {"no-plot"}, "identify " + kind);
  if (!options.has("campaign") || !options.has("out")) {
    throw std::invalid_argument("identify " + kind + " needs --campaign FILE and --out DIR");
  }
  const std::string campaign_path = options.get("campaign", "");
  const RobotSetup setup = loadRobotSetup(options, robotFile("rx170"), "params", parameterFile("rx170"));
  const std::string& urdf = setup.urdf;
  const std::string& params = setup.params;
  const std::string out = options.get("out", "");
  prepareOutputFolder(out);
  const std::string use = options.get("use", "local");
  if (use != "local" && use != "global") throw std::invalid_argument("--use takes local or global");

  const std::shared_ptr<const Robot>& robot = setup.robot;
  const JointErrorModel& nominal = setup.parameters.model;
  const std::vector<DriveParameters>& drives = setup.parameters.drives;  // kept in the updated file
  const MeasurementCampaign campaign = readCampaignFile(campaign_path);
  std::unique_ptr<JointErrorModel> truth;
  if (options.has("truth"))
    truth = std::make_unique<JointErrorModel>(loadParameterFile(options.get("truth", ""), robot));

  ReportSources sources;
  sources.campaign = campaign_path;
  sources.parameters = params;
  sources.robot = urdf;
  sources.updated_parameters = out + "/params.json";
  nlohmann::ordered_json report;
  std::string summary;
  std::string plot_name;
  if (kind == "stiffness") {
    if (options.has("joint") || options.has("stage") || options.has("orders")) {
      throw std::invalid_argument("identify stiffness takes no --joint, --stage or --orders");
    }
    const StiffnessIdentificationResult result = identifyStiffness(nominal, campaign);
    sources.method_used = use;
    const JointErrorModel updated = withIdentifiedStiffness(nominal, result, use == "global", campaign_path);
    saveParameterFile(updated, sources.updated_parameters, drives);
    report = stiffnessReportJson(result, sources, truth.get());
    summary = stiffnessSummary(result, sources, truth.get());
    plot_name = "stiffness.png";
  } else {
    if (options.has("use")) throw std::invalid_argument("identify transmission takes no --use");
    TransmissionIdentificationOptions o;
    o.joint = static_cast<int>(options.integer("joint", 2, 1, kMaxJoints)) - 1;
    o.stage = static_cast<int>(options.integer("stage", 2, 1, 16));
    if (options.has("orders"))
      o.candidate_orders =
          numberList(options.get("orders", ""), "orders", {0.0, static_cast<double>(kMaxHarmonicOrder), true});
    const TransmissionIdentificationResult result = identifyTransmissionError(nominal, campaign, o);
    const JointErrorModel updated = withIdentifiedHarmonics(nominal, result, campaign_path);
    saveParameterFile(updated, sources.updated_parameters, drives);
    report = transmissionReportJson(result, sources, truth.get());
    summary = transmissionSummary(result, sources, truth.get());
    plot_name = "transmission_error.png";
  }
  writeFileAtomically(out + "/report.json", report.dump(2) + "\n");
  writeFileAtomically(out + "/summary.txt", summary);
  std::printf("%s\n", summary.c_str());
  std::printf("wrote %s/params.json, %s/report.json, %s/summary.txt\n", out.c_str(), out.c_str(), out.c_str());
  if (!options.has("no-plot")) drawPlot("plot_identification.py", out + "/report.json", out + "/" + plot_name);

  return 0;
}

}  // namespace jointcomp::cli
