#include "model/effects/joint_offset.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"

namespace jointcomp {

const std::vector<PerJointEffect::Field>& JointOffsetEffect::layout() {
  static const std::vector<Field> fields = {{"offset_rad", "offset_rad"}};
  return fields;
}

JointOffsetEffect::JointOffsetEffect(const Robot& robot, const std::vector<double>& offsets_rad)
    : PerJointEffect(robot, layout()) {
  setParameters(offsets_rad);
}

std::unique_ptr<Effect> JointOffsetEffect::fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain&,
                                                    const std::string& path) {
  return readAs<JointOffsetEffect>(json, robot, path);
}

std::unique_ptr<Effect> JointOffsetEffect::fromValues(const Robot& robot, const std::vector<double>& values,
                                                      const std::vector<double>&) {
  return std::make_unique<JointOffsetEffect>(robot, values);
}

void JointOffsetEffect::addJointError(const Robot&, const JointContext&, JointVector& dq) const {
  const std::vector<double>& offsets = field(0);
  for (std::size_t i = 0; i < offsets.size(); ++i) dq[static_cast<int>(i)] += offsets[i];
}

}  // namespace jointcomp
