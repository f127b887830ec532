// What every entry point of the C API shares: the handle types, the argument checks, and the one place
// where exceptions become status codes (so that none crosses the C boundary).
#pragma once

#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "handle_registry.hpp"
#include "jointcomp/jointcomp.h"
#include "model/common/errors.hpp"
#include "model/common/progress.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/io/parameter_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"
#include "model/robot/drive_parameters.hpp"
#include "model/robot/inverse_kinematics.hpp"

// Handles are looked up in the table of live handles (handle_registry.hpp) before they are trusted, and are
// busy while a call uses them.
struct jc_robot : jointcomp::capi::HandleHeader {
  static constexpr jointcomp::capi::HandleKind kKind = jointcomp::capi::HandleKind::Robot;
  jc_robot(std::shared_ptr<const jointcomp::Robot> loaded, jointcomp::JointErrorModel nominal,
           std::vector<jointcomp::DriveParameters> drive_parameters);

  std::mutex mutex;  // serialises calls on this handle
  const std::shared_ptr<const jointcomp::Robot> robot;
  const jointcomp::JointErrorModel model;
  const std::vector<jointcomp::DriveParameters> drives;  // empty when the parameters have no "plant"
  // Scratch of the calls, reused under the lock so that the calls allocate little.
  jointcomp::JointErrorWorkspace workspace;
  jointcomp::InverseKinematics inverse_kinematics;
  // Conditions set by jc_robot_set_payload / jc_robot_set_tool_wrench.
  double payload_mass = 0.0;
  Eigen::Vector3d payload_com = Eigen::Vector3d::Zero();
  jointcomp::Vector6 tool_wrench = jointcomp::Vector6::Zero();
  // Where a calibration put the target and the instrument's frame (jc_calibrate, jc_discover, or a parameter
  // file's "tool" and "base_frame"); set before the handle is handed out, then never changed.
  std::optional<jointcomp::ToolTarget> tool;
  std::optional<jointcomp::BaseFrame> base_frame;
};

struct jc_plant : jointcomp::capi::HandleHeader {
  static constexpr jointcomp::capi::HandleKind kKind = jointcomp::capi::HandleKind::Plant;
  explicit jc_plant(std::unique_ptr<jointcomp::FlexibleJointPlant> created) : plant(std::move(created)) {}

  std::mutex mutex;
  const std::unique_ptr<jointcomp::FlexibleJointPlant> plant;
};

struct jc_report : jointcomp::capi::HandleHeader {
  static constexpr jointcomp::capi::HandleKind kKind = jointcomp::capi::HandleKind::Report;
  jc_report(std::string json_text, std::string summary_text)
      : json(std::move(json_text)), summary(std::move(summary_text)) {}

  const std::string json;  // immutable once made: no lock needed
  const std::string summary;
};

namespace jointcomp::capi {

// An error found by the C API's own checks, with its status.
class ApiError : public std::runtime_error {
public:
  ApiError(jc_status status, const std::string& message) : std::runtime_error(message), status_(status) {}
  jc_status status() const { return status_; }

private:
  jc_status status_;
};

[[noreturn]] void invalid(const std::string& message);

void clearLastError() noexcept;
// The progress callback this thread set with jc_set_progress_callback, as a Progress (empty: none).
Progress threadProgress();
jc_status fail(const char* function, jc_status status, const char* message) noexcept;

// Runs `body`, turning every exception into a status and the thread's last-error message, which names
// `function`. Entry points use CAPI_ENTRY({ ... }) so that the name is the entry point's own.
template <class Body>
jc_status guarded(const char* function, Body&& body) noexcept {
  clearLastError();
  const EntryScope scope;  // releases the handles the call marked busy
  try {
    body();
    return JC_OK;
  } catch (const ApiError& error) {
    return fail(function, error.status(), error.what());
  } catch (const InvalidArgument& error) {
    return fail(function, JC_ERROR_INVALID_ARGUMENT, error.what());
  } catch (const UrdfError& error) {
    return fail(function, JC_ERROR_FILE, error.what());
  } catch (const ParameterError& error) {
    return fail(function, JC_ERROR_FILE, error.what());
  } catch (const MeasurementError& error) {
    return fail(function, JC_ERROR_FILE, error.what());
  } catch (const UnreachableError& error) {
    return fail(function, JC_ERROR_UNREACHABLE, error.what());
  } catch (const SolverError& error) {
    return fail(function, JC_ERROR_SOLVER, error.what());
  } catch (const PlantLimitError& error) {
    return fail(function, JC_ERROR_PLANT_LIMIT, error.what());
  } catch (const Error& error) {  // the untyped ones: a file that cannot be read or written
    return fail(function, JC_ERROR_FILE, error.what());
  } catch (const std::bad_alloc&) {
    return fail(function, JC_ERROR_OUT_OF_MEMORY, "out of memory");
  } catch (const std::exception& error) {
    return fail(function, JC_ERROR_INTERNAL, error.what());
  } catch (...) {
    return fail(function, JC_ERROR_INTERNAL, "unknown exception");
  }
}

#define CAPI_ENTRY(...) ::jointcomp::capi::guarded(__func__, [&]() __VA_ARGS__)

// The handle behind a pointer, after checking that it is a live one of the expected kind; it stays busy
// (cannot be freed) until the entry point returns. `name`: the parameter's name in the header.
template <class Handle>
Handle& useHandle(Handle* handle, const char* name) {
  acquireHandle(handle, Handle::kKind, name);
  return *handle;
}
inline jc_robot& robotHandle(jc_robot* robot, const char* name = "robot") { return useHandle(robot, name); }
inline jc_plant& plantHandle(jc_plant* plant) { return useHandle(plant, "plant"); }
inline jc_report& reportHandle(jc_report* report) { return useHandle(report, "report"); }
// Frees a handle no call is using (NULL: nothing); JC_ERROR_BUSY while one is.
template <class Handle>
void freeHandle(Handle* handle, const char* name) {
  if (!handle) return;
  retireHandle(handle, Handle::kKind, name);
  delete handle;
}

// Argument checks; `name` is the parameter's name in the header.
void requirePointer(const void* pointer, const char* name);
const char* requireText(const char* text, const char* name);
// Length of an array that must hold exactly `expected` values.
void requireLength(std::int64_t length, std::int64_t expected, const char* name, const char* meaning);
// Input arrays: non-NULL, of exactly `expected` values, all finite.
void requireFinite(const double* values, std::int64_t count, const char* name);
JointVector jointInput(const double* values, std::int32_t length, int dof, const char* name);
// An optional input: zeros when NULL (its length must then be 0).
JointVector optionalJointInput(const double* values, std::int32_t length, int dof, const char* name);
Eigen::Vector3d vector3Input(const double* values, std::int32_t length, const char* name);
Vector6 vector6Input(const double* values, std::int32_t length, const char* name);
double finiteScalar(double value, const char* name);
// Output arrays: non-NULL (unless optional and then of length 0) and of exactly `expected` values.
void requireOutput(const double* values, std::int32_t length, std::int64_t expected, const char* name,
                   const char* meaning);
bool optionalOutput(const void* values, std::int32_t length, std::int64_t expected, const char* name,
                    const char* meaning);

// Copies a string into a caller's buffer (see jc_robot_name).
void copyText(const std::string& text, char* buffer, std::int32_t capacity, std::int32_t* length);

void copyJoints(const JointVector& values, double* out);

// Poses cross the API as 4 x 4 row-major homogeneous transforms.
Eigen::Isometry3d poseInput(const double* pose, std::int32_t length, const char* name);
void copyPose(const Eigen::Isometry3d& pose, double* out);

// The effect mask of an `effects` selection (see the header).
EffectMask effectSelection(const JointErrorModel& model, const char* effects);

}  // namespace jointcomp::capi
