// What every entry point of the C API shares: the handle types, the argument checks, and the one place
// where exceptions become status codes (so that none crosses the C boundary).
#pragma once

#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "jointcomp/jointcomp.h"
#include "model/common/errors.hpp"
#include "model/common/progress.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/plant/flexible_joint_plant.hpp"
#include "model/robot/drive_parameters.hpp"
#include "model/robot/inverse_kinematics.hpp"

// Every handle starts with a magic number naming its kind; free overwrites it, so that a handle of the
// wrong kind or an already freed one is recognised as long as its memory has not been reused.
constexpr std::uint64_t kRobotMagic = 0x6a63'726f'626f'7431ULL;      // "jcrobot1"
constexpr std::uint64_t kPlantMagic = 0x6a63'706c'616e'7431ULL;      // "jcplant1"
constexpr std::uint64_t kReportMagic = 0x6a63'7265'706f'7274ULL;     // "jcreport"
constexpr std::uint64_t kSpiralJobMagic = 0x6a63'7370'6a6f'6231ULL;  // "jcspjob1"
constexpr std::uint64_t kFreedMagic = 0x6a63'6672'6565'6421ULL;      // "jcfreed!"

struct jc_robot {
  jc_robot(std::shared_ptr<const jointcomp::Robot> loaded, jointcomp::JointErrorModel nominal,
           std::vector<jointcomp::DriveParameters> drive_parameters);

  std::uint64_t magic = kRobotMagic;  // first member: read before anything else is trusted
  std::mutex mutex;                   // serialises calls on this handle
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
};

struct jc_plant {
  explicit jc_plant(std::unique_ptr<jointcomp::FlexibleJointPlant> created) : plant(std::move(created)) {}

  std::uint64_t magic = kPlantMagic;
  std::mutex mutex;
  const std::unique_ptr<jointcomp::FlexibleJointPlant> plant;
};

struct jc_report {
  jc_report(std::string json_text, std::string summary_text)
      : json(std::move(json_text)), summary(std::move(summary_text)) {}

  std::uint64_t magic = kReportMagic;
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

// The handle behind a pointer, after checking that it is one of the expected kind and still alive.
// `name`: the parameter's name in the header, for the message.
jc_robot& robotHandle(jc_robot* robot, const char* name = "robot");
jc_plant& plantHandle(jc_plant* plant);
jc_report& reportHandle(jc_report* report);
// The magic number of a live handle at `handle` must be `magic`, else the error names what was found.
void requireHandleKind(const void* handle, std::uint64_t magic, const char* expected, const char* name);

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
