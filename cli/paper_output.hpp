// What `jointcomp paper` prints and writes: the runs of the nominal model, of the identified model and of
// the perfect model (the floor) as a Table II analogue, spiral_runs.csv and summary.json, and the
// identification that gave the identified model (its parameters with their intervals, its reports).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "model/experiment/paper_identification.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "model/robot/drive_parameters.hpp"

namespace jointcomp::cli {

// The paper's feed rate (m/s).
constexpr double kPaperFeedRate = 0.03;

// The runs of one `paper`: the nominal model's always, the identified model's (from run 1) and the perfect
// model's (from run 2) unless --nominal-only (null then).
struct PaperRuns {
  const SpiralExperimentResult* nominal = nullptr;
  const SpiralExperimentResult* identified = nullptr;
  const SpiralExperimentResult* perfect = nullptr;
};

std::string runsCsv(const PaperRuns& runs);
std::string summaryJson(const PaperRuns& runs, const SpiralExperimentSpec& spec, const std::string& robot_name,
                        const nlohmann::ordered_json& identification);
void printTable(const PaperRuns& runs);

// Where the identification's files went (under `folder`), for the console and summary.json.
struct IdentificationFiles {
  std::string folder, parameters, truth, report, stiffness_report, transmission_report, summary, stiffness_campaign,
      sweep_campaign;
};

// The identified parameters with their intervals beside the truth, on the console.
std::string identificationSummary(const PaperIdentification& identification, const JointErrorModel& truth);
// Writes the campaigns, the identified parameter file (with `drives`), the two identifications' reports and
// report.json, which holds both (jointcomp montecarlo --params PARAMS --report report.json draws from it).
IdentificationFiles writeIdentification(const std::string& folder, const PaperIdentification& identification,
                                        const JointErrorModel& truth, const std::vector<DriveParameters>& drives,
                                        const std::string& nominal_params, const std::string& urdf);
// summary.json's "identification": the identified values, intervals and truths, and the files.
nlohmann::ordered_json identificationJson(const PaperIdentification& identification, const JointErrorModel& truth,
                                          const IdentificationFiles& files);

}  // namespace jointcomp::cli
