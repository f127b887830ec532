#include "api_support.hpp"

#include <cmath>
#include <sstream>

#include "model/effects/registry.hpp"

jc_robot::jc_robot(std::shared_ptr<const jointcomp::Robot> loaded, jointcomp::JointErrorModel nominal,
                   std::vector<jointcomp::DriveParameters> drive_parameters)
    : robot(std::move(loaded)),
      model(std::move(nominal)),
      drives(std::move(drive_parameters)),
      workspace(*robot),
      inverse_kinematics(*robot) {}

namespace jointcomp::capi {
namespace {

// One message per thread, so that threads never read each other's errors.
thread_local std::string last_error;
thread_local jc_progress_callback progress_callback = nullptr;
thread_local void* progress_user_data = nullptr;

std::string describe(double value) {
  if (std::isnan(value)) return "NaN";
  return value > 0 ? "+infinity" : "-infinity";
}

}  // namespace

void invalid(const std::string& message) { throw ApiError(JC_ERROR_INVALID_ARGUMENT, message); }

void clearLastError() noexcept { last_error.clear(); }

Progress threadProgress() {
  if (!progress_callback) return {};
  const jc_progress_callback callback = progress_callback;
  void* user_data = progress_user_data;
  return [callback, user_data](const std::string& what) { callback(what.c_str(), user_data); };
}

jc_status fail(const char* function, jc_status status, const char* message) noexcept {
  try {
    last_error = std::string(function) + ": " + message;
  } catch (...) {
    // No memory for the message: the status still tells the kind of failure.
    last_error.clear();
  }
  return status;
}

void requirePointer(const void* pointer, const char* name) {
  if (!pointer) invalid(std::string(name) + " is NULL");
}

const char* requireText(const char* text, const char* name) {
  requirePointer(text, name);
  return text;
}

void requireLength(std::int64_t length, std::int64_t expected, const char* name, const char* meaning) {
  if (length != expected) {
    invalid(std::string(name) + "_len is " + std::to_string(length) + ", must be " + std::to_string(expected) + " (" +
            meaning + ")");
  }
}

void requireFinite(const double* values, std::int64_t count, const char* name) {
  for (std::int64_t i = 0; i < count; ++i) {
    if (!std::isfinite(values[i])) invalid(std::string(name) + "[" + std::to_string(i) + "] is " + describe(values[i]));
  }
}

JointVector jointInput(const double* values, std::int32_t length, int dof, const char* name) {
  requirePointer(values, name);
  requireLength(length, dof, name, "the robot's number of joints");
  requireFinite(values, length, name);
  return Eigen::Map<const Eigen::VectorXd>(values, dof);
}

JointVector optionalJointInput(const double* values, std::int32_t length, int dof, const char* name) {
  if (!values) {
    requireLength(length, 0, name, "NULL, so no values");
    return JointVector::Zero(dof);
  }
  return jointInput(values, length, dof, name);
}

Eigen::Vector3d vector3Input(const double* values, std::int32_t length, const char* name) {
  requirePointer(values, name);
  requireLength(length, 3, name, "x, y, z");
  requireFinite(values, 3, name);
  return Eigen::Vector3d(values[0], values[1], values[2]);
}

Vector6 vector6Input(const double* values, std::int32_t length, const char* name) {
  requirePointer(values, name);
  requireLength(length, 6, name, "force x, y, z, then moment x, y, z");
  requireFinite(values, 6, name);
  return Eigen::Map<const Vector6>(values);
}

double finiteScalar(double value, const char* name) {
  if (!std::isfinite(value)) invalid(std::string(name) + " is " + describe(value));
  return value;
}

void requireOutput(const double* values, std::int32_t length, std::int64_t expected, const char* name,
                   const char* meaning) {
  requirePointer(values, name);
  requireLength(length, expected, name, meaning);
}

bool optionalOutput(const void* values, std::int32_t length, std::int64_t expected, const char* name,
                    const char* meaning) {
  if (!values) {
    requireLength(length, 0, name, "NULL, so not wanted");
    return false;
  }
  requireLength(length, expected, name, meaning);
  return true;
}

void copyText(const std::string& text, char* buffer, std::int32_t capacity, std::int32_t* length) {
  requirePointer(length, "length");
  if (capacity < 0) invalid("capacity is negative");
  if (!buffer && capacity != 0) invalid("buffer is NULL but capacity is " + std::to_string(capacity));
  if (text.size() > static_cast<std::size_t>(INT32_MAX - 1)) invalid("the text is longer than an int32_t can say");
  const auto needed = static_cast<std::int32_t>(text.size());
  if (buffer) {
    if (capacity < needed + 1) {
      invalid("buffer holds " + std::to_string(capacity) + " bytes, the text needs " + std::to_string(needed + 1) +
              " with its NUL");
    }
    std::memcpy(buffer, text.c_str(), text.size() + 1);
  }
  *length = needed;
}

void copyJoints(const JointVector& values, double* out) {
  for (int i = 0; i < values.size(); ++i) out[i] = values[i];
}

Eigen::Isometry3d poseInput(const double* pose, std::int32_t length, const char* name) {
  requirePointer(pose, name);
  requireLength(length, 16, name, "a 4 x 4 transform, row-major");
  requireFinite(pose, 16, name);
  Eigen::Matrix4d matrix;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) matrix(r, c) = pose[4 * r + c];
  }
  if (matrix(3, 0) != 0.0 || matrix(3, 1) != 0.0 || matrix(3, 2) != 0.0 || matrix(3, 3) != 1.0) {
    invalid(std::string(name) + "'s last row is not 0 0 0 1");
  }
  const Eigen::Matrix3d rotation = matrix.topLeftCorner<3, 3>();
  // Loose enough for rotations written with a few digits, tight enough to catch a scaled or skewed matrix.
  const double skew = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (skew > 1e-6 || rotation.determinant() <= 0.0) {
    invalid(std::string(name) + "'s upper-left 3 x 3 block is not a rotation (max |R^T R - I| = " +
            std::to_string(skew) + ", det R = " + std::to_string(rotation.determinant()) + ")");
  }
  Eigen::Isometry3d result = Eigen::Isometry3d::Identity();
  result.linear() = rotation;
  result.translation() = matrix.topRightCorner<3, 1>();
  return result;
}

void copyPose(const Eigen::Isometry3d& pose, double* out) {
  const Eigen::Matrix4d& matrix = pose.matrix();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) out[4 * r + c] = matrix(r, c);
  }
}

EffectMask effectSelection(const JointErrorModel& model, const char* effects) {
  if (!effects) return model.allEffects();
  const std::vector<std::string> known = registeredEffectTypes();
  std::vector<std::string> wanted;
  std::stringstream list(effects);
  std::string item;
  while (std::getline(list, item, ',')) {
    const auto first = item.find_first_not_of(" \t");
    const auto last = item.find_last_not_of(" \t");
    item = first == std::string::npos ? std::string() : item.substr(first, last - first + 1);
    if (item.empty()) continue;
    bool registered = false;
    for (const std::string& type : known) registered = registered || type == item;
    if (!registered) {
      std::string names;
      for (const std::string& type : known) names += (names.empty() ? "" : ", ") + type;
      invalid("effects names '" + item + "', which is not an effect type (known: " + names + ")");
    }
    wanted.push_back(item);
  }
  EffectMask mask = 0;
  for (int i = 0; i < model.effectCount(); ++i) {
    bool selected = model.effect(i).role() == EffectRole::Load;
    for (const std::string& type : wanted) selected = selected || model.effect(i).type() == type;
    if (selected) mask |= EffectMask(1) << i;
  }
  return mask;
}

}  // namespace jointcomp::capi

extern "C" {

const char* jc_version(void) { return JOINTCOMP_VERSION_STRING; }

int32_t jc_abi_version(void) { return JC_ABI_VERSION; }

const char* jc_last_error(void) { return jointcomp::capi::last_error.c_str(); }

jc_status jc_set_progress_callback(jc_progress_callback callback, void* user_data) {
  jointcomp::capi::clearLastError();
  jointcomp::capi::progress_callback = callback;
  jointcomp::capi::progress_user_data = user_data;
  return JC_OK;
}

const char* jc_status_name(jc_status status) {
  switch (status) {
    case JC_OK: return "JC_OK";
    case JC_ERROR_INVALID_ARGUMENT: return "JC_ERROR_INVALID_ARGUMENT";
    case JC_ERROR_FILE: return "JC_ERROR_FILE";
    case JC_ERROR_UNREACHABLE: return "JC_ERROR_UNREACHABLE";
    case JC_ERROR_SOLVER: return "JC_ERROR_SOLVER";
    case JC_ERROR_WRONG_HANDLE: return "JC_ERROR_WRONG_HANDLE";
    case JC_ERROR_OUT_OF_MEMORY: return "JC_ERROR_OUT_OF_MEMORY";
    case JC_ERROR_INTERNAL: return "JC_ERROR_INTERNAL";
    case JC_ERROR_PLANT_LIMIT: return "JC_ERROR_PLANT_LIMIT";
    case JC_ERROR_BUSY: return "JC_ERROR_BUSY";
    default: return "JC_UNKNOWN_STATUS";
  }
}

}  // extern "C"
