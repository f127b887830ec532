// What the per-joint effects share: one or more vectors of one value per joint, each a named parameter of
// every joint ("<joint>.<parameter>") and a key of the parameter file, read, checked and written alike. A
// type derived from it keeps only its physics (and its own extra keys, if any).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "model/common/json_fields.hpp"
#include "model/effects/effect.hpp"

namespace jointcomp {

class PerJointEffect : public Effect {
public:
  enum class Check {
    Finite,           // any finite value
    PositiveOrRigid,  // positive, +infinity for a rigid joint (null in the file)
    Positive,         // finite and positive
  };
  struct Field {
    std::string json_key;   // "width_rad"
    std::string parameter;  // "backlash_width_rad", named "<joint>.backlash_width_rad"
    Check check = Check::Finite;
    bool optional = false;  // may be left out of the file (zeros)
  };
  // A single number of the effect beside the per-joint vectors (a velocity scale, a reference temperature).
  struct Scalar {
    std::string json_key;   // "velocity_scale_rad_per_s"
    double fallback = 0.0;  // when the file leaves it out
    Check check = Check::Finite;
  };

  // Field by field, joint by joint.
  std::vector<std::string> parameterNames() const override;
  std::vector<double> parameters() const override;
  // Throws ParameterError naming the parameter; a rejected update leaves the effect as it was.
  void setParameters(const std::vector<double>& values) override;
  nlohmann::json toJson() const override;

protected:
  PerJointEffect(const Robot& robot, std::vector<Field> fields, std::vector<Scalar> scalars = {});
  // Every field of a parameter file's object, in the order of setParameters, and its scalars, in their
  // order (the caller reads its own keys, if any, and then calls rejectUnknownKeys).
  static std::vector<double> readFields(JsonFields& fields, const std::vector<Field>& layout, int dof);
  static std::vector<double> readScalars(JsonFields& fields, const std::vector<Scalar>& layout);
  // Throws ParameterError naming the scalar (derived constructors call it: type() is theirs).
  void setScalars(const std::vector<double>& values);
  double scalar(std::size_t k) const { return scalar_values_[k]; }
  // No scalars: the default for a type that declares none.
  static const std::vector<Scalar>& scalarLayout() {
    static const std::vector<Scalar> none;
    return none;
  }
  // A per-joint effect of type T from its parameter-file object: T's fields and scalars (T::layout(),
  // T::scalarLayout()), its estimate note, nothing else; then T::fromValues(robot, values, scalars).
  template <typename T>
  static std::unique_ptr<Effect> readAs(const nlohmann::json& json, const Robot& robot, const std::string& path) {
    JsonFields fields(json, path);
    fields.text("type");
    const std::vector<double> values = readFields(fields, T::layout(), robot.dof());
    const std::vector<double> scalars = readScalars(fields, T::scalarLayout());
    const std::string note = fields.textOr("estimate", "");
    fields.rejectUnknownKeys();
    std::unique_ptr<Effect> effect = T::fromValues(robot, values, scalars);
    effect->estimate_note = note;
    return effect;
  }
  // Joins per-field vectors into the order of setParameters.
  static std::vector<double> joined(std::initializer_list<const std::vector<double>*> vectors);

  const std::vector<double>& field(std::size_t k) const { return values_[k]; }
  std::size_t jointCount() const { return joint_names_.size(); }
  // Called after every accepted setParameters (e.g. to cache 1 / stiffness).
  virtual void parametersChanged() {}

private:
  std::vector<std::string> joint_names_;
  std::vector<Field> fields_;
  std::vector<std::vector<double>> values_;
  std::vector<Scalar> scalars_;
  std::vector<double> scalar_values_;
};

}  // namespace jointcomp
