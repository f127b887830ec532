// What residual discovery needs of an effect type, said by the type itself: the candidate columns it
// offers for the fitted data (per joint, per stage and order where that applies), and how fitted
// coefficients become the effect, with named parameters and uncertainties. Discovery (model/identify)
// fits the columns and iterates over the registry's families; it never asks for a type by name.
//
// A candidate either brings feature columns, the joint error of its joint per unit coefficient (so the
// predicted measurement moves by dm/dq_j times the column), or, for a load (through_compliance), blocks of
// one column per joint: the load torque of every joint per unit coefficient, which moves the joints
// through their current compliances, or (joint_error_blocks) the joint error of every joint per unit
// coefficient. It may also free parameters that the kinematic calibration owns
// (a joint's offset, compliance or placement), alone or beside its columns.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "model/effects/effect.hpp"
#include "model/effects/gear_train.hpp"

namespace jointcomp {

class JointErrorModel;

// The fitted rows as discovery offers them to the families (row i of every vector is one used campaign row).
struct DiscoveryData {
  const Robot* robot = nullptr;
  const GearTrain* gears = nullptr;
  std::vector<JointVector> command;      // rad
  std::vector<JointVector> motor;        // rad, through the gear train
  std::vector<JointVector> approach;     // side of each joint's lost motion (+1, -1; 0 not known yet)
  std::vector<JointVector> load_torque;  // N m, what each joint's transmission carries
  std::vector<double> time;              // s
  std::vector<double> temperature;       // degC; NaN where not measured
  bool torque_known = false;             // the robot has inertials
  bool have_temperature = false;         // every row has a temperature
  double time0 = 0.0;                    // s, the campaign's start (the reference of time drift)
  double temperature0 = 20.0;            // degC, the rows' mean temperature (the reference of thermal drift)
  double velocity_scale = 1e-3;          // rad/s, smooth sign of lost motion
  int max_harmonic_order = 4;
  std::vector<int> table_knots = {16, 32, 64, 128};  // knots per revolution of the periodic tables offered
  // The base fit's residual mapped to the joints (per joint, per row, rad), for families that scan it for
  // what their fixed candidates miss (harmonic orders beyond max_harmonic_order); empty when not known.
  std::vector<std::vector<double>> joint_residual;
  int rows() const { return static_cast<int>(command.size()); }
};

struct DiscoveryCandidate {
  std::string type;     // the family's name in the vocabulary
  int joint = -1;       // -1: the whole robot
  int stage = 0;        // gear part: 1 = motor ... stageCount + 1 = output (harmonics)
  std::string part;     // "motor", "stage_k", "output"; or the variant ("temperature", "time")
  double cycles = 0.0;  // harmonic order (cycles per revolution of the part)
  std::string detail;   // appended to the label, e.g. " motor order 2"
  // What the report says of the step beside its type and joint, e.g. {"part", "stage", "order"} of a
  // harmonic: the family says it, so the report never asks for a type by name.
  nlohmann::ordered_json report_fields = nlohmann::ordered_json::object();
  std::vector<CalibrationParameter> releases;
  // rows x coefficients; through_compliance: rows x (coefficients * dof), block k holding the load torque
  // of every joint per unit of coefficient k; joint_error_blocks: the same layout, block k holding the
  // joint error of every joint per unit of coefficient k (an effect that moves several joints at once).
  Eigen::MatrixXd columns;
  bool through_compliance = false;
  bool joint_error_blocks = false;
  // A quadratic prior on the coefficients, coefficients x coefficients (SI units; empty: none), e.g. a
  // table's roughness. Discovery weighs it by a factor it chooses by cross-validation on the fitted data.
  Eigen::MatrixXd prior;

  int coefficients(int dof) const {
    return through_compliance || joint_error_blocks ? static_cast<int>(columns.cols()) / dof
                                                    : static_cast<int>(columns.cols());
  }
  std::string label() const;  // "backlash joint 3", "harmonic joint 2 motor order 1", "payload (tool)"
};

// An accepted candidate with its fitted coefficients and their standard deviations (SI units).
struct FittedCandidate {
  const DiscoveryCandidate* candidate = nullptr;
  Eigen::VectorXd theta;
  Eigen::VectorXd sigma;
};

struct NamedEstimate {
  std::string name;  // e.g. "shoulder_lift_joint.backlash_width_rad"
  double value = 0.0;
  double sigma = 0.0;
};

class DiscoveryFamily {
public:
  virtual ~DiscoveryFamily() = default;
  // The name in the discovery vocabulary (--types), e.g. "harmonic" for transmission-error harmonics.
  virtual std::string name() const = 0;
  // Appends this family's candidates for `joint` (0 .. dof-1), or for the whole robot (joint -1): every
  // family is asked for each joint in turn, then once for the robot.
  virtual void offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const = 0;
  // The effect that all accepted candidates of this family make together (in acceptance order), or
  // nullptr when the family only frees calibration parameters.
  virtual std::unique_ptr<Effect> makeEffect(const DiscoveryData& data,
                                             const std::vector<FittedCandidate>& accepted) const;
  // Named estimates of one accepted candidate's coefficients; `model` holds the effect makeEffect built.
  // The calibration parameters it freed are reported by discovery itself.
  virtual std::vector<NamedEstimate> describe(const FittedCandidate& fitted, const JointErrorModel& model) const;
  // Empty when `theta` (the candidate's coefficients, SI) make a physical effect over the fitted rows (their
  // torques, angles, times), given each joint's linear compliance `compliance` (rad/(N m)); else why not.
  // Discovery refuses a candidate whose fit is not physical, however well it fits. By default the bound every
  // joint-error family shares (jointErrorBeyondThePlausible); a family with constraints of its own (a sign,
  // a monotone curve) states them in its override.
  virtual std::string physicalProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                                      const Eigen::VectorXd& theta, const JointVector& compliance) const;
};

// A family that only frees one of the calibration's own parameters of each joint (offset, compliance,
// placement): no columns, no effect of its own.
class CalibrationParameterDiscovery : public DiscoveryFamily {
public:
  std::string name() const override { return name_; }
  void offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const override;

protected:
  CalibrationParameterDiscovery(std::string name, CalibrationParameter parameter, bool needs_torque)
      : name_(std::move(name)), parameter_(parameter), needs_torque_(needs_torque) {}

private:
  std::string name_;
  CalibrationParameter parameter_;
  bool needs_torque_;  // offered only when the load torque is known
};

// "instrument_scale": one robot-wide candidate that frees the instrument's relative scale error, so that a
// tracker that measures 1.0002 m for a metre is named as such rather than spread over joint placements.
class InstrumentScaleDiscovery : public DiscoveryFamily {
public:
  std::string name() const override { return "instrument_scale"; }
  void offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const override;
};

// A family of one feature column per joint whose coefficients are the effect's one per-joint vector
// (named "<joint>.<parameter>"): the derived type gives the column and makes the effect.
class PerJointFeatureDiscovery : public DiscoveryFamily {
public:
  std::string name() const override { return name_; }
  void offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const override;
  std::unique_ptr<Effect> makeEffect(const DiscoveryData& data,
                                     const std::vector<FittedCandidate>& accepted) const override;
  std::vector<NamedEstimate> describe(const FittedCandidate& fitted, const JointErrorModel& model) const override;

protected:
  PerJointFeatureDiscovery(std::string name, std::string parameter, bool needs_torque)
      : name_(std::move(name)), parameter_(std::move(parameter)), needs_torque_(needs_torque) {}
  // The column of `joint` at fitted row `row`: the joint error per unit coefficient.
  virtual double feature(const DiscoveryData& data, int row, int joint) const = 0;
  virtual std::unique_ptr<Effect> effectOf(const DiscoveryData& data, const std::vector<double>& per_joint) const = 0;

private:
  std::string name_;
  std::string parameter_;
  bool needs_torque_;
};

// One feature column of `joint`'s candidate from a function of the row.
template <typename Feature>
Eigen::MatrixXd featureColumn(const DiscoveryData& data, Feature feature) {
  Eigen::MatrixXd column(data.rows(), 1);
  for (int i = 0; i < data.rows(); ++i) column(i, 0) = feature(i);
  return column;
}

// The joint's name, for "<joint>.<parameter>" names.
const std::string& jointNameOf(const DiscoveryData& data, int joint);

// The physical bound every joint-error family shares: no effect may turn a joint by more than this over
// the fitted rows (0.57 deg; a robot deflecting or losing that much would not hold a path to a millimetre).
constexpr double kMaxPlausibleJointError = 0.01;  // rad
// The largest |load torque| of `joint` over the fitted rows (N m).
double largestTorque(const DiscoveryData& data, int joint);

// The largest joint error (rad) a candidate's columns make at `theta` over the fitted rows, with the joint
// and the row where: plain columns move the candidate's own joint, joint-error blocks every joint, load-torque
// blocks every joint through its compliance. NaN when any is not finite; 0 for a candidate without columns
// (one that only frees calibration parameters).
struct LargestJointError {
  double value = 0.0;  // rad
  int joint = -1;
  int row = -1;
};
LargestJointError largestJointError(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                                    const Eigen::VectorXd& theta, const JointVector& compliance);
// Empty when the candidate turns no joint by more than kMaxPlausibleJointError over the fitted rows; else
// why not, naming the effect, the joint, the row and the turn.
std::string jointErrorBeyondThePlausible(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                                         const Eigen::VectorXd& theta, const JointVector& compliance);

// The constraint of a transmission error (harmonics, periodic tables) of a part of a joint's gear train:
// it turns the joint by at most kMaxPlausibleJointError over the fitted rows, and the link turns with the
// motor, never against it: |d(error)/d(joint angle)| = |slope per part angle| * |part angle per joint
// angle| stays below kMaxTransmissionSlope (at 1 the link would stand while the motor turns). Empty when
// physical; else why not, naming the joint and the part.
constexpr double kMaxTransmissionSlope = 1.0;
std::string transmissionProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate, double largest_error,
                                double largest_part_slope);
// The part's angle per joint angle (the gear ratios up to part `stage` of `joint`).
double partAnglePerJointAngle(const DiscoveryData& data, int joint, int stage);

}  // namespace jointcomp
