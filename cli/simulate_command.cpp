// `jointcomp simulate`: a measurement campaign generated from a "true" robot with simulated instruments.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/output_paths.hpp"
#include "cli/robot_setup.hpp"
#include "model/common/errors.hpp"
#include "model/effects/perturbation.hpp"
#include "model/experiment/campaign_simulation.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp::cli {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;
// What the options of a simulated campaign may be (beyond them a run is refused naming the option): angles
// within ten turns, a target within 10 m of the flange, settling up to an hour per pose, rows as the
// experiment layer allows (kMaxSweepRows, kMaxRandomPoses).
constexpr Bounds kAngleDeg = {-3600.0, 3600.0};
constexpr Bounds kTargetMm = {-1e4, 1e4};
constexpr long long kMaxCycles = 10000;
constexpr long long kMaxGlobalPoses = 1000;

// --warm-up RISE_DEGC[,TAU_S[,START_DEGC]] into `profile`.
void readWarmUp(const std::string& text, TemperatureProfile& profile) {
  const std::vector<std::string> items = splitCommaList(text);
  if (items.empty() || items.size() > 3) throw UsageError("--warm-up takes RISE_DEGC[,TAU_S[,START_DEGC]]");
  profile.enabled = true;
  profile.rise_degc = parseNumber(items[0], "warm-up", {-200.0, 200.0});
  if (items.size() > 1) profile.time_constant_s = parseNumber(items[1], "warm-up", {0.0, 1e7, true});
  if (items.size() > 2) profile.start_degc = parseNumber(items[2], "warm-up", {-100.0, 200.0});
}

// The options that shape the campaign (target, pose, sweep, counts, warm-up, plant) into `spec`.
void readCampaignOptions(const Options& options, const RobotSetup& setup, CampaignSimulationSpec& spec) {
  if (options.has("target")) {
    const std::vector<double> target = numberList(options.get("target", ""), "target", kTargetMm);
    if (target.size() != 3) throw std::invalid_argument("--target takes x,y,z in mm");
    spec.target_in_flange = Eigen::Vector3d(target[0], target[1], target[2]) * 1e-3;
  }
  if (options.has("pose")) {
    const std::vector<double> pose = numberList(options.get("pose", ""), "pose", kAngleDeg);
    if (static_cast<int>(pose.size()) != setup.robot->dof()) {
      throw std::invalid_argument("--pose takes " + std::to_string(setup.robot->dof()) + " joint angles in degrees");
    }
    JointVector q(setup.robot->dof());
    for (int j = 0; j < setup.robot->dof(); ++j) q[j] = pose[j] * kDegree;
    spec.stiffness.pose = q;
    spec.sweep.pose = q;
  }
  spec.sweep.joint = static_cast<int>(options.integer("joint", 2, 1, kMaxJoints)) - 1;
  spec.sweep.from_rad = options.number("from", spec.sweep.from_rad / kDegree, kAngleDeg) * kDegree;
  spec.sweep.to_rad = options.number("to", spec.sweep.to_rad / kDegree, kAngleDeg) * kDegree;
  spec.sweep.step_rad = options.number("step", spec.sweep.step_rad / kDegree, {0.0, 360.0, true}) * kDegree;
  spec.sweep.settle_s = options.number("settle", spec.sweep.settle_s, {0.0, 3600.0, true});
  spec.sweep.cycles = static_cast<int>(options.integer("cycles", spec.sweep.cycles, 1, kMaxCycles));
  spec.random.count = static_cast<int>(options.integer("count", spec.random.count, 1, kMaxRandomPoses));
  spec.stiffness.global_poses =
      static_cast<int>(options.integer("global-poses", spec.stiffness.global_poses, 0, kMaxGlobalPoses));
  if (options.has("warm-up")) readWarmUp(options.get("warm-up", ""), spec.temperature);
  if (options.has("plant")) {
    if (!setup.parameters.hasDrives()) {
      throw ParameterError(setup.params + ": no \"plant\" object (drives and controller gains) for the plant");
    }
    spec.drives = setup.parameters.drives;
  }
}

// The instruments' noise, as the run simulates them.
void printInstruments(const CampaignSimulationSpec& spec) {
  std::printf(
      "  instruments: tracker 1 sigma = %.1f um + %.1f um/m from (%.0f, %.0f, %.0f) mm; levels 1 sigma = %.4f deg%s\n",
      spec.tracker.constant_m * 1e6, spec.tracker.per_metre * 1e6, spec.tracker.tracker_position.x() * 1e3,
      spec.tracker.tracker_position.y() * 1e3, spec.tracker.tracker_position.z() * 1e3, spec.level.sigma_rad / kDegree,
      spec.noise ? "" : " (noise off)");
}

}  // namespace

int runSimulate(int argc, char** argv) {
  const Options options(argc, argv,
                        {"protocol", "truth",  "urdf",   "base-link", "tip-link", "seed",         "out",
                         "perturb",  "plant",  "target", "joint",     "from",     "to",           "step",
                         "settle",   "cycles", "count",  "pose",      "no-noise", "global-poses", "warm-up"},
                        {"plant", "no-noise"});
  if (!options.has("protocol") || !options.has("truth")) {
    throw std::invalid_argument(
        "simulate needs --protocol stiffness|joint2-sweep|spiral|random|back-and-forth and --truth PARAMS.json");
  }
  const std::string protocol_name = options.get("protocol", "");
  const RobotSetup setup = loadRobotSetup(options, robotFile("rx170"), "truth");
  const std::string& truth_path = setup.params;
  CampaignSimulationSpec spec = defaultCampaignSpec(protocolFromName(protocol_name));
  const std::string out = options.get("out", "out/" + protocolName(spec.protocol) + ".csv");
  prepareOutputFile(out);
  const std::shared_ptr<const Robot>& robot = setup.robot;
  JointErrorModel truth = setup.parameters.model;
  spec.metadata["truth"] = truth_path;
  std::string truth_written;
  if (options.has("perturb")) {
    PerturbationSpec perturbation;
    perturbation.seed = static_cast<std::uint64_t>(options.integer("perturb", 2012, 0, kMaxSeed));
    truth = perturbedModel(truth, perturbation);
    std::filesystem::path truth_file(out);
    truth_file.replace_extension(".truth.json");
    truth_written = truth_file.string();
    spec.metadata["truth"] =
        truth_written + " (" + truth_path + " perturbed with seed " + options.get("perturb", "") + ")";
  }
  spec.seed = static_cast<std::uint64_t>(options.integer("seed", 1, 0, kMaxSeed));
  spec.noise = !options.has("no-noise");
  readCampaignOptions(options, setup, spec);

  std::printf("jointcomp simulate: %s campaign of robot '%s'\n  truth %s\n", protocolName(spec.protocol).c_str(),
              robot->name.c_str(), spec.metadata["truth"].c_str());
  printInstruments(spec);
  const MeasurementCampaign campaign = simulateCampaign(truth, spec, [](const std::string& what) {
    std::printf("  %s\n", what.c_str());
    std::fflush(stdout);
  });
  writeCampaignFile(campaign, out);
  if (!truth_written.empty()) saveParameterFile(truth, truth_written);
  std::printf("wrote %zu rows (%.0f s of campaign, %s) to %s\n", campaign.size(), campaign.time.back(),
              campaign.metadata.at("simulated_by").c_str(), out.c_str());
  if (!truth_written.empty()) std::printf("wrote the perturbed truth to %s\n", truth_written.c_str());
  return 0;
}

}  // namespace jointcomp::cli
