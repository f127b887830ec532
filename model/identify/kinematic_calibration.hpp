// The kinematic calibration as residual discovery uses it, and no more: the fitted campaigns and their
// instrument set-ups, held once; a model calibrated on them; the rows as a model predicts them; one row's
// prediction with its Jacobian by every calibration parameter; a held-out campaign's evaluation; the
// calibrated model to write. The measurement model, the fit and its options are geometric_calibration.hpp's;
// discovery reaches them only through this class.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "model/identify/geometric_calibration.hpp"
#include "model/io/parameter_file.hpp"

namespace jointcomp {

class KinematicCalibration {
public:
  // The fitted campaigns' instrument set-ups are found on the prior (instrumentSetUps) when there are
  // several. Throws InvalidArgument for campaigns that cannot be calibrated together.
  KinematicCalibration(const JointErrorModel& prior, std::vector<MeasurementCampaign> fitted,
                       const GeometricCalibrationOptions& options);

  const std::vector<MeasurementCampaign>& fitted() const { return fitted_; }
  const MeasurementCampaign& whole() const { return whole_; }  // the fitted campaigns as one
  int setUps() const { return setups_; }
  // The calibration's parameters for a robot of `dof` joints: their layout and names.
  GeometricParameterLayout layout(int dof) const { return GeometricParameterLayout(dof, setups_); }
  std::vector<std::string> parameterNames(const Robot& robot) const;

  // `model` calibrated on the fitted campaigns (calibrateGeometry).
  GeometricCalibrationResult calibrate(const JointErrorModel& model, const GeometricCalibrationOptions& options) const;
  // The fitted rows as `model` predicts them (load torques, its other joint errors), each with its set-up.
  CalibrationData fittedRows(const JointErrorModel& model) const;
  // The rows of another campaign (a held-out one) as `model` predicts them.
  static CalibrationData rows(const JointErrorModel& model, const MeasurementCampaign& campaign);
  // Row `row`'s predicted reading under `parameters`, and its Jacobian by every parameter when asked.
  static Eigen::Vector3d predict(const Robot& robot, const GeometricParameters& parameters, const CalibrationData& data,
                                 std::size_t row, Eigen::MatrixXd* jacobian = nullptr);
  // A held-out campaign with the robot of `parameters`, its instrument frame re-fitted (evaluateOnCampaign).
  static HoldoutEvaluation evaluate(const JointErrorModel& model, const GeometricParameters& parameters,
                                    const MeasurementCampaign& campaign, const GeometricCalibrationOptions& options);
  // The model to write: the corrected robot, the fitted offsets and compliance (calibratedJointErrorModel).
  static JointErrorModel calibratedModel(const JointErrorModel& model, const GeometricCalibrationResult& result,
                                         std::vector<std::string>& left_out);
  // What the written files describe (asWritten): the model on the corrected robot, its load torques.
  static CalibratedView written(const JointErrorModel& model, const GeometricParameters& estimate) {
    return asWritten(model, estimate);
  }

private:
  std::vector<MeasurementCampaign> fitted_;
  std::vector<int> setup_of_campaign_;
  MeasurementCampaign whole_;
  int setups_ = 1;
};

// Where a calibration's written files put the fitted target and the instrument's frame: the tool point on
// the nominal robot's tip link, as the link "<tip>_target", and, for campaigns in an instrument's frame,
// the base's pose in the first set-up's frame as the link "<root>_measurement_frame" (none in the base
// frame). calibrate and discover write them into the URDF and parameter file; jc_calibrate's handle holds them.
struct CalibratedFrames {
  ToolTarget tool;
  std::optional<BaseFrame> base_frame;
};
CalibratedFrames calibratedFrames(const Robot& nominal, const MeasurementCampaign& first,
                                  const GeometricParameters& estimate);

}  // namespace jointcomp
