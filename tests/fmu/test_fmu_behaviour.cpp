// What the FMU does for a master that uses it well beyond the paper's spiral: a plain run follows the demo
// move, the dynamic corrections follow fast moves, the reference follows the inputs or the demo, a runaway
// is discarded and a saturating step settles, a parameter file extended by discovery drives the FMU.
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

#include "tests/fmu/fmu_spiral.hpp"

namespace jointcomp {
namespace {

using namespace fmutest;  // NOLINT(google-build-using-namespace): the master of fmu_master.hpp

class FmuBehaviour : public ::testing::TestWithParam<int> {};

// A 0.5 rad step of q_desired_1 (once: every step OK while q_link_1 swung away to -46 rad) leaves the
// drive's tracking envelope: the step is discarded, naming the joint and the envelope, and stepping on
// is refused until the master goes back to an earlier state. With the envelope widened, the same step
// is followed and settles (the controller's anti-windup), inside the joint limits.
// A plain run (no input set) follows the built-in demo move, and the compensation shows in it: the links
// follow the planned move more closely with the correction than without.
TEST_P(FmuBehaviour, APlainRunMovesTheRobotAndShowsTheCompensation) {
  double worst_error[3] = {0.0, 0.0, 0.0};  // max |q_link - q_planned| of joints 2 and 3, per mode
  for (int mode : {0, 2}) {
    auto m = makeMaster(GetParam());
    ASSERT_TRUE(m->instantiate());
    ASSERT_EQ(m->enterInitialization(), kOK);
    ASSERT_EQ(m->setEnumeration(m->vr("compensation"), mode), kOK);
    ASSERT_EQ(m->exitInitialization(), kOK) << m->log();
    const std::vector<std::uint32_t> vrs = {m->vr("q_planned.joint_2"), m->vr("q_planned.joint_3"),
                                            m->vr("q_link.joint_2"), m->vr("q_link.joint_3"),
                                            m->vr("q_desired.joint_2")};
    std::vector<double> values;
    double lowest = 1e9, highest = -1e9, t = 0.0;
    for (int k = 0; k < 600; ++k, t += 0.01) {
      ASSERT_EQ(m->doStep(t, 0.01), kOK) << "t = " << t << m->log();
      ASSERT_EQ(m->getReals(vrs, values), kOK);
      lowest = std::min(lowest, values[0]);
      highest = std::max(highest, values[0]);
      EXPECT_EQ(values[4], 0.0);  // the inputs keep their start values; the robot follows the demo
      if (t > 1.0) {
        worst_error[mode] =
            std::max({worst_error[mode], std::abs(values[2] - values[0]), std::abs(values[3] - values[1])});
      }
    }
    EXPECT_GT(highest - lowest, 0.3) << "the demo move swings joint 2 by 0.35 rad in 5 s";
    // After initialisation, a desired input is refused with the way out, not silently ignored.
    EXPECT_EQ(m->setReals({m->vr("q_desired.joint_1")}, {0.1}), kError);
    EXPECT_TRUE(m->logged("reference = inputs")) << m->log();
    EXPECT_EQ(m->terminate(), kOK);
  }
  std::printf(
      "demo move, joints 2 and 3 after the first second: %.2g rad off the plan without correction, %.2g rad "
      "with the stiffness and kinematic correction\n",
      worst_error[0], worst_error[2]);
  EXPECT_LT(worst_error[0], 0.01) << "the links follow the demo move";
  EXPECT_LT(worst_error[2], 0.5 * worst_error[0])
      << "with correction " << worst_error[2] << " rad, without " << worst_error[0] << " rad";
}

// The dynamic compensation through the FMU (issue 18): the master computes the references offline
// (jc_compensate_trajectory_dynamic, Python's compensate_dynamic, or here the core) and feeds them with their
// velocities as inputs, compensation none; with the FMU's robot equal to the model and no noise, its links
// follow a fast move (joints 1 to 3 by 20 to 30 degrees in 0.8 s) to within 1e-6 rad.
TEST_P(FmuBehaviour, OfflineDynamicReferencesMakeTheLinksFollowAFastMoveWithin1e6Rad) {
  const ParameterSet set = loadParameterSet(unzipped(2) + "/resources/parameters.json", spiral().robot);
  JointTrajectory planned;
  const JointVector start = (JointVector(kDof) << 0, 30, 60, 0, 45, 0).finished() * kDegree;
  const JointVector travel = (JointVector(kDof) << 30, 20, -25, 0, 15, 0).finished() * kDegree;
  for (int k = 0; k <= 250; ++k) {
    const double t = 0.004 * k, s = std::clamp((t - 0.1) / 0.8, 0.0, 1.0);
    planned.time.push_back(t);
    planned.q.push_back(start + s * s * s * s * (35 - 84 * s + 70 * s * s - 20 * s * s * s) * travel);
    planned.qd.push_back(140 * s * s * s * (1 - s) * (1 - s) * (1 - s) / 0.8 * travel);
  }
  DynamicCompensationOptions options;
  options.tolerance_rad = 2e-7;
  options.plant = DynamicCompensationOptions::tightPlantOptions(1e-8);
  std::vector<JointVector> reference, velocity;
  compensateDynamically(set.model, set.drives, planned, reference, velocity, options);

  auto m = makeMaster(GetParam());
  ASSERT_TRUE(m->instantiate());
  ASSERT_EQ(m->enterInitialization(), kOK);
  ASSERT_EQ(m->setEnumeration(m->vr("compensation"), 0), kOK);
  ASSERT_EQ(m->setBoolean(m->vr("use_velocity_inputs"), true), kOK);
  ASSERT_EQ(m->setReals({m->vr("integrator.relative_tolerance"), m->vr("integrator.absolute_tolerance")},
                        {options.plant.relative_tolerance, options.plant.absolute_tolerance}),
            kOK);
  ASSERT_EQ(m->setReals(m->vrs("q_desired_", kDof), values(reference[0])), kOK);
  ASSERT_EQ(m->setReals(m->vrs("qd_desired_", kDof), values(velocity[0])), kOK);
  ASSERT_EQ(m->exitInitialization(), kOK) << m->log();
  double worst = 0.0, largest_correction = 0.0;
  std::vector<double> link;
  for (std::size_t k = 0; k < planned.time.size(); ++k) {
    ASSERT_EQ(m->setReals(m->vrs("q_desired_", kDof), values(reference[k])), kOK);
    ASSERT_EQ(m->setReals(m->vrs("qd_desired_", kDof), values(velocity[k])), kOK);
    ASSERT_EQ(m->getReals(m->vrs("q_link_", kDof), link), kOK);
    for (int j = 0; j < kDof; ++j) worst = std::max(worst, std::abs(link[j] - planned.q[k][j]));
    for (int j = 0; j < kDof; ++j)
      largest_correction = std::max(largest_correction, std::abs(reference[k][j] - planned.q[k][j]));
    if (k + 1 < planned.time.size()) {
      ASSERT_EQ(m->doStep(planned.time[k], planned.time[k + 1] - planned.time[k]), kOK) << m->log();
    }
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_GT(largest_correction, 1e-4) << "the references do differ from the plan";
  EXPECT_EQ(m->terminate(), kOK);
}

// compensation = dynamic (issue 18's online mode): the closed form one communication step at a time, from
// q, qd and qdd desired. Its q_ref is the core's OnlineDynamicCompensator's bit for bit (the sequence
// instance.hpp documents); on a fast move, with the FMU's robot equal to the model, its links stay several
// times closer to the plan than with the static correction; an FMU state taken mid-move carries the drive
// filter, so a run restored from it (or from its bytes) repeats bit for bit.
TEST_P(FmuBehaviour, TheDynamicModeFollowsAFastMoveCloserThanTheStaticCorrectionAndItsStateRoundTrips) {
  const ParameterSet set = loadParameterSet(unzipped(2) + "/resources/parameters.json", spiral().robot);
  const JointVector start = (JointVector(kDof) << 0, 30, 60, 0, 45, 0).finished() * kDegree;
  const JointVector travel = (JointVector(kDof) << 30, 20, -25, 0, 15, 0).finished() * kDegree;
  const double period = 0.004, duration = 0.8;
  const int samples = 300;
  std::vector<JointVector> q(samples), qd(samples), qdd(samples);
  for (int k = 0; k < samples; ++k) {
    const double s = std::clamp((period * k - 0.1) / duration, 0.0, 1.0);
    q[k] = start + s * s * s * s * (35 - 84 * s + 70 * s * s - 20 * s * s * s) * travel;
    qd[k] = 140 * s * s * s * (1 - s) * (1 - s) * (1 - s) / duration * travel;
    qdd[k] = 420 * s * s * (1 - s) * (1 - s) * (1 - 2 * s) / (duration * duration) * travel;
  }
  OnlineDynamicCompensator core(set.model, set.drives);
  OnlineDynamicState core_state = core.initialState();
  double worst[4] = {0, 0, 0, 0};
  std::vector<double> link_at_end;
  for (long mode : {2L, 3L}) {
    auto m = makeMaster(GetParam());
    ASSERT_TRUE(m->instantiate());
    ASSERT_EQ(m->enterInitialization(), kOK);
    ASSERT_EQ(m->setEnumeration(m->vr("compensation"), mode), kOK);
    ASSERT_EQ(m->setBoolean(m->vr("use_velocity_inputs"), true), kOK);
    auto feed = [&](int k) {
      ASSERT_EQ(m->setReals(m->vrs("q_desired_", kDof), values(q[k])), kOK);
      ASSERT_EQ(m->setReals(m->vrs("qd_desired_", kDof), values(qd[k])), kOK);
      ASSERT_EQ(m->setReals(m->vrs("qdd_desired_", kDof), values(qdd[k])), kOK);
    };
    feed(0);
    ASSERT_EQ(m->exitInitialization(), kOK) << m->log();
    void* saved = nullptr;
    std::vector<double> link, q_ref;
    for (int k = 0; k < samples; ++k) {
      feed(k);
      ASSERT_EQ(m->getReals(m->vrs("q_link_", kDof), link), kOK);
      for (int j = 0; j < kDof; ++j) worst[mode] = std::max(worst[mode], std::abs(link[j] - q[k][j]));
      if (mode == 3) {
        JointVector reference, velocity;
        // q_ref is read at the FMU's time, the end of the last step (t_(k-1) + h); doStep then takes the
        // importer's clock (k h) when the two differ in their last bits, and that sample is the one kept.
        const double read_at = k == 0 ? 0.0 : period * (k - 1) + period;
        OnlineDynamicState probe;
        ASSERT_TRUE(
            core.compensate(core_state, read_at, q[k], qd[k], qdd[k], Vector6::Zero(), reference, velocity, probe)
                .converged);
        ASSERT_EQ(m->getReals(m->vrs("q_ref_", kDof), q_ref), kOK);
        for (int j = 0; j < kDof; ++j) ASSERT_EQ(q_ref[j], reference[j]) << "sample " << k << " joint " << j + 1;
        core.compensate(core_state, period * k, q[k], qd[k], qdd[k], Vector6::Zero(), reference, velocity, core_state);
        if (k == 150) {
          ASSERT_EQ(m->getState(&saved), kOK);
        }
      }
      if (k + 1 < samples) {
        ASSERT_EQ(m->doStep(period * k, period), kOK) << m->log();
      }
    }
    if (mode == 3) {
      link_at_end = link;
      std::vector<unsigned char> bytes;
      ASSERT_EQ(m->serialize(saved, bytes), kOK);
      for (int round = 0; round < 2; ++round) {
        void* restored = nullptr;
        if (round == 0) {
          ASSERT_EQ(m->setState(saved), kOK);
        } else {
          ASSERT_EQ(m->deserialize(bytes, &restored), kOK);
          ASSERT_EQ(m->setState(restored), kOK);
        }
        for (int k = 150; k < samples; ++k) {
          feed(k);
          if (k + 1 < samples) {
            ASSERT_EQ(m->doStep(period * k, period), kOK) << m->log();
          }
        }
        ASSERT_EQ(m->getReals(m->vrs("q_link_", kDof), link), kOK);
        for (int j = 0; j < kDof; ++j) EXPECT_EQ(link[j], link_at_end[j]) << "round " << round << " joint " << j + 1;
        if (restored) {
          ASSERT_EQ(m->freeState(&restored), kOK);
        }
      }
      ASSERT_EQ(m->freeState(&saved), kOK);
    }
    EXPECT_EQ(m->terminate(), kOK);
  }
  std::printf(
      "fast move through the FMU: largest link error %.3g rad with the static correction, %.3g rad with "
      "the dynamic mode\n",
      worst[2], worst[3]);
  EXPECT_LT(worst[3], 0.2 * worst[2]);
}

// Inputs set during initialisation (even to their start values) make reference = auto follow the inputs;
// reference = demo follows the demo move whatever the inputs say.
TEST_P(FmuBehaviour, TheReferenceFollowsTheInputsOnceOneIsSetOrTheDemoWhenAsked) {
  for (long source : {0L, 2L}) {
    auto m = makeMaster(GetParam());
    ASSERT_TRUE(m->instantiate());
    ASSERT_EQ(m->enterInitialization(), kOK);
    ASSERT_EQ(m->setEnumeration(m->vr("reference"), source), kOK);
    ASSERT_EQ(m->setReals({m->vr("q_desired.joint_2")}, {0.2}), kOK);
    ASSERT_EQ(m->exitInitialization(), kOK) << m->log();
    std::vector<double> planned;
    for (double t = 0.0; t < 2.0 - 1e-9; t += 0.01) ASSERT_EQ(m->doStep(t, 0.01), kOK) << m->log();
    ASSERT_EQ(m->getReals({m->vr("q_planned.joint_2")}, planned), kOK);
    if (source == 0) {
      EXPECT_EQ(planned[0], 0.2);
      EXPECT_EQ(m->setReals({m->vr("q_desired.joint_2")}, {0.25}), kOK);
    } else {
      EXPECT_NE(planned[0], 0.2);  // the demo at t = 2 s
      EXPECT_EQ(m->setReals({m->vr("q_desired.joint_2")}, {0.25}), kError);
      EXPECT_TRUE(m->logged("reference = demo")) << m->log();
      EXPECT_EQ(m->setReals({m->vr("qd_desired.joint_6")}, {0.1}), kError);
      // The inputs that are not desired ones still take values while the robot follows the demo.
      EXPECT_EQ(m->setReals({m->vr("tool_wrench.force_z")}, {-10.0}), kOK) << m->log();
    }
    EXPECT_EQ(m->terminate(), kOK);
  }
}

TEST_P(FmuBehaviour, ARunawayIsDiscardedAndASaturatingStepSettles) {
  auto m = makeMaster(GetParam());
  ASSERT_TRUE(m->instantiate());
  ASSERT_EQ(m->enterInitialization(), kOK);
  ASSERT_EQ(m->setEnumeration(m->vr("reference"), 1), kOK);  // the inputs, first set after initialisation
  ASSERT_EQ(m->exitInitialization(), kOK) << m->log();
  void* before = nullptr;
  ASSERT_EQ(m->getState(&before), kOK);
  ASSERT_EQ(m->setReals({m->vr("q_desired.joint_1")}, {-0.5}), kOK);
  EXPECT_EQ(m->doStep(0.0, 0.01), kDiscard);
  EXPECT_TRUE(m->logged("logStatusDiscard")) << m->log();
  EXPECT_TRUE(m->logged("joint_1")) << m->log();
  EXPECT_TRUE(m->logged("tracking envelope")) << m->log();
  EXPECT_EQ(m->doStep(m->lastSuccessfulTime(), 0.01), kError);
  ASSERT_EQ(m->setState(before), kOK);
  EXPECT_EQ(m->doStep(0.0, 0.01), kOK) << m->log();  // the state before the step holds q_desired_1 = 0
  EXPECT_EQ(m->terminate(), kOK);
  EXPECT_EQ(m->freeState(&before), kOK);

  auto wide = makeMaster(GetParam());
  ASSERT_TRUE(wide->instantiate());
  ASSERT_EQ(wide->enterInitialization(), kOK);
  ASSERT_EQ(wide->setReals({wide->vr("watchdog.tracking_envelope")}, {1.0}), kOK);
  ASSERT_EQ(wide->setReals({wide->vr("q_desired.joint_1")}, {0.0}), kOK);  // reference = auto: the inputs
  ASSERT_EQ(wide->exitInitialization(), kOK) << wide->log();
  ASSERT_EQ(wide->setReals({wide->vr("q_desired.joint_1")}, {-0.5}), kOK);
  std::vector<double> link;
  double t = 0.0;
  for (int k = 0; k < 800; ++k, t += 0.01) ASSERT_EQ(wide->doStep(t, 0.01), kOK) << "t = " << t << wide->log();
  ASSERT_EQ(wide->getReals({wide->vr("q_link.joint_1")}, link), kOK);
  EXPECT_NEAR(link[0], -0.5, 1e-3);
}

// A parameter file extended by discovery (payload, hysteresis, joint offset) drives the FMU: it
// instantiates with it, and its predicted joint errors are the C++ model's for that file, not the
// shipped file's.
TEST_P(FmuBehaviour, AParameterFileExtendedByDiscoveryDrivesTheFmu) {
  const std::string scratch = JOINTCOMP_FMU_SCRATCH_DIR;
  ::mkdir(scratch.c_str(), 0755);
  const std::string folder = scratch + "/extended parameters " + std::to_string(GetParam());
  ::mkdir(folder.c_str(), 0755);
  writeFileAtomically(folder + "/robot.json", readFile(unzipped(2) + "/resources/robot.json"));
  nlohmann::json parameters = nlohmann::json::parse(readFile(unzipped(2) + "/resources/parameters.json"));
  parameters["effects"].push_back({{"type", "payload"}, {"mass_kg", 20.0}, {"com_m", {0.0, 0.0, 0.1}}});
  parameters["effects"].push_back({{"type", "hysteresis"}, {"width_rad_per_nm", {0.0, 1e-6, 0.0, 0.0, 0.0, 0.0}}});
  parameters["effects"].push_back({{"type", "offset"}, {"offset_rad", {0.0, 0.0, 1e-3, 0.0, 0.0, 0.0}}});
  writeFileAtomically(folder + "/parameters.json", parameters.dump(2));
  const std::string location = GetParam() == 2 ? "file://" + percentEncoded(folder) : folder + "/";

  // Other resources are another FMU: its token is that of their bytes.
  const std::string token = fmu::instantiationToken(readFile(folder + "/robot.json"),
                                                    readFile(folder + "/parameters.json"), JOINTCOMP_FMU_VERSION);
  auto m = makeMaster(GetParam());
  ASSERT_TRUE(m->instantiate("robot", location, token)) << m->log();
  ASSERT_EQ(m->enterInitialization(spiral().time[0]), kOK) << m->log();
  ASSERT_EQ(m->setReals(m->vrs("q_desired_", kDof), values(spiral().q[0])), kOK) << m->log();
  ASSERT_EQ(m->exitInitialization(), kOK) << m->log();
  std::vector<double> q_link, q_motor, dq_predicted;
  ASSERT_EQ(m->getReals(m->vrs("q_link_", kDof), q_link), kOK);
  ASSERT_EQ(m->getReals(m->vrs("q_motor_", kDof), q_motor), kOK);
  ASSERT_EQ(m->getReals(m->vrs("dq_predicted_", kDof), dq_predicted), kOK);
  // The plant carries the payload and the offset; the compensation (mode 2: every effect of the file)
  // knows them, so the links still stand where planned, and the prediction is the plant's own error.
  for (int j = 0; j < kDof; ++j) {
    EXPECT_NEAR(q_link[j], spiral().q[0][j], 1e-9) << "joint " << j + 1;
    EXPECT_NEAR(dq_predicted[j], q_link[j] - q_motor[j], 1e-9) << "joint " << j + 1;
  }
  // The same start with the shipped file: the extended file's errors differ by the offset and payload.
  auto shipped = makeMaster(GetParam());
  start(*shipped, 2);
  std::vector<double> dq_shipped;
  ASSERT_EQ(shipped->getReals(shipped->vrs("dq_predicted_", kDof), dq_shipped), kOK);
  EXPECT_GT(std::abs(dq_predicted[1] - dq_shipped[1]), 1e-5);  // 20 kg at the flange bends joint 2
  EXPECT_GT(std::abs(dq_predicted[2] - dq_shipped[2]), 5e-4);  // the 1 mrad joint-3 offset
}

INSTANTIATE_TEST_SUITE_P(Fmi, FmuBehaviour, ::testing::Values(2, 3), [](const ::testing::TestParamInfo<int>& param) {
  return "fmi" + std::to_string(param.param);
});

}  // namespace
}  // namespace jointcomp
