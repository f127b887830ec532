// The preamble most commands share: the robot of --urdf and everything its parameter file says (joint-error
// model and drives), read once (model/io/parameter_file.hpp). A malformed "plant" object is an error in
// every command, whether it simulates or only carries the drives over into the file it writes.
#pragma once

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "cli/file_locations.hpp"
#include "cli/options.hpp"
#include "model/common/progress.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp::cli {

struct RobotSetup {
  std::string urdf;    // the URDF read
  std::string params;  // the parameter file read; "" when there was none
  std::shared_ptr<const Robot> robot;
  ParameterSet parameters;  // without a file: no effects, a direct gear train, no drives
  // What was assumed for want of a parameter file, said once by the commands that fit ("" with a file).
  std::string assumed() const {
    return params.empty() ? "no --params: no prior joint errors, every gear ratio 1 (a joint's motor turns with it: "
                            "motor and output harmonics are one), no drives"
                          : "";
  }
};

// The chain of the URDF that --base-link and --tip-link choose (default: the URDF's root, and the end of
// its longest moving chain).
inline UrdfChainOptions chainOptions(const Options& options) {
  UrdfChainOptions chain;
  chain.root_link = options.get("base-link", "");
  chain.tip_link = options.get("tip-link", "");
  return chain;
}

// The console's progress lines of a long command, "[  12.3 s] what", unless --quiet.
inline Progress consoleProgress(const Options& options) {
  if (options.has("quiet")) return {};
  const auto started = std::chrono::steady_clock::now();
  return [started](const std::string& what) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    std::printf("  [%7.2f s] %s\n", elapsed, what.c_str());
    std::fflush(stdout);
  };
}

// `params_option` is the option naming the file ("params", or "truth" for simulate). With an empty
// `default_params` the file is optional.
inline RobotSetup loadRobotSetup(const Options& options, const std::string& default_urdf,
                                 const std::string& params_option = "params", const std::string& default_params = "") {
  const std::string urdf = options.get("urdf", default_urdf);
  const std::string params = options.get(params_option, default_params);
  auto robot = std::make_shared<const Robot>(loadRobotFromUrdfFile(urdf, chainOptions(options)));
  ParameterSet parameters =
      params.empty()
          ? ParameterSet{JointErrorModel(robot, GearTrain::direct(robot->dof()), {}), {}, std::nullopt, std::nullopt}
          : loadParameterSet(params, robot);
  return RobotSetup{urdf, params, std::move(robot), std::move(parameters)};
}

}  // namespace jointcomp::cli
