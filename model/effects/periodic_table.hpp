// A joint error of any periodic shape: per table, a smooth periodic function of the angle of one part of a
// joint's gear train (the motor, the input of stage k, or the output), written as a uniform periodic cubic
// B-spline with `knots` coefficients over one revolution of that part:
//   dq_joint += sum_i c_i B((angle / (2 pi)) * knots - i),
// B the cubic B-spline (C2, so the plant can differentiate it; the B_i sum to one). Where the harmonics of
// transmission_error need one pair of terms per order, a table takes a tooth-shaped, flat-topped or
// stepped error with a few dozen coefficients, and its spectrum (spectrum()) tells which orders repeat.
// Discovery offers tables of the knot counts DiscoveryData::table_knots (16 to 128 by default); knots whose
// support the fitted rows never visited stay at zero, and the candidate reports which angle ranges the
// table covers.
#pragma once

#include <utility>
#include <vector>

#include "model/effects/discovery_family.hpp"
#include "model/effects/effect.hpp"
#include "model/effects/gear_train.hpp"

namespace jointcomp {

struct PeriodicTable {
  int joint = 0;
  int stage = 1;  // 1 = motor, k = input of stage k, stageCount + 1 = output (as Harmonic::stage)
  std::vector<double> coefficients_rad;
};

// The uniform periodic cubic B-spline with `knots` coefficients at `angle` (rad, one period = 2 pi):
// the four weights of coefficients first, first + 1, first + 2, first + 3 (indices modulo knots), and
// their derivatives with respect to the angle.
struct PeriodicSplineWeights {
  int first = 0;
  double weight[4] = {0, 0, 0, 0};
  double slope[4] = {0, 0, 0, 0};  // d weight / d angle, 1/rad
};
PeriodicSplineWeights periodicSplineWeights(int knots, double angle);

// Amplitude of each order 1 .. max_order (cycles per revolution of the part) of a table's function,
// from 16 samples per knot and order.
std::vector<double> periodicTableSpectrum(const std::vector<double>& coefficients, int max_order);

class PeriodicTableEffect : public Effect {
public:
  static constexpr const char* kType = "periodic_table";
  static constexpr int kMinKnots = 4;
  static constexpr int kMaxKnots = 720;
  PeriodicTableEffect(const Robot& robot, GearTrain gears, std::vector<PeriodicTable> tables);
  static std::unique_ptr<Effect> fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                          const std::string& path);

  std::string type() const override { return kType; }
  EffectRole role() const override { return EffectRole::JointError; }
  bool dependsOnCommand() const override { return true; }
  void addJointError(const Robot& robot, const JointContext& ctx, JointVector& dq) const override;
  bool addMotorSlope(const Robot& robot, const JointContext& ctx, JointVector& slope) const override;
  // Each table's spline weights once for both (the same bits as the two calls).
  bool addJointErrorAndMotorSlope(const Robot& robot, const JointContext& ctx, JointVector& dq,
                                  JointVector& slope) const override;
  void markCommandJoints(int dof, bool* joints) const override;  // the tables' joints
  std::vector<std::string> parameterNames() const override;
  std::vector<double> parameters() const override;
  void setParameters(const std::vector<double>& values) override;
  nlohmann::json toJson() const override;
  std::unique_ptr<Effect> clone() const override { return std::make_unique<PeriodicTableEffect>(*this); }

  const std::vector<PeriodicTable>& tables() const { return tables_; }
  // The joint error of table `t` at its part's angle (rad).
  double valueAt(std::size_t t, double angle) const;

private:
  std::vector<std::string> joint_names_;
  GearTrain gears_;
  std::vector<PeriodicTable> tables_;
};

// The knots of a table of `knots` for (joint, stage) that the fitted rows support (a weight of at least 2),
// but for the most supported one (the B-splines sum to one: all of them would repeat the joint's offset):
// the coefficients of a "periodic" candidate, in this order.
std::vector<int> fittedTableKnots(const DiscoveryData& data, int joint, int stage, int knots);

// Discovery: "periodic", per joint and distinct part, a table of each knot count of
// DiscoveryData::table_knots (one column per knot the fitted rows visit), with a roughness prior (discovery
// adds a ridge toward zero). Cross-validation picks the count and the priors' weights, and against the
// harmonics.
class PeriodicTableDiscovery : public DiscoveryFamily {
public:
  std::string name() const override { return "periodic"; }
  void offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const override;
  std::unique_ptr<Effect> makeEffect(const DiscoveryData& data,
                                     const std::vector<FittedCandidate>& accepted) const override;
  std::vector<NamedEstimate> describe(const FittedCandidate& fitted, const JointErrorModel& model) const override;
  // transmissionProblem: the table's largest |value| over the fitted rows within kMaxPlausibleJointError,
  // its steepest slope over the period (the unvisited knots at zero, 32 samples per knot) times the part
  // angle per joint angle below kMaxTransmissionSlope.
  std::string physicalProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                              const Eigen::VectorXd& theta, const JointVector& compliance) const override;
};

}  // namespace jointcomp
