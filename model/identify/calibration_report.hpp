// A kinematic calibration run end to end, as the CLI (`jointcomp calibrate`) and the C API (jc_calibrate)
// both do it: fit on one campaign or on several (one instrument frame per set-up), check on held-out ones, build the
// calibrated robot and joint-error model; then its report (JSON, a readable summary, the per-row residuals as CSV).
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "model/identify/geometric_calibration.hpp"
#include "model/identify/residual_analysis.hpp"

namespace jointcomp {

struct CalibrationHoldoutRun {
  std::string name;                   // the campaign's file name, as given
  HoldoutEvaluation before;           // nominal robot, frame re-fitted
  HoldoutEvaluation after;            // calibrated robot, frame re-fitted
  HoldoutEvaluation shared_frame;     // calibrated robot in the calibration campaign's frame
  std::vector<RowResidual> residual;  // calibrated robot, frame re-fitted (after), per used row
};

struct CalibrationRun {
  GeometricCalibrationResult result;
  std::vector<CalibrationHoldoutRun> holdouts;
  std::shared_ptr<const Robot> calibrated_robot;  // joint placements corrected
  JointErrorModel calibrated;                     // offsets and compliance as fitted, on calibrated_robot
  std::vector<std::string> compliance_left_out;   // "<joint>: reason" (see calibratedJointErrorModel)
  double seconds = 0.0;                           // wall time of the fit
  std::vector<RowResidual> residual;              // calibrated, per used row of the campaign
  PosePredictability pose;                        // how much of that residual is a function of the pose
  std::vector<std::size_t> campaign_rows;         // rows of each fitted campaign, used or not
};

CalibrationRun runCalibration(const JointErrorModel& prior, const MeasurementCampaign& campaign,
                              const std::vector<std::pair<std::string, MeasurementCampaign>>& holdouts,
                              const GeometricCalibrationOptions& options);
// Fitted on several campaigns: one robot, one frame (and scale) per instrument set-up (calibrateGeometry).
CalibrationRun runCalibration(const JointErrorModel& prior, const std::vector<MeasurementCampaign>& campaigns,
                              const std::vector<std::pair<std::string, MeasurementCampaign>>& holdouts,
                              const GeometricCalibrationOptions& options);

// What the report names: the inputs as the user gave them and, when written, the outputs.
struct CalibrationSources {
  std::string urdf;
  std::string parameters;              // empty: no parameter file (no prior effects)
  std::string campaign;                // as the user gave it (several: the files joined by ',')
  std::vector<std::string> campaigns;  // each fitted campaign's file; empty: {campaign}
  nlohmann::ordered_json outputs = nlohmann::ordered_json::object();
};

nlohmann::ordered_json calibrationReportJson(const CalibrationRun& run, const GeometricCalibrationOptions& options,
                                             const CalibrationSources& sources);
std::string calibrationSummary(const CalibrationRun& run, const CalibrationSources& sources);
// campaign,role,row,before_mm,after_mm,weight, then the residual after calibration, measured - predicted:
// dx_mm,dy_mm,dz_mm in the campaign's frame and dq_<joint>_mrad mapped to the joints (RowResidual): one line
// per used row of every campaign.
std::string calibrationResidualsCsv(const CalibrationRun& run, const CalibrationSources& sources);

// The instrument set-ups of a calibration on several campaigns (`files`: each campaign's file, as given):
// each set-up's campaigns, frame and scale; and the sentence the summaries print.
nlohmann::ordered_json instrumentSetUpsJson(const GeometricCalibrationResult& result,
                                            const std::vector<std::string>& files);
std::string describeInstrumentSetUps(const GeometricCalibrationResult& result, const std::vector<std::string>& files);

// Statistics in the units people read (mm), as every report writes them.
nlohmann::ordered_json errorStatisticsJson(const ErrorStatistics& statistics);
// residual_analysis.hpp's PosePredictability in report units (mm, rad); null when not computed.
nlohmann::ordered_json posePredictabilityJson(const PosePredictability& pose);

}  // namespace jointcomp
