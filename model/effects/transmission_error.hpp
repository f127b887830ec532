// Transmission (kinematic) error of the gears: the link angle differs from motor angle / ratio by a
// periodic function of the angles of the rotating parts. Each harmonic is counted per revolution of a
// named part of one joint's gear train (the motor, the input of stage k, or the output):
//   dq_joint += amplitude * sin(cycles_per_revolution * angle_of_part + phase).
// The harmonic-drive signature of the paper is 2 cycles per input revolution of the second stage.
#pragma once

#include <cstddef>

#include "model/effects/discovery_family.hpp"
#include "model/effects/effect.hpp"
#include "model/effects/gear_train.hpp"
#include "model/robot/sin_cos_near.hpp"

namespace jointcomp {

// What a parameter file may hold of one transmission_error effect: a gear train has a few harmonics per
// joint, of orders up to its teeth counts. Beyond these the file is refused naming the entry.
constexpr std::size_t kMaxHarmonics = 1024;
constexpr double kMaxCyclesPerRevolution = 10000.0;

struct Harmonic {
  int joint = 0;
  int stage = 1;  // 1 = motor (input of stage 1), k = input of stage k, stageCount + 1 = output
  double cycles_per_revolution = 1.0;
  double amplitude_rad = 0.0;
  double phase_rad = 0.0;
};

class TransmissionErrorEffect : public Effect {
public:
  static constexpr const char* kType = "transmission_error";
  TransmissionErrorEffect(const Robot& robot, GearTrain gears, std::vector<Harmonic> harmonics);
  static std::unique_ptr<Effect> fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                          const std::string& path);

  std::string type() const override { return kType; }
  EffectRole role() const override { return EffectRole::JointError; }
  bool dependsOnCommand() const override { return true; }
  void addJointError(const Robot& robot, const JointContext& ctx, JointVector& dq) const override;
  bool addMotorSlope(const Robot& robot, const JointContext& ctx, JointVector& slope) const override;
  // Each harmonic's phase once, its sine and cosine together: the same bits as the two calls.
  bool addJointErrorAndMotorSlope(const Robot& robot, const JointContext& ctx, JointVector& dq,
                                  JointVector& slope) const override;
  void markCommandJoints(int dof, bool* joints) const override;  // the harmonics' joints
  // One anchor per harmonic, its angle the harmonic's phase (Effect's continuation).
  std::size_t continuationSize() const override { return harmonics_.size(); }
  bool continueJointErrorAndMotorSlope(const Robot& robot, const JointContext& ctx, SinCosAnchor* anchors, bool reuse,
                                       JointVector& dq, JointVector& slope) const override;
  // A harmonic's higher derivatives are its sine and cosine again, times powers of its phase rate.
  bool knowsMotorDerivatives() const override { return true; }
  void continueJointErrorAndMotorDerivatives(const Robot& robot, const JointContext& ctx, SinCosAnchor* anchors,
                                             bool reuse, JointVector& dq, JointVector& slope, JointVector& second,
                                             JointVector& third) const override;
  std::vector<std::string> parameterNames() const override;
  std::vector<double> parameters() const override;
  void setParameters(const std::vector<double>& values) override;
  nlohmann::json toJson() const override;
  std::unique_ptr<Effect> clone() const override { return std::make_unique<TransmissionErrorEffect>(*this); }

  const std::vector<Harmonic>& harmonics() const { return harmonics_; }
  // "motor", "stage_k" or "output" for a stage number of a joint.
  std::string partName(int joint, int stage) const;

private:
  std::vector<std::string> joint_names_;
  GearTrain gears_;
  std::vector<Harmonic> harmonics_;
  std::vector<double> phase_per_motor_;  // per harmonic: d(phase)/d(motor angle), cycles over the ratio before
};

// Discovery: "harmonic", per joint a sine and a cosine column, a sin(k x) + b cos(k x), x the angle of
// the motor, of each stage's input or of the output (distinct parts only), k = 1 .. max_harmonic_order;
// beyond that range, each stage's gear-mesh order (stage_input_teeth of the gear data) and the order a
// spectrum scan of the base fit's joint residual finds standing out (up to kMaxScannedHarmonicOrder), so
// that a high order is proposed rather than missed silently. A part's order at the frequency of an earlier
// part's order is the same column and is not offered twice. Written as the harmonics (amplitude, phase) of
// one transmission_error effect.
constexpr int kMaxScannedHarmonicOrder = 24;
class HarmonicDiscovery : public DiscoveryFamily {
public:
  std::string name() const override { return "harmonic"; }
  void offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const override;
  std::unique_ptr<Effect> makeEffect(const DiscoveryData& data,
                                     const std::vector<FittedCandidate>& accepted) const override;
  std::vector<NamedEstimate> describe(const FittedCandidate& fitted, const JointErrorModel& model) const override;
  // transmissionProblem: the amplitude sqrt(a^2 + b^2) within kMaxPlausibleJointError, the slope
  // amplitude * order * (part angle per joint angle) below kMaxTransmissionSlope.
  std::string physicalProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                              const Eigen::VectorXd& theta, const JointVector& compliance) const override;
};

}  // namespace jointcomp
