// libFuzzer target: the plant under any drive parameters, options and references (NaN, infinities, zero,
// negative and absurd values among them). Every call either works or throws a jointcomp::Error, and the
// work is bounded (gains no drive can have are refused, every advance has a step budget); a run that
// returns normally has a finite state and its links within their limits (plus the margin): the watchdog
// lets nothing else through.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include <fuzzer/FuzzedDataProvider.h>

#include "model/common/errors.hpp"
#include "model/io/parameter_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"
#include "model/robot/load_urdf.hpp"

namespace {

using namespace jointcomp;

// A double that is often ordinary and sometimes hostile, as a user's file or a careless master gives.
double anyValue(FuzzedDataProvider& input, double typical) {
  switch (input.ConsumeIntegralInRange<int>(0, 7)) {
    case 0: return std::nan("");
    case 1: return HUGE_VAL * (input.ConsumeBool() ? 1.0 : -1.0);
    case 2: return 0.0;
    case 3: return -typical;
    case 4: return input.ConsumeFloatingPoint<double>();  // anything, 1e300 included
    default: return typical * std::exp(input.ConsumeFloatingPointInRange<double>(-6.0, 6.0));
  }
}

[[noreturn]] void broken(const char* what) {
  std::fprintf(stderr, "fuzz_plant: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const auto robot =
      std::make_shared<const Robot>(loadRobotFromUrdfFile(JOINTCOMP_DATA_DIR "/robots/rx170.urdf"));
  static const JointErrorModel model = loadParameterFile(JOINTCOMP_DATA_DIR "/params/rx170.json", robot);
  static const std::vector<DriveParameters> shipped =
      loadDriveParameters(JOINTCOMP_DATA_DIR "/params/rx170.json", *robot);
  FuzzedDataProvider input(data, size);
  const int n = robot->dof();

  std::vector<DriveParameters> drives = shipped;
  const int spoiled = input.ConsumeIntegralInRange<int>(0, n);  // joints whose drives the input rewrites
  for (int k = 0; k < spoiled; ++k) {
    DriveParameters& d = drives[input.ConsumeIntegralInRange<int>(0, n - 1)];
    for (const DriveField& field : driveFields()) {
      if (input.ConsumeBool()) d.*field.member = anyValue(input, d.*field.member > 0.0 ? d.*field.member : 1.0);
    }
  }
  PlantOptions options;
  if (input.ConsumeBool()) options.relative_tolerance = anyValue(input, 1e-6);
  if (input.ConsumeBool()) options.absolute_tolerance = anyValue(input, 1e-8);
  if (input.ConsumeBool()) options.max_step = anyValue(input, 1e-3);
  if (input.ConsumeBool()) options.max_steps_per_advance = input.ConsumeIntegralInRange<long>(-5, 1000000);
  if (input.ConsumeBool()) options.max_order = input.ConsumeIntegralInRange<int>(-1, 7);
  if (input.ConsumeBool()) options.tracking_envelope_rad = anyValue(input, 0.2);
  if (input.ConsumeBool()) options.joint_limit_margin_rad = anyValue(input, 0.02);
  options.control = !input.ConsumeBool() || input.ConsumeBool();

  try {
    FlexibleJointPlant plant(model, drives, options);
    JointVector start(n);
    for (int j = 0; j < n; ++j) {
      const Joint& limits = robot->joints[j];
      start[j] = std::isfinite(limits.lower) && std::isfinite(limits.upper)
                     ? input.ConsumeFloatingPointInRange<double>(limits.lower, limits.upper)
                     : input.ConsumeFloatingPointInRange<double>(-3.0, 3.0);
    }
    plant.reset(start);
    double t = 0.0;
    for (int update = 0; update < 8 && input.remaining_bytes() > 0; ++update) {
      JointVector position = start, velocity = JointVector::Zero(n);
      const int joint = input.ConsumeIntegralInRange<int>(0, n - 1);
      position[joint] += anyValue(input, 0.05);
      velocity[joint] = input.ConsumeBool() ? anyValue(input, 0.1) : 0.0;
      try {
        plant.setReference(position, velocity);
      } catch (const InvalidArgument&) {
        continue;  // NaN or infinity in the reference: refused, the plant goes on with the last one
      }
      t += input.ConsumeFloatingPointInRange<double>(1e-4, 0.02);
      plant.advance(t);
      const double* y = plant.state();
      for (int i = 0; i < plant.stateSize(); ++i) {
        if (!std::isfinite(y[i])) broken("an advance returned normally with a state that is not finite");
      }
      for (int j = 0; j < n; ++j) {
        const double margin = plant.options().joint_limit_margin_rad;
        if (y[j] > robot->joints[j].upper + margin || y[j] < robot->joints[j].lower - margin) {
          broken("an advance returned normally with a link beyond its limits and margin");
        }
      }
    }
  } catch (const Error&) {
    // Refused with a reason: what the plant must do with what it cannot run.
  }
  return 0;
}
