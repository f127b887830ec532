// The paper's spiral at 1 ms as the FMU tests run it (tests/fmu/test_fmu_importer.cpp, test_fmu_calls.cpp,
// test_fmu_behaviour.cpp): the plan, the paper's truth through the plant.* parameters, and the start of a run.
#pragma once

#include <dlfcn.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <sys/stat.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#ifdef JOINTCOMP_TEST_WITH_CAPI
#include "jointcomp/jointcomp.h"
#endif

#include "fmu/description/variable_table.hpp"
#include "fmu/fmi2_api.hpp"
#include "fmu/fmi3_api.hpp"
#include "fmu/robot/fmu_plant_options.hpp"
#include "model/compensation/compensator.hpp"
#include "model/compensation/feed_rate.hpp"
#include "model/compensation/joint_trajectory.hpp"
#include "model/compensation/path.hpp"
#include "model/dynamic_compensation/dynamic_compensation.hpp"
#include "model/effects/perturbation.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/parameter_file.hpp"
#include "model/io/robot_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"
#include "model/robot/kinematics.hpp"
#include "tests/fmu/fmu_master.hpp"

namespace jointcomp::fmutest {
// ---- The paper's spiral at 1 ms ------------------------------------------------------------------------

struct Spiral {
  std::shared_ptr<const Robot> robot;  // the FMU's own robot.json
  std::vector<double> time;
  std::vector<JointVector> q;
  std::vector<Eigen::Vector3d> tool;
};

inline const Spiral& spiral() {
  static const Spiral s = [] {
    Spiral result;
    result.robot = std::make_shared<const Robot>(loadRobotFile(unzipped(2) + "/resources/robot.json"));
    const Path path = logarithmicSpiral(SpiralExperimentSpec::defaultSpiral());
    FeedRateSpec feed;
    feed.controller_period = 0.001;
    JointVector seed = JointVector::Zero(kDof);
    seed[1] = seed[2] = seed[4] = 60 * kDegree;  // as the paper's experiment: forward, elbow up
    const JointTrajectory trajectory =
        planJointTrajectory(*result.robot, planFeedRate(path, feed), toolPointingDown(), seed);
    result.time = trajectory.time;
    result.q = trajectory.q;
    result.tool = trajectory.tool_position;
    return result;
  }();
  return s;
}

inline std::vector<double> values(const JointVector& q) { return std::vector<double>(q.data(), q.data() + q.size()); }

// The paper's truth: the nominal parameters moved by the paper experiment's default perturbation.
inline JointErrorModel nominalModel() {
  return loadParameterFile(unzipped(2) + "/resources/parameters.json", spiral().robot);
}
inline JointErrorModel truthModel() { return perturbedModel(nominalModel(), PerturbationSpec{}); }

// Gives the FMU's plant the truth's effect parameters, through the FMU's plant.* parameters.
inline void setTruth(Master& m, const JointErrorModel& truth) {
  std::vector<std::uint32_t> vrs;
  std::vector<double> numbers;
  for (int e = 0; e < truth.effectCount(); ++e) {
    const std::vector<std::string> names = truth.effect(e).parameterNames();
    const std::vector<double> v = truth.effect(e).parameters();
    for (std::size_t k = 0; k < names.size(); ++k) {
      // Model names carry the unit after the last '_' of the last part: joint_1.stiffness_nm_per_rad.
      std::string name = names[k];
      for (const char* unit : {"_nm_per_rad", "_n_per_m", "_rad", "_m", "_n"}) {
        const std::string suffix = unit;
        if (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0) {
          name.erase(name.size() - suffix.size());
          break;
        }
      }
      vrs.push_back(m.vr("plant." + name));
      numbers.push_back(v[k]);
    }
  }
  ASSERT_EQ(vrs.size(), 20u);
  ASSERT_EQ(m.setReals(vrs, numbers), kOK) << m.log();
}

// Instantiates and initialises at the spiral's first sample.
// step_past_updates: integrator.step_past_updates, s, and step_past_tolerance: integrator.step_past_tolerance,
// rad (negative: the FMU's defaults, fmuPlantOptions()).
inline void start(Master& m, long mode, const JointErrorModel* truth = nullptr, bool even_steps = true,
                  double step_past_updates = -1.0, double step_past_tolerance = -1.0) {
  ASSERT_TRUE(m.instantiate()) << m.log();
  ASSERT_EQ(m.enterInitialization(spiral().time[0]), kOK) << m.log();
  ASSERT_EQ(m.setEnumeration(m.vr("compensation"), mode), kOK) << m.log();
  if (truth) setTruth(m, *truth);
  if (!even_steps) {
    ASSERT_EQ(m.setBoolean(m.vr("integrator.even_steps"), false), kOK) << m.log();
  }
  if (step_past_updates >= 0.0) {
    ASSERT_EQ(m.setReals({m.vr("integrator.step_past_updates")}, {step_past_updates}), kOK) << m.log();
  }
  if (step_past_tolerance >= 0.0) {
    ASSERT_EQ(m.setReals({m.vr("integrator.step_past_tolerance")}, {step_past_tolerance}), kOK) << m.log();
  }
  ASSERT_EQ(m.setReals(m.vrs("q_desired_", kDof), values(spiral().q[0])), kOK) << m.log();
  ASSERT_EQ(m.exitInitialization(), kOK) << m.log();
}

}  // namespace jointcomp::fmutest
