// `jointcomp paper`'s identification: its parameters with their intervals beside the truth (console and
// summary.json) and its files (campaigns, identified parameter file, reports).
#include <cmath>
#include <cstdio>
#include <sstream>

#include "cli/output_paths.hpp"
#include "cli/paper_output.hpp"
#include "model/effects/compliance.hpp"
#include "model/identify/identification_report.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/parameter_file.hpp"

namespace jointcomp::cli {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

// The estimate that went into the identified model (withIdentifiedStiffness's choice), null when none did.
const StiffnessEstimate* usedEstimate(const StiffnessIdentificationResult& result, std::size_t joint, bool use_global) {
  const StiffnessEstimate& first = use_global ? result.global[joint] : result.local[joint];
  const StiffnessEstimate& second = use_global ? result.local[joint] : result.global[joint];
  if (first.identified) return &first;
  if (second.identified) return &second;
  return nullptr;
}

double trueStiffness(const JointErrorModel& truth, std::size_t joint) {
  const int index = truth.findEffect(ComplianceEffect::kType);
  if (index < 0) return std::nan("");
  return static_cast<const ComplianceEffect&>(truth.effect(index)).stiffness(static_cast<int>(joint));
}

nlohmann::ordered_json finiteOrNull(double value) {
  return std::isfinite(value) ? nlohmann::ordered_json(value) : nlohmann::ordered_json(nullptr);
}

}  // namespace

std::string identificationSummary(const PaperIdentification& identification, const JointErrorModel& truth) {
  const PaperIdentificationSources sources{"the nominal parameters", truth.robot().name,
                                           identification.stiffness_campaign.source,
                                           identification.sweep_campaign.source, ""};
  return paperIdentificationReport(identification, sources, &truth).summary;
}

IdentificationFiles writeIdentification(const std::string& folder, const PaperIdentification& identification,
                                        const JointErrorModel& truth, const std::vector<DriveParameters>& drives,
                                        const std::string& nominal_params, const std::string& urdf) {
  prepareOutputFolder(folder, "--out (its identification folder)");
  IdentificationFiles files;
  files.folder = folder;
  files.stiffness_campaign = folder + "/stiffness_campaign.csv";
  files.sweep_campaign = folder + "/sweep_campaign.csv";
  files.parameters = folder + "/params.json";
  files.stiffness_report = folder + "/stiffness_report.json";
  files.transmission_report = folder + "/transmission_report.json";
  files.report = folder + "/report.json";
  files.summary = folder + "/summary.txt";
  writeCampaignFile(identification.stiffness_campaign, files.stiffness_campaign);
  writeCampaignFile(identification.sweep_campaign, files.sweep_campaign);
  saveParameterFile(*identification.identified, files.parameters, drives);
  files.truth = folder + "/truth.json";  // the simulated robot, for a rerun through the C API or Python
  saveParameterFile(truth, files.truth, drives);

  const PaperIdentificationSources sources{nominal_params, urdf, files.stiffness_campaign, files.sweep_campaign,
                                           files.parameters};
  const PaperIdentificationReport report = paperIdentificationReport(identification, sources, &truth);
  writeFileAtomically(files.stiffness_report, report.stiffness.dump(2) + "\n");
  writeFileAtomically(files.transmission_report, report.transmission.dump(2) + "\n");
  writeFileAtomically(files.report, report.both.dump(2) + "\n");
  writeFileAtomically(files.summary, report.summary);
  return files;
}

nlohmann::ordered_json identificationJson(const PaperIdentification& identification, const JointErrorModel& truth,
                                          const IdentificationFiles& files) {
  nlohmann::ordered_json json;
  const StiffnessIdentificationResult& s = identification.stiffness;
  json["confidence"] = s.confidence;
  json["campaign_rows"] = {{"stiffness", identification.stiffness_campaign.size()},
                           {"sweep", identification.sweep_campaign.size()}};
  for (std::size_t j = 0; j < s.joint_names.size(); ++j) {
    nlohmann::ordered_json entry = {{"joint", s.joint_names[j]}};
    const double truth_k = trueStiffness(truth, j);
    if (const StiffnessEstimate* e = usedEstimate(s, j, false)) {
      entry["method"] = e->method;
      entry["stiffness_nm_per_rad"] = e->stiffness;
      entry["stiffness_se_nm_per_rad"] = e->stiffness_se;
      entry["stiffness_interval_nm_per_rad"] = {e->stiffness_low, finiteOrNull(e->stiffness_high)};
      if (std::isfinite(truth_k))
        entry["interval_covers_truth"] = truth_k >= e->stiffness_low && truth_k <= e->stiffness_high;
    } else {
      entry["method"] = nullptr;
    }
    entry["true_stiffness_nm_per_rad"] = finiteOrNull(truth_k);
    json["stiffness"].push_back(entry);
  }
  const TransmissionIdentificationResult& t = identification.transmission;
  json["transmission_error"] = {
      {"joint", t.joint_name}, {"of", t.part}, {"harmonics", nlohmann::ordered_json::array()}};
  for (const HarmonicEstimate& h : t.harmonics) {
    nlohmann::ordered_json entry = {
        {"cycles_per_revolution", h.order},
        {"amplitude_deg", h.amplitude_rad * kRadToDeg},
        {"amplitude_interval_deg", {h.amplitude_low_rad * kRadToDeg, h.amplitude_high_rad * kRadToDeg}},
        {"phase_rad", h.phase_rad},
        {"phase_interval_rad", {h.phase_low_rad, h.phase_high_rad}}};
    double amplitude = 0.0, phase = 0.0;
    if (trueHarmonic(truth, t.joint, t.stage, h.order, amplitude, phase)) {
      entry["true_amplitude_deg"] = amplitude * kRadToDeg;
      entry["true_phase_rad"] = phase;
    }
    json["transmission_error"]["harmonics"].push_back(entry);
  }
  json["load_refit"] = sweepLoadRefitJson(identification.load_refit);
  json["files"] = {{"parameters", files.parameters},
                   {"report", files.report},
                   {"truth", files.truth},
                   {"stiffness_campaign", files.stiffness_campaign},
                   {"sweep_campaign", files.sweep_campaign}};
  return json;
}

}  // namespace jointcomp::cli
