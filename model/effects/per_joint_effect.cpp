#include "model/effects/per_joint_effect.hpp"

#include <cmath>
#include <limits>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"

namespace jointcomp {

PerJointEffect::PerJointEffect(const Robot& robot, std::vector<Field> fields, std::vector<Scalar> scalars)
    : fields_(std::move(fields)), scalars_(std::move(scalars)) {
  for (const Joint& joint : robot.joints) joint_names_.push_back(joint.name);
  values_.assign(fields_.size(), std::vector<double>(joint_names_.size(), 0.0));
  for (const Scalar& s : scalars_) scalar_values_.push_back(s.fallback);
}

void PerJointEffect::setScalars(const std::vector<double>& values) {
  if (values.size() != scalars_.size())
    throw ParameterError(type() + ": expected " + std::to_string(scalars_.size()) + " scalars");
  for (std::size_t k = 0; k < values.size(); ++k) {
    const std::string& key = scalars_[k].json_key;
    if (!std::isfinite(values[k])) throw ParameterError(type() + ": " + key + " must be finite");
    if (scalars_[k].check != Check::Finite && !(values[k] > 0.0)) {
      throw ParameterError(type() + ": " + key + " must be finite and positive");
    }
  }
  scalar_values_ = values;
}

std::vector<double> PerJointEffect::readScalars(JsonFields& fields, const std::vector<Scalar>& layout) {
  std::vector<double> values;
  for (const Scalar& s : layout) {
    values.push_back(fields.numberOr(s.json_key, s.fallback));
    if (s.check != Check::Finite && !(values.back() > 0.0)) fields.fail(s.json_key, "must be positive");
  }
  return values;
}

std::vector<std::string> PerJointEffect::parameterNames() const {
  std::vector<std::string> names;
  for (const Field& f : fields_) {
    for (const std::string& joint : joint_names_) names.push_back(joint + "." + f.parameter);
  }
  return names;
}

std::vector<double> PerJointEffect::parameters() const {
  std::vector<double> all;
  for (const auto& v : values_) all.insert(all.end(), v.begin(), v.end());
  return all;
}

void PerJointEffect::setParameters(const std::vector<double>& values) {
  const std::size_t n = joint_names_.size();
  if (values.size() != fields_.size() * n) {
    throw ParameterError(type() + ": expected " + std::to_string(fields_.size() * n) + " parameters (" +
                         fields_.front().parameter + (fields_.size() > 1 ? ", ..." : "") + " of " + std::to_string(n) +
                         " joints), found " + std::to_string(values.size()));
  }
  // Check everything before changing anything.
  for (std::size_t f = 0; f < fields_.size(); ++f) {
    for (std::size_t j = 0; j < n; ++j) {
      const double value = values[f * n + j];
      const std::string name = type() + ": " + joint_names_[j] + "." + fields_[f].parameter;
      if (fields_[f].check != Check::PositiveOrRigid && !std::isfinite(value))
        throw ParameterError(name + " must be finite");
      if (fields_[f].check == Check::Positive && !(value > 0.0)) throw ParameterError(name + " must be positive");
      if (fields_[f].check == Check::PositiveOrRigid && (std::isnan(value) || !(value > 0.0))) {
        throw ParameterError(name + " must be positive (+infinity for a rigid joint)");
      }
    }
  }
  for (std::size_t f = 0; f < fields_.size(); ++f) {
    values_[f].assign(values.begin() + static_cast<long>(f * n), values.begin() + static_cast<long>((f + 1) * n));
  }
  parametersChanged();
}

nlohmann::json PerJointEffect::toJson() const {
  nlohmann::json json = {{"type", type()}};
  for (std::size_t f = 0; f < fields_.size(); ++f) {
    nlohmann::json list = nlohmann::json::array();
    for (double v : values_[f]) list.push_back(std::isinf(v) ? nlohmann::json(nullptr) : nlohmann::json(v));
    json[fields_[f].json_key] = list;
  }
  for (std::size_t k = 0; k < scalars_.size(); ++k) json[scalars_[k].json_key] = scalar_values_[k];
  if (!estimate_note.empty()) json["estimate"] = estimate_note;
  return json;
}

std::vector<double> PerJointEffect::readFields(JsonFields& fields, const std::vector<Field>& layout, int dof) {
  std::vector<double> all;
  for (const Field& f : layout) {
    if (f.optional && !fields.has(f.json_key)) {
      all.insert(all.end(), static_cast<std::size_t>(dof), 0.0);
      continue;
    }
    if (f.check != Check::PositiveOrRigid) {
      const std::vector<double> values = fields.numbers(f.json_key, dof);
      all.insert(all.end(), values.begin(), values.end());
      continue;
    }
    // null marks a joint taken as rigid (no compliance known or identifiable).
    const nlohmann::json& list = fields.array(f.json_key);
    if (static_cast<int>(list.size()) != dof) {
      fields.fail(f.json_key, "expected " + std::to_string(dof) + " values, found " + std::to_string(list.size()));
    }
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string element = f.json_key + "[" + std::to_string(i) + "]";
      if (list[i].is_null()) {
        all.push_back(std::numeric_limits<double>::infinity());
        continue;
      }
      if (!list[i].is_number()) fields.fail(element, "expected a number or null (rigid)");
      const double value = list[i].get<double>();
      if (!std::isfinite(value)) fields.fail(element, "not finite");
      if (!(value > 0.0)) fields.fail(element, "must be positive");
      all.push_back(value);
    }
  }
  return all;
}

std::vector<double> PerJointEffect::joined(std::initializer_list<const std::vector<double>*> vectors) {
  std::vector<double> all;
  for (const std::vector<double>* v : vectors) all.insert(all.end(), v->begin(), v->end());
  return all;
}

}  // namespace jointcomp
