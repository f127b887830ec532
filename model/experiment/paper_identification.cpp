#include "model/experiment/paper_identification.hpp"

#include <chrono>
#include <cstdio>

#include "model/common/errors.hpp"
#include "model/identify/identification_report.hpp"

namespace jointcomp {
namespace {

void tell(const std::function<void(const std::string&)>& progress, const std::string& what) {
  if (progress) progress(what);
}

std::string loadRefitSummary(const SweepLoadRefit& refit) {
  if (refit.names.empty()) return "";
  constexpr double kMilliDegree = 180.0 / 3.14159265358979323846 * 1e3;
  char line[200];
  std::snprintf(line, sizeof line,
                "\nLoad effects refitted to the sweep (what the harmonics left of it: RMS %.3f -> %.3f 1e-3 deg)\n",
                refit.rms_before_rad * kMilliDegree, refit.rms_after_rad * kMilliDegree);
  std::string text = line;
  for (std::size_t p = 0; p < refit.names.size(); ++p) {
    std::snprintf(line, sizeof line, "  %-42s %12.6g -> %12.6g +- %.2g\n", refit.names[p].c_str(), refit.nominal[p],
                  refit.value[p], refit.se[p]);
    text += line;
  }
  return text;
}

}  // namespace

nlohmann::ordered_json sweepLoadRefitJson(const SweepLoadRefit& refit) {
  nlohmann::ordered_json json;
  json["method"] = "the sweep's baseline, Gauss-Newton with a prior of the catalogue's tolerance";
  json["rows"] = refit.rows;
  json["residual_rms_before_deg"] = refit.rms_before_rad * 180.0 / 3.14159265358979323846;
  json["residual_rms_after_deg"] = refit.rms_after_rad * 180.0 / 3.14159265358979323846;
  json["parameters"] = nlohmann::ordered_json::array();
  for (std::size_t p = 0; p < refit.names.size(); ++p) {
    json["parameters"].push_back(
        {{"name", refit.names[p]}, {"nominal", refit.nominal[p]}, {"value", refit.value[p]}, {"se", refit.se[p]}});
  }
  return json;
}

std::pair<std::uint64_t, std::uint64_t> paperCampaignSeeds(std::uint64_t seed) {
  // Two odd multipliers keep the streams of neighbouring seeds and of the two campaigns apart.
  return {seed * 6364136223846793005ULL + 1442695040888963407ULL, seed * 2862933555777941757ULL + 3037000493ULL};
}

PaperIdentification identifyFromSimulatedCampaigns(const JointErrorModel& nominal, const JointErrorModel& truth,
                                                   const PaperIdentificationSpec& spec,
                                                   const std::function<void(const std::string&)>& progress) {
  if (truth.robot().dof() != nominal.robot().dof()) {
    throw InvalidArgument("the truth robot '" + truth.robot().name + "' has " + std::to_string(truth.robot().dof()) +
                          " joints, the nominal robot '" + nominal.robot().name + "' " +
                          std::to_string(nominal.robot().dof()));
  }
  if (spec.stiffness_campaign.protocol != CampaignProtocol::Stiffness ||
      spec.sweep_campaign.protocol != CampaignProtocol::JointSweep) {
    throw InvalidArgument("paper identification: the campaigns must be a stiffness protocol and a joint sweep");
  }
  if (spec.sweep_campaign.sweep.joint != spec.transmission.joint) {
    throw InvalidArgument("paper identification: the sweep moves joint " +
                          std::to_string(spec.sweep_campaign.sweep.joint + 1) +
                          ", the transmission error is asked of joint " + std::to_string(spec.transmission.joint + 1));
  }
  const auto started = std::chrono::steady_clock::now();
  PaperIdentification result;
  const auto [stiffness_seed, sweep_seed] = paperCampaignSeeds(spec.seed);

  CampaignSimulationSpec stiffness_spec = spec.stiffness_campaign;
  stiffness_spec.seed = stiffness_seed;
  tell(progress, "measuring the stiffness protocol (tracker and levels under known loads)");
  result.stiffness_campaign = simulateCampaign(truth, stiffness_spec);
  result.stiffness_campaign.source =
      "simulated stiffness campaign (paper identification, seed " + std::to_string(spec.seed) + ")";
  tell(progress, "identifying the joint stiffnesses");
  result.stiffness = identifyStiffness(nominal, result.stiffness_campaign, spec.stiffness);
  JointErrorModel stiff =
      withIdentifiedStiffness(nominal, result.stiffness, spec.use_global, result.stiffness_campaign.source);

  CampaignSimulationSpec sweep_spec = spec.sweep_campaign;
  sweep_spec.seed = sweep_seed;
  tell(progress, "measuring the joint-" + std::to_string(spec.transmission.joint + 1) + " sweep (tracker)");
  result.sweep_campaign = simulateCampaign(truth, sweep_spec);
  result.sweep_campaign.source = "simulated joint-" + std::to_string(spec.transmission.joint + 1) +
                                 " sweep (paper identification, seed " + std::to_string(spec.seed) + ")";
  tell(progress, "identifying the transmission error of joint " + std::to_string(spec.transmission.joint + 1));
  // Against the identified stiffness: the sweep's angles minus that model's deflection are the kinematic error.
  result.transmission = identifyTransmissionError(stiff, result.sweep_campaign, spec.transmission);
  JointErrorModel loads = stiff;
  if (spec.refit_loads) {
    tell(progress, "refitting the load effects of joint " + std::to_string(spec.transmission.joint + 1) +
                       " to what the harmonics leave of the sweep");
    result.load_refit = refitSweptJointLoads(loads, result.sweep_campaign, result.transmission, spec.load_refit);
    // The harmonics again, against the deflection the refitted loads predict.
    result.transmission = identifyTransmissionError(loads, result.sweep_campaign, spec.transmission);
  }
  result.identified = std::make_shared<const JointErrorModel>(
      withIdentifiedHarmonics(loads, result.transmission, result.sweep_campaign.source));
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return result;
}

PaperIdentificationReport paperIdentificationReport(const PaperIdentification& identification,
                                                    const PaperIdentificationSources& sources,
                                                    const JointErrorModel* truth) {
  ReportSources s;
  s.parameters = sources.nominal_parameters;
  s.robot = sources.robot;
  s.updated_parameters = sources.updated_parameters;
  s.method_used = "local";
  s.campaign = sources.stiffness_campaign;
  PaperIdentificationReport report;
  report.stiffness = stiffnessReportJson(identification.stiffness, s, truth);
  report.summary = stiffnessSummary(identification.stiffness, s, truth);
  s.campaign = sources.sweep_campaign;
  report.transmission = transmissionReportJson(identification.transmission, s, truth);
  report.summary += "\n" + transmissionSummary(identification.transmission, s, truth);
  report.both["format"] = "jointcomp-identification-reports/1";
  report.both["parameters"] = sources.updated_parameters;
  report.both["reports"] = {report.stiffness, report.transmission};
  report.both["load_refit"] = sweepLoadRefitJson(identification.load_refit);
  report.summary += loadRefitSummary(identification.load_refit);
  return report;
}

}  // namespace jointcomp
