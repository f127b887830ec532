#include "model/identify/kinematic_calibration.hpp"

#include <algorithm>

#include "model/common/errors.hpp"
#include "model/io/urdf_writer.hpp"

namespace jointcomp {

KinematicCalibration::KinematicCalibration(const JointErrorModel& prior, std::vector<MeasurementCampaign> fitted,
                                           const GeometricCalibrationOptions& options)
    : fitted_(std::move(fitted)) {
  if (fitted_.empty()) throw InvalidArgument("kinematic calibration: no fitted campaign");
  // Fitted campaigns from several tracker set-ups are fitted together, each set-up with its own frame.
  setup_of_campaign_ =
      fitted_.size() == 1 ? std::vector<int>{0} : instrumentSetUps(prior, fitted_, options).setup_of_campaign;
  whole_ = concatenateCampaigns(fitted_);
  setups_ = 1 + *std::max_element(setup_of_campaign_.begin(), setup_of_campaign_.end());
}

std::vector<std::string> KinematicCalibration::parameterNames(const Robot& robot) const {
  return geometricParameterNames(robot, setups_);
}

GeometricCalibrationResult KinematicCalibration::calibrate(const JointErrorModel& model,
                                                           const GeometricCalibrationOptions& options) const {
  return calibrateGeometry(model, fitted_, setup_of_campaign_, options);
}

CalibrationData KinematicCalibration::fittedRows(const JointErrorModel& model) const {
  CalibrationData data = prepareCalibrationData(model, whole_);
  assignCampaigns(data, fitted_, setup_of_campaign_);
  return data;
}

CalibrationData KinematicCalibration::rows(const JointErrorModel& model, const MeasurementCampaign& campaign) {
  return prepareCalibrationData(model, campaign);
}

Eigen::Vector3d KinematicCalibration::predict(const Robot& robot, const GeometricParameters& parameters,
                                              const CalibrationData& data, std::size_t row, Eigen::MatrixXd* jacobian) {
  return predictMeasurement(robot, parameters, data.command[row], data.load_torque[row], data.other_error[row],
                            jacobian, data.setup[row]);
}

HoldoutEvaluation KinematicCalibration::evaluate(const JointErrorModel& model, const GeometricParameters& parameters,
                                                 const MeasurementCampaign& campaign,
                                                 const GeometricCalibrationOptions& options) {
  return evaluateOnCampaign(model, parameters, campaign, true, options);
}

JointErrorModel KinematicCalibration::calibratedModel(const JointErrorModel& model,
                                                      const GeometricCalibrationResult& result,
                                                      std::vector<std::string>& left_out) {
  return calibratedJointErrorModel(model, std::make_shared<const Robot>(correctedRobot(model.robot(), result.estimate)),
                                   result, left_out);
}

CalibratedFrames calibratedFrames(const Robot& nominal, const MeasurementCampaign& first,
                                  const GeometricParameters& estimate) {
  CalibratedFrames frames;
  frames.tool = ToolTarget{nominal.tip_link, uniqueLinkName(nominal, nominal.tip_link + "_target"), estimate.target};
  if (first.frame == MeasurementFrame::Instrument) {
    frames.base_frame = BaseFrame{nominal.root_link,
                                  uniqueLinkName(nominal, nominal.root_link + "_measurement_frame", {frames.tool.link}),
                                  estimate.instrumentFromBase()};
  }
  return frames;
}

}  // namespace jointcomp
