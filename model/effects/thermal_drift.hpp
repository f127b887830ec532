// Thermal and time drift of the joint zeros: dq_j = a_j * (temperature - T0) + d_j * (time - t0), with
// a_j in rad/degC and d_j in rad/s. A context without a measured temperature carries the default 20 degC
// (JointContext), so a model whose T0 is not 20 degC should only be used with temperatures. Parameter file:
//   {"type": "thermal", "coefficient_rad_per_degc": [n], "reference_temperature_degc": T0,
//    "drift_rad_per_s": [n], "reference_time_s": t0}
#pragma once

#include "model/effects/discovery_family.hpp"
#include "model/effects/effect.hpp"
#include "model/effects/gear_train.hpp"
#include "model/effects/per_joint_effect.hpp"

namespace jointcomp {

class ThermalDriftEffect : public PerJointEffect {
public:
  static constexpr const char* kType = "thermal";
  // Throws ParameterError for wrong sizes or values that are not finite.
  ThermalDriftEffect(const Robot& robot, const std::vector<double>& coefficient_rad_per_degc,
                     double reference_temperature_degc, const std::vector<double>& drift_rad_per_s,
                     double reference_time_s);
  static std::unique_ptr<Effect> fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                          const std::string& path);

  // The file format: the fields (and scalars) the parameter file holds.
  static const std::vector<Field>& layout();
  static const std::vector<Scalar>& scalarLayout();  // reference_temperature_degc, reference_time_s
  static std::unique_ptr<Effect> fromValues(const Robot& robot, const std::vector<double>& values,
                                            const std::vector<double>& scalars);

  std::string type() const override { return kType; }
  EffectRole role() const override { return EffectRole::JointError; }
  void addJointError(const Robot& robot, const JointContext& ctx, JointVector& dq) const override;
  std::unique_ptr<Effect> clone() const override { return std::make_unique<ThermalDriftEffect>(*this); }

  double referenceTemperature() const { return scalar(0); }
  double referenceTime() const { return scalar(1); }
};

// Discovery: "thermal", per joint a temperature drift (when every row has a temperature) and a time
// drift, each with the joint's offset: a drift is known up to the zero it drifts from, and the reference
// temperature or time of the column is only the rows' mean or the campaign's start, so the two variants
// compete on the shape of the drift alone.
class ThermalDriftDiscovery : public DiscoveryFamily {
public:
  std::string name() const override { return "thermal"; }
  void offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const override;
  std::unique_ptr<Effect> makeEffect(const DiscoveryData& data,
                                     const std::vector<FittedCandidate>& accepted) const override;
  std::vector<NamedEstimate> describe(const FittedCandidate& fitted, const JointErrorModel& model) const override;
};

}  // namespace jointcomp
