// `jointcomp discover`: residual discovery. Fits the base model (frame, target; optionally the textbook
// geometry) to the fitted campaigns, then adds, one at a time, the candidate effect that best lowers the
// time-blocked cross-validated error and the BIC, refitting everything each time, until none helps.
// Writes report.json (effect types from the fixed vocabulary), summary.txt, steps.csv, the extended
// parameter file (parameters.json, with the calibrated URDF beside it) and a plot.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <sys/stat.h>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "model/common/errors.hpp"
#include "model/identify/discovery.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/measurement_campaign.hpp"
#include "model/io/parameter_file.hpp"
#include "model/io/urdf_writer.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp::cli {
namespace {

nlohmann::ordered_json stats(const ErrorStatistics& s) {
  return {{"rows", s.rows}, {"mean_mm", s.mean * 1e3}, {"rms_mm", s.rms * 1e3}, {"max_mm", s.max * 1e3}};
}

nlohmann::ordered_json stateJson(const DiscoveryState& s, const std::vector<std::string>& holdouts) {
  nlohmann::ordered_json held = nlohmann::ordered_json::array();
  for (std::size_t k = 0; k < s.heldout.size(); ++k) {
    nlohmann::ordered_json entry = stats(s.heldout[k]);
    entry["campaign"] = holdouts[k];
    held.push_back(entry);
  }
  return {{"fitted", stats(s.fitted)}, {"held_out", held}, {"cv_rms_per_axis_mm", s.cv_rms * 1e3},
          {"ra_rz_on_paths", nullptr}};
}

std::string heldRms(const DiscoveryState& s) {
  if (s.heldout.empty()) return "-";
  char text[64];
  std::snprintf(text, sizeof(text), "%.4f", s.heldout[0].rms * 1e3);
  return text;
}

}  // namespace

int runDiscover(int argc, char** argv) {
  std::vector<std::string> campaigns, holdouts;
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--campaign" || arg == "--holdout") {
      if (i + 1 >= argc) throw std::invalid_argument("option " + arg + " needs a value");
      for (const std::string& item : splitCommaList(argv[++i])) (arg == "--campaign" ? campaigns : holdouts).push_back(item);
      continue;
    }
    rest.push_back(argv[i]);
  }
  const Options options(static_cast<int>(rest.size()), rest.data(),
                        {"urdf", "params", "out", "base", "max-steps", "orders", "folds", "types", "noise-floor-mm",
                         "loss", "min-cv-gain", "no-plot"},
                        {"no-plot"});
  if (campaigns.empty() || !options.has("out")) {
    throw std::invalid_argument("discover needs --campaign FILE[,FILE..] and --out DIR (and --urdf, --params, --holdout)");
  }
  const std::string urdf = options.get("urdf", JOINTCOMP_DATA_DIR "/robots/ur10.urdf");
  const std::string out = options.get("out", "");
  const auto started = std::chrono::steady_clock::now();
  auto robot = std::make_shared<const Robot>(loadRobotFromUrdfFile(urdf));
  const bool has_params = options.has("params");
  const JointErrorModel prior = has_params ? loadParameterFile(options.get("params", ""), robot)
                                           : JointErrorModel(robot, GearTrain::direct(robot->dof()), {});
  DiscoveryOptions discovery;
  discovery.calibration.loss = parseRobustLoss(options.get("loss", "huber"));
  const std::string base = options.get("base", "frame");
  if (base != "frame" && base != "textbook") throw std::invalid_argument("--base must be frame or textbook, not '" + base + "'");
  discovery.base_geometry = base == "textbook";
  discovery.max_steps = std::stoi(options.get("max-steps", "8"));
  discovery.max_harmonic_order = std::stoi(options.get("orders", "4"));
  discovery.folds = std::stoi(options.get("folds", "5"));
  discovery.min_cv_gain = std::stod(options.get("min-cv-gain", "0.02"));
  discovery.noise_floor = std::stod(options.get("noise-floor-mm", "0")) * 1e-3;
  discovery.types = splitCommaList(options.get("types", ""));
  for (const std::string& type : discovery.types) {
    bool known = false;
    for (const std::string& t : discoveryEffectTypes()) known = known || t == type;
    if (!known) throw std::invalid_argument("--types: unknown effect type '" + type + "'");
  }

  std::vector<MeasurementCampaign> fitted, held;
  for (const std::string& path : campaigns) fitted.push_back(readCampaignFile(path));
  for (const std::string& path : holdouts) held.push_back(readCampaignFile(path));
  std::printf("jointcomp discover: robot %s, %zu fitted and %zu held-out campaign(s), base %s\n", robot->name.c_str(),
              fitted.size(), held.size(), base.c_str());
  const auto fit_started = std::chrono::steady_clock::now();
  const DiscoveryResult result = discoverEffects(prior, fitted, held, discovery);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - fit_started).count();

  ::mkdir(out.c_str(), 0755);
  const std::string urdf_out = out + "/" + robot->name + "_discovered.urdf";
  saveRobotUrdf(result.model.robot(), urdf_out,
                "  " + robot->name + " after jointcomp discover\n  nominal: " + urdf +
                    "\n  Joint placements corrected; joint offsets, compliance and the discovered effects are in the "
                    "parameter file.");
  std::vector<DriveParameters> drives;
  if (has_params) {
    try {
      drives = loadDriveParameters(options.get("params", ""), *robot);
    } catch (const ParameterError&) {
      drives.clear();
    }
  }
  const std::string params_out = out + "/parameters.json";
  saveParameterFile(result.model, params_out, drives);

  nlohmann::ordered_json report;
  report["format"] = "jointcomp-discovery-report/1";
  report["robot"] = robot->name;
  report["urdf"] = urdf;
  report["params"] = has_params ? nlohmann::ordered_json(options.get("params", "")) : nlohmann::ordered_json(nullptr);
  report["campaigns"] = campaigns;
  report["held_out"] = holdouts;
  report["vocabulary"] = discoveryEffectTypes();
  report["selection"] = {{"cross_validation", "time-blocked K-fold (blocks of consecutive rows)"},
                         {"folds", discovery.folds},
                         {"min_cv_gain", discovery.min_cv_gain},
                         {"criterion", "dBIC = N ln(RSS_c/RSS_0) + dk ln N + 2 ln(candidates) < 0"},
                         {"base", base},
                         {"max_steps", discovery.max_steps},
                         {"max_harmonic_order", discovery.max_harmonic_order},
                         {"candidates", result.candidates}};
  report["fitted_rows"] = result.fitted_rows;
  report["initial"] = stateJson(result.initial, holdouts);
  report["initial"]["joint_residual_rms_rad"] = result.joint_residual_rms_initial;
  nlohmann::ordered_json steps = nlohmann::ordered_json::array();
  std::ostringstream csv;
  csv << "step,effect,fitted_rms_mm,heldout_rms_mm,cv_rms_mm\n";
  csv << "0,base," << result.initial.fitted.rms * 1e3 << ',' << heldRms(result.initial) << ','
      << result.initial.cv_rms * 1e3 << "\n";
  std::ostringstream summary;
  summary << "jointcomp discover: " << robot->name << ", " << result.fitted_rows << " fitted rows, "
          << result.candidates << " candidates, base " << base << "\n";
  char line[512];
  std::snprintf(line, sizeof(line), "base model: fitted RMS %.4f mm, held-out RMS %s mm\n", result.initial.fitted.rms * 1e3,
                heldRms(result.initial).c_str());
  summary << line;
  int index = 0;
  for (const DiscoveryStep& s : result.steps) {
    ++index;
    nlohmann::ordered_json entry = {{"step", index}, {"type", s.type}, {"joint", s.joint_name}, {"joint_index", s.joint + 1}};
    if (s.type == "harmonic") {
      entry["part"] = s.part;
      entry["stage"] = s.stage;
      entry["order"] = s.cycles;
    }
    if (s.type == "thermal") entry["variant"] = s.part;
    nlohmann::ordered_json parameters = nlohmann::ordered_json::array();
    for (const DiscoveredParameter& p : s.parameters) parameters.push_back({{"name", p.name}, {"value", p.value}, {"sigma", p.sigma}});
    entry["parameters"] = parameters;
    entry["evidence"] = {{"cv_rms_per_axis_mm_before", s.cv_rms_before * 1e3},
                         {"cv_rms_per_axis_mm_after", s.cv_rms_after * 1e3},
                         {"delta_bic", s.delta_bic},
                         {"candidates_tried", s.candidates_tried},
                         {"runner_up", s.runner_up}};
    entry["before"] = stateJson(s.before, holdouts);
    entry["after"] = stateJson(s.after, holdouts);
    steps.push_back(entry);
    std::string label = s.type + " " + s.joint_name;
    if (s.type == "harmonic") label += " " + s.part + " order " + std::to_string(static_cast<int>(s.cycles));
    if (s.type == "thermal") label += " (" + s.part + ")";
    std::snprintf(line, sizeof(line), "step %d: %-44s CV %.4f -> %.4f mm/axis, dBIC %.1f; fitted RMS %.4f -> %.4f mm, held-out %s -> %s mm\n",
                  index, label.c_str(), s.cv_rms_before * 1e3, s.cv_rms_after * 1e3, s.delta_bic, s.before.fitted.rms * 1e3,
                  s.after.fitted.rms * 1e3, heldRms(s.before).c_str(), heldRms(s.after).c_str());
    summary << line;
    for (const DiscoveredParameter& p : s.parameters) {
      std::snprintf(line, sizeof(line), "    %-48s %.6g +- %.3g\n", p.name.c_str(), p.value, p.sigma);
      summary << line;
    }
    csv << index << ',' << label << ',' << s.after.fitted.rms * 1e3 << ',' << heldRms(s.after) << ','
        << s.after.cv_rms * 1e3 << "\n";
  }
  report["steps"] = steps;
  report["final"] = stateJson(result.final_state, holdouts);
  report["final"]["joint_residual_rms_rad"] = result.joint_residual_rms_final;
  report["stop_reason"] = result.stop_reason;
  const double final_held = result.final_state.heldout.empty() ? result.final_state.fitted.rms : result.final_state.heldout[0].rms;
  report["noise_floor"] = {{"rms_3d_mm", result.noise_floor * 1e3},
                           {"final_over_floor", result.noise_floor > 0.0 ? nlohmann::ordered_json(final_held / result.noise_floor)
                                                                          : nlohmann::ordered_json(nullptr)}};
  report["not_candidates"] = {"payload", "hysteresis"};
  report["seconds"] = seconds;
  report["outputs"] = {{"parameters", params_out}, {"urdf", urdf_out}};
  writeFileAtomically(out + "/report.json", report.dump(2) + "\n");
  writeFileAtomically(out + "/steps.csv", csv.str());
  std::snprintf(line, sizeof(line), "stopped: %s\nfinal: fitted RMS %.4f mm, held-out RMS %s mm; noise floor %.4f mm (3-D RMS)%s\n",
                result.stop_reason.c_str(), result.final_state.fitted.rms * 1e3, heldRms(result.final_state).c_str(),
                result.noise_floor * 1e3, result.noise_floor > 0.0 ? "" : " (not known: give --noise-floor-mm)");
  summary << line;
  summary << "Wrote " << params_out << ", " << urdf_out << ", " << out << "/report.json, " << out << "/steps.csv\n";
  writeFileAtomically(out + "/summary.txt", summary.str());
  std::fputs(summary.str().c_str(), stdout);
  if (!options.has("no-plot")) {
    const std::string command = "/usr/bin/python3 '" JOINTCOMP_SOURCE_DIR "/cli/plots/plot_discovery.py' '" + out +
                                "/steps.csv' '" + out + "/discovery.png'";
    if (std::system(command.c_str()) == 0) std::printf("wrote %s/discovery.png\n", out.c_str());
    else std::printf("no plot: %s failed (needs Debian's python3-matplotlib)\n", command.c_str());
  }
  std::printf("done in %.2f s (discovery %.2f s)\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), seconds);
  return 0;
}

}  // namespace jointcomp::cli
