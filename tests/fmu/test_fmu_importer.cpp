// The FMUs as a master uses them: the binary is loaded with dlopen from the unzipped FMU (in a folder
// whose path has a space), value references are read from its modelDescription.xml, and the paper's
// spiral is stepped through it. What a master may do wrong is tried too; every such call must return an
// error (and say why in the log), never crash.
//
// The numbers through the FMU are compared with the same sequence run on FlexibleJointPlant and
// Compensator directly (the sequence fmu/robot/robot_model.hpp documents): they must agree bit for bit.
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

// Communication steps as sample counts of the 1 ms plan: 1 throughout, or a varying pattern.
std::vector<int> stepPattern(bool varying) {
  if (!varying) return {1};
  return {1, 2, 3, 1, 5, 2, 1, 4};
}

// Outputs after each step.
struct Record {
  std::vector<std::vector<double>> q_link, q_ref, outputs;
  std::vector<std::size_t> sample;  // the spiral sample each step ended at
};

// Steps the FMU from sample `from` until sample `to` (or the end), reading the outputs after each step.
Record run(Master& m, std::size_t from, std::size_t to, bool varying) {
  const Spiral& s = spiral();
  Record record;
  const auto q_desired = m.vrs("q_desired_", kDof);
  const auto q_link = m.vrs("q_link_", kDof);
  const auto q_ref = m.vrs("q_ref_", kDof);
  const std::vector<int> pattern = stepPattern(varying);
  std::size_t k = from;
  for (std::size_t i = 0; k + 1 < std::min(to, s.time.size()); ++i) {
    const std::size_t next = std::min(k + pattern[i % pattern.size()], s.time.size() - 1);
    EXPECT_EQ(m.setReals(q_desired, values(s.q[k])), kOK);
    std::vector<double> ref;
    EXPECT_EQ(m.getReals(q_ref, ref), kOK);  // the command for this step, before it is taken
    const int status = m.doStep(s.time[k], s.time[next] - s.time[k]);
    if (status != kOK) {
      ADD_FAILURE() << "step at t = " << s.time[k] << " returned " << status << "\n" << m.log();
      break;
    }
    std::vector<double> link, all;
    EXPECT_EQ(m.getReals(q_link, link), kOK);
    EXPECT_EQ(m.getReals(m.md.outputs, all), kOK);
    record.q_link.push_back(link);
    record.q_ref.push_back(ref);
    record.outputs.push_back(all);
    record.sample.push_back(next);
    k = next;
  }
  return record;
}

// The FMU's estimate of the desired velocity from q_desired at the last three communication points
// (fmu/robot/held_steps.cpp), written out again: the slope now of the parabola through them.
JointVector parabolaSlope(const JointVector& q, double t, const JointVector& last_q, double last_t,
                          const JointVector& earlier_q, double earlier_t) {
  const double last = t - last_t, earlier = last_t - earlier_t, both = last + earlier;
  return q * ((2.0 * last + earlier) / (last * both)) - last_q * (both / (last * earlier)) +
         earlier_q * (last / (earlier * both));
}

// The same sequence on the plant and the compensator directly (fmu/robot/robot_model.hpp, steps 1-4).
Record runDirectly(long mode, const JointErrorModel& truth, std::size_t to, bool varying,
                   const PlantOptions& options = fmuPlantOptions()) {
  const Spiral& s = spiral();
  const JointErrorModel nominal = nominalModel();
  const std::vector<DriveParameters> drives = loadDriveParameters(unzipped(2) + "/resources/parameters.json", *s.robot);
  FlexibleJointPlant plant(truth, drives, options);
  EffectMask mask = 0;
  if (mode == 1) mask = nominal.loadsAnd({"compliance"});
  if (mode == 2) mask = nominal.allEffects();
  Compensator compensator(nominal, mask);
  JointContext ctx(kDof);
  auto reference = [&](const JointVector& q, const JointVector& v, double t) {
    if (mode == 0) return q;
    ctx.q = q;
    ctx.velocity = v;
    ctx.time = t;
    ctx.tool_wrench = Vector6::Zero();
    JointVector ref;
    EXPECT_TRUE(compensator.compensate(ctx, ref).converged);
    return ref;
  };
  plant.setToolWrench(Vector6::Zero());
  plant.reset(reference(s.q[0], JointVector::Zero(kDof), s.time[0]), s.time[0]);
  Record record;
  const std::vector<int> pattern = stepPattern(varying);
  bool has_last = false, has_earlier = false;
  JointVector last_q, earlier_q;
  double last_t = 0.0, earlier_t = 0.0;
  std::size_t k = 0;
  for (std::size_t i = 0; k + 1 < std::min(to, s.time.size()); ++i) {
    const std::size_t next = std::min(k + pattern[i % pattern.size()], s.time.size() - 1);
    const double t = s.time[k];
    JointVector v = JointVector::Zero(kDof);
    if (has_earlier) {
      v = parabolaSlope(s.q[k], t, last_q, last_t, earlier_q, earlier_t);
    } else if (has_last) {
      v = (s.q[k] - last_q) / (t - last_t);
    }
    const JointVector ref = reference(s.q[k], v, t);
    plant.setReference(ref, v);
    plant.advance(t + (s.time[next] - t));
    record.q_link.push_back(values(plant.linkPositions()));
    record.q_ref.push_back(values(ref));
    record.sample.push_back(next);
    has_earlier = has_last;
    earlier_q = last_q;
    earlier_t = last_t;
    has_last = true;
    last_q = s.q[k];
    last_t = t;
    k = next;
  }
  return record;
}

// RMS of the tool's Z deviation from the planned spiral (the paper's measure), from the FMU's tool output.
double rmsZError(Master& m, const Record& record) {
  const std::size_t tool_z = std::find(m.md.outputs.begin(), m.md.outputs.end(), m.vr("tool_z")) - m.md.outputs.begin();
  double sum = 0.0;
  for (std::size_t i = 0; i < record.outputs.size(); ++i) {
    const double e = record.outputs[i][tool_z] - spiral().tool[record.sample[i]].z();
    sum += e * e;
  }
  return std::sqrt(sum / static_cast<double>(record.outputs.size()));
}

class FmuTest : public ::testing::TestWithParam<int> {};

// ---- The spiral through the FMU ------------------------------------------------------------------------

TEST_P(FmuTest, DescribesItselfAndExportsTheStandardVersion) {
  if (GetParam() == 2) {
    EXPECT_STREQ(fmi2().fmi2GetVersion(), "2.0");
    EXPECT_STREQ(fmi2().fmi2GetTypesPlatform(), "default");
  } else {
    EXPECT_STREQ(fmi3().fmi3GetVersion(), "3.0");
  }
  const ModelDescription md = readModelDescription(GetParam(), unzipped(GetParam()));
  EXPECT_EQ(md.outputs.size(), 51u);
  // 5 scalars, 3 x 6 desired inputs, 6 wrench inputs, 51 outputs, the 20 effect parameters of the shipped file
  // twice (plant and compensator), 8 x 6 drive parameters and 14 integrator and watchdog options.
  EXPECT_EQ(md.vr.size(), 5u + 18u + 6u + 51u + 40u + 48u + 14u);
  EXPECT_FALSE(md.token.empty());
}

TEST_P(FmuTest, SpiralAt1msMatchesThePlantAndCompensatorRunDirectlyBitForBit) {
  const JointErrorModel truth = truthModel();
  for (long mode : {0L, 1L, 2L}) {
    auto m = makeMaster(GetParam());
    start(*m, mode, &truth);
    const Record fmu = run(*m, 0, spiral().time.size(), false);
    const Record direct = runDirectly(mode, truth, spiral().time.size(), false);
    ASSERT_EQ(fmu.q_link.size(), direct.q_link.size());
    ASSERT_EQ(fmu.q_link.size() + 1, spiral().time.size());
    std::size_t differing = 0;
    for (std::size_t i = 0; i < fmu.q_link.size(); ++i) {
      if (fmu.q_link[i] != direct.q_link[i] || fmu.q_ref[i] != direct.q_ref[i]) ++differing;
    }
    EXPECT_EQ(differing, 0u) << "mode " << mode;
    m->freeInstance();
  }
}

#ifdef JOINTCOMP_TEST_WITH_CAPI
// The regression of plant against corrected plant, through the FMU and through the C API with the same
// robot and parameter files: the same numbers, bit for bit (none and stiffness + kinematic correction).
TEST_P(FmuTest, RegressionThroughTheFmuEqualsTheCApi) {
  const std::string resources = unzipped(2) + "/resources/";
  jc_robot* robot = nullptr;
  ASSERT_EQ(jc_robot_load((resources + "rx170.urdf").c_str(), (resources + "parameters.json").c_str(), &robot), JC_OK)
      << jc_last_error();
  const std::size_t end = 3000;
  for (long mode : {0L, 2L}) {
    auto m = makeMaster(GetParam());
    start(*m, mode);
    const Record fmu = run(*m, 0, end, false);
    m->freeInstance();
    ASSERT_EQ(fmu.q_link.size(), end - 1);
    ASSERT_EQ(fmu.q_ref.size(), end - 1);

    // The FMU's default options (fmuPlantOptions()) by name.
    jc_plant* plant = nullptr;
    ASSERT_EQ(jc_plant_create_with_options(robot, "{\"step_past_updates_s\": 0.01}", &plant), JC_OK) << jc_last_error();
    ASSERT_EQ(fmuPlantOptions().step_past_updates_s, 0.01);
    const Spiral& s = spiral();
    auto reference = [&](const JointVector& q, const JointVector& v) {
      JointVector ref = q;
      if (mode == 2) {
        int32_t iterations = 0;
        EXPECT_EQ(jc_compensate_point(robot, nullptr, q.data(), kDof, v.data(), kDof, ref.data(), kDof, &iterations),
                  JC_OK)
            << jc_last_error();
      }
      return ref;
    };
    const JointVector start_reference = reference(s.q[0], JointVector::Zero(kDof));
    ASSERT_EQ(jc_plant_reset(plant, start_reference.data(), kDof, s.time[0]), JC_OK) << jc_last_error();
    std::size_t differing = 0;
    JointVector last_q = s.q[0];
    for (std::size_t k = 0; k + 1 < end; ++k) {
      const double t = s.time[k];
      JointVector v = JointVector::Zero(kDof);
      if (k > 1) {
        v = parabolaSlope(s.q[k], t, s.q[k - 1], s.time[k - 1], s.q[k - 2], s.time[k - 2]);
      } else if (k > 0) {
        v = (s.q[k] - last_q) / (t - s.time[k - 1]);
      }
      const JointVector ref = reference(s.q[k], v);
      ASSERT_EQ(jc_plant_set_reference(plant, ref.data(), kDof, v.data(), kDof), JC_OK) << jc_last_error();
      ASSERT_EQ(jc_plant_advance(plant, s.time[k + 1]), JC_OK) << jc_last_error();
      JointVector link(kDof);
      ASSERT_EQ(jc_plant_link_positions(plant, link.data(), kDof), JC_OK);
      if (values(link) != fmu.q_link[k] || values(ref) != fmu.q_ref[k]) ++differing;
      last_q = s.q[k];
    }
    EXPECT_EQ(differing, 0u) << "mode " << mode;
    jc_plant_free(plant);
  }
  jc_robot_free(robot);
}
#endif

TEST_P(FmuTest, VaryingCommunicationStepsMatchTheDirectRunBitForBit) {
  const JointErrorModel truth = truthModel();
  auto m = makeMaster(GetParam());
  start(*m, 2, &truth);
  const std::size_t end = 8000;
  const Record fmu = run(*m, 0, end, true);
  const Record direct = runDirectly(2, truth, end, true);
  ASSERT_EQ(fmu.q_link.size(), direct.q_link.size());
  EXPECT_GT(fmu.q_link.size(), 2000u);
  for (std::size_t i = 0; i < fmu.q_link.size(); ++i) {
    ASSERT_EQ(fmu.q_link[i], direct.q_link[i]) << "step " << i;
    ASSERT_EQ(fmu.q_ref[i], direct.q_ref[i]) << "step " << i;
  }
}

// An integrator option through the FMU against the plant: the FMU's run (started by `start_fmu`) must be the
// plant's with `options` bit for bit; returned: how many steps and how far (worst link, rad) it ends from the
// plant with the `baseline` options, to show that the option reached the plant and what it costs.
struct OptionEffect {
  std::size_t steps = 0, differing = 0;
  double largest = 0.0;
};
OptionEffect throughTheFmuAsThePlant(Master& m, const JointErrorModel& truth, const PlantOptions& options,
                                     std::size_t end, bool varying, const PlantOptions& baseline = fmuPlantOptions()) {
  const Record fmu = run(m, 0, end, varying);
  const Record direct = runDirectly(2, truth, end, varying, options);
  const Record defaults = runDirectly(2, truth, end, varying, baseline);
  OptionEffect effect;
  EXPECT_EQ(fmu.q_link.size(), direct.q_link.size());
  EXPECT_EQ(fmu.q_link.size(), defaults.q_link.size());
  effect.steps = std::min({fmu.q_link.size(), direct.q_link.size(), defaults.q_link.size()});
  for (std::size_t i = 0; i < effect.steps; ++i) {
    EXPECT_EQ(fmu.q_link[i], direct.q_link[i]) << "step " << i;
    EXPECT_EQ(fmu.q_ref[i], direct.q_ref[i]) << "step " << i;
    if (fmu.q_link[i] != defaults.q_link[i]) ++effect.differing;
    for (int j = 0; j < kDof; ++j) {
      effect.largest = std::max(effect.largest, std::abs(fmu.q_link[i][j] - defaults.q_link[i][j]));
    }
  }
  return effect;
}

// integrator.even_steps reaches the plant: switched off, the FMU takes CVODE's own steps, the plant's with
// PlantOptions::even_steps off bit for bit, and on steps of up to 5 ms those are other steps than the
// default's (the ending in two equal steps), which end within the tolerance's reach of them (two relative
// tolerances on angles near 1 rad: the two step sequences' errors do not cancel; 1.04 urad measured).
TEST_P(FmuTest, EvenStepsOffIsThePlantsOwnStepsBitForBit) {
  const JointErrorModel truth = truthModel();
  auto m = makeMaster(GetParam());
  start(*m, 2, &truth, false);
  PlantOptions uneven = fmuPlantOptions();
  uneven.even_steps = false;
  const OptionEffect effect = throughTheFmuAsThePlant(*m, truth, uneven, 3000, true);
  EXPECT_GT(effect.differing, effect.steps / 2);
  EXPECT_LT(effect.largest, 2.0 * fmuPlantOptions().relative_tolerance);
  EXPECT_EQ(m->terminate(), kOK);
}

// By default (integrator.step_past_updates = 0.01 s) at 1 ms steps CVODE steps through several
// communication points; the FMU is the plant with fmuPlantOptions() bit for bit, its links stay within a few
// microradians of the run that stops at every point (the smooth spiral's new inputs stay within the departure
// tolerance, so they take over from CVODE's next step), and a state saved mid-run continues identically.
TEST_P(FmuTest, SteppingPastCommunicationPointsIsThePlantsAndStaysNearTheStoppingRun) {
  const JointErrorModel truth = truthModel();
  auto m = makeMaster(GetParam());
  start(*m, 2, &truth);
  const std::size_t end = 6000;
  ASSERT_GT(fmuPlantOptions().step_past_updates_s, 0.0);
  const OptionEffect effect = throughTheFmuAsThePlant(*m, truth, fmuPlantOptions(), end, false, PlantOptions{});
  EXPECT_LT(effect.largest, 5e-6);
  EXPECT_GT(effect.largest, 0.0) << "the default steps past the communication points";

  void* state = nullptr;
  ASSERT_EQ(m->getState(&state), kOK);
  const Record first = run(*m, end - 1, end + 800, false);
  ASSERT_EQ(m->setState(state), kOK) << m->log();
  const Record again = run(*m, end - 1, end + 800, false);
  ASSERT_FALSE(first.outputs.empty());
  EXPECT_EQ(first.outputs, again.outputs);
  EXPECT_EQ(m->freeState(&state), kOK);
  EXPECT_EQ(m->terminate(), kOK);
}

// The FMU's default steps past communication points, yet a master's correction is not delayed: inputs that
// jump by 2 mrad on joint 2 at a communication point restart CVODE there (their reference departs from the one
// CVODE integrated ahead by far more than integrator.step_past_tolerance), and the links follow the run that
// stops at every point within microradians. With the check switched off (a tolerance of 10 rad) the same jump
// lands up to a CVODE step late and the links lag by far more.
TEST_P(FmuTest, AJumpOfTheInputsTakesEffectAtItsCommunicationPoint) {
  const Spiral& s = spiral();
  constexpr std::size_t kJumpAt = 1500, kEnd = 1800;
  // Negative: the FMU's default (start()).
  auto links = [&](double step_past, double tolerance) {
    auto m = makeMaster(GetParam());
    std::vector<std::vector<double>> record;
    start(*m, 2, nullptr, true, step_past, tolerance);
    const auto q_desired = m->vrs("q_desired_", kDof);
    const auto q_link = m->vrs("q_link_", kDof);
    for (std::size_t k = 0; k + 1 < kEnd; ++k) {
      std::vector<double> q = values(s.q[k]);
      if (k >= kJumpAt) q[1] += 2e-3;
      EXPECT_EQ(m->setReals(q_desired, q), kOK);
      if (m->doStep(s.time[k], s.time[k + 1] - s.time[k]) != kOK) {
        ADD_FAILURE() << "step at t = " << s.time[k] << "\n" << m->log();
        break;
      }
      std::vector<double> link;
      EXPECT_EQ(m->getReals(q_link, link), kOK);
      record.push_back(link);
    }
    EXPECT_EQ(m->terminate(), kOK);
    return record;
  };
  const auto largest = [](const std::vector<std::vector<double>>& a, const std::vector<std::vector<double>>& b) {
    double worst = 0.0;
    for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
      for (std::size_t j = 0; j < a[i].size(); ++j) worst = std::max(worst, std::abs(a[i][j] - b[i][j]));
    }
    return worst;
  };
  const auto stopping = links(0.0, -1.0);
  const auto by_default = links(-1.0, -1.0);
  const auto unchecked = links(-1.0, 10.0);
  ASSERT_EQ(by_default.size(), kEnd - 1);
  const double on_time = largest(stopping, by_default);
  const double late = largest(stopping, unchecked);
  EXPECT_LT(on_time, 5e-6);
  EXPECT_GT(late, 10.0 * on_time) << "late " << late << " rad, on time " << on_time << " rad";
}

// integrator.step_past_updates = 0: CVODE stops at every communication point, the library's default plant bit
// for bit; and integrator.step_past_tolerance reaches the plant (0 rad: every changed input restarts CVODE at
// its communication point, which is the stopping run within two relative tolerances on angles near 1 rad:
// each restart starts from the state interpolated at the point; 1.16 urad measured).
TEST_P(FmuTest, StoppingAtEveryCommunicationPointIsTheLibrarysDefaultPlant) {
  const JointErrorModel truth = truthModel();
  {
    auto m = makeMaster(GetParam());
    start(*m, 2, &truth, true, 0.0);
    const OptionEffect effect = throughTheFmuAsThePlant(*m, truth, PlantOptions{}, 3000, true);
    EXPECT_GT(effect.differing, 0u) << "stopping is not the FMU's default";
    EXPECT_EQ(m->terminate(), kOK);
  }
  auto m = makeMaster(GetParam());
  start(*m, 2, &truth, true, -1.0, 0.0);
  PlantOptions restarting = fmuPlantOptions();
  restarting.step_past_tolerance_rad = 0.0;
  const OptionEffect effect = throughTheFmuAsThePlant(*m, truth, restarting, 1500, false, PlantOptions{});
  EXPECT_LT(effect.largest, 2.0 * fmuPlantOptions().relative_tolerance);
  EXPECT_EQ(m->terminate(), kOK);
}

TEST(FmuRegression, CompensationThroughTheFmuReducesThePaperErrorAndBothVersionsAgree) {
  // The paper's Table II through the FMU: none, stiffness, stiffness and kinematic correction against a
  // robot whose parameters differ from the compensator's.
  const JointErrorModel truth = truthModel();
  double rms[3];
  Record fmi2_record;
  for (long mode : {0L, 1L, 2L}) {
    Master2 m;
    start(m, mode, &truth);
    const Record record = run(m, 0, spiral().time.size(), false);
    rms[mode] = rmsZError(m, record);
    if (mode == 2) fmi2_record = record;
  }
  std::printf("RMS Z error through the FMU [mm]: none %.4f, stiffness %.4f, stiffness and kinematic %.4f\n",
              rms[0] * 1e3, rms[1] * 1e3, rms[2] * 1e3);
  EXPECT_LT(rms[1], rms[0]);
  EXPECT_LT(rms[2], rms[1]);
  EXPECT_LT(rms[2], 0.5 * rms[0]);
  Master3 m3;
  start(m3, 2, &truth);
  const Record fmi3_record = run(m3, 0, spiral().time.size(), false);
  EXPECT_EQ(fmi3_record.outputs, fmi2_record.outputs);  // one instance code, two APIs
}

TEST_P(FmuTest, OutputsAreConsistentWithTheModel) {
  auto m = makeMaster(GetParam());
  start(*m, 2);
  std::vector<double> q_link, q_motor, tool, dq_actual, dq_predicted, q_ref;
  ASSERT_EQ(m->getReals(m->vrs("q_link_", kDof), q_link), kOK);
  ASSERT_EQ(m->getReals(m->vrs("q_motor_", kDof), q_motor), kOK);
  ASSERT_EQ(m->getReals({m->vr("tool_x"), m->vr("tool_y"), m->vr("tool_z")}, tool), kOK);
  ASSERT_EQ(m->getReals(m->vrs("dq_actual_", kDof), dq_actual), kOK);
  ASSERT_EQ(m->getReals(m->vrs("dq_predicted_", kDof), dq_predicted), kOK);
  ASSERT_EQ(m->getReals(m->vrs("q_ref_", kDof), q_ref), kOK);
  // At rest in static equilibrium, with the plant's truth the nominal model: prediction = actual error.
  for (int j = 0; j < kDof; ++j) {
    EXPECT_EQ(dq_actual[j], q_link[j] - q_motor[j]);
    EXPECT_NEAR(dq_predicted[j], dq_actual[j], 1e-9) << "joint " << j + 1;
    EXPECT_NEAR(q_motor[j], q_ref[j], 1e-9);  // the motors start at the command
  }
  // The compensated command brings the links to the desired positions.
  for (int j = 0; j < kDof; ++j) EXPECT_NEAR(q_link[j], spiral().q[0][j], 1e-9) << "joint " << j + 1;
  RobotWorkspace ws(*spiral().robot);
  JointVector q(kDof);
  for (int j = 0; j < kDof; ++j) q[j] = q_link[j];
  // The tool output is toolPosition's, and that is forwardKinematics' to rounding.
  const Eigen::Vector3d tool_position = toolPosition(*spiral().robot, q);
  forwardKinematics(*spiral().robot, ws, q);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(tool[k], tool_position[k]);
    EXPECT_NEAR(tool[k], ws.tool_pose.translation()[k], 1e-14);
  }
  // q_ref follows the inputs at once (direct feed-through), the plant's outputs do not.
  std::vector<double> moved = values(spiral().q[0]);
  moved[0] += 0.01;
  ASSERT_EQ(m->setReals(m->vrs("q_desired_", kDof), moved), kOK);
  std::vector<double> q_ref_after, q_link_after;
  ASSERT_EQ(m->getReals(m->vrs("q_ref_", kDof), q_ref_after), kOK);
  ASSERT_EQ(m->getReals(m->vrs("q_link_", kDof), q_link_after), kOK);
  EXPECT_NEAR(q_ref_after[0] - q_ref[0], 0.01, 1e-4);
  EXPECT_EQ(q_link_after, q_link);
  // Switching the compensation off (tunable) changes the command to the plan.
  ASSERT_EQ(m->setEnumeration(m->vr("compensation"), 0), kOK);
  ASSERT_EQ(m->getReals(m->vrs("q_ref_", kDof), q_ref_after), kOK);
  EXPECT_EQ(q_ref_after, moved);
  long mode = -1;
  ASSERT_EQ(m->getEnumeration(m->vr("compensation"), mode), kOK);
  EXPECT_EQ(mode, 0);
}

// ---- FMU state -----------------------------------------------------------------------------------------

TEST_P(FmuTest, RestoringAStateMidRunContinuesIdentically) {
  auto m = makeMaster(GetParam());
  start(*m, 2);
  const Spiral& s = spiral();
  const std::size_t mid = 3000, end = 4500;
  run(*m, 0, mid, false);
  void* state = nullptr;
  ASSERT_EQ(m->getState(&state), kOK);
  ASSERT_NE(state, nullptr);
  const Record first = run(*m, mid - 1, end, true);
  ASSERT_EQ(m->setState(state), kOK) << m->log();
  const Record again = run(*m, mid - 1, end, true);
  ASSERT_FALSE(first.outputs.empty());
  EXPECT_EQ(first.outputs, again.outputs);

  // Serialised and read back into another instance: the same continuation there.
  std::vector<unsigned char> bytes;
  ASSERT_EQ(m->serialize(state, bytes), kOK);
  auto other = makeMaster(GetParam());
  ASSERT_TRUE(other->instantiate("other"));
  void* copy = nullptr;
  ASSERT_EQ(other->deserialize(bytes, &copy), kOK) << other->log();
  ASSERT_EQ(other->setState(copy), kOK) << other->log();
  const Record elsewhere = run(*other, mid - 1, end, true);
  EXPECT_EQ(first.outputs, elsewhere.outputs);
  // A state can be overwritten in place (FMI 2: a non-null *FMUstate), and freed once.
  ASSERT_EQ(m->getState(&state), kOK);
  EXPECT_EQ(m->freeState(&state), kOK);
  EXPECT_EQ(state, nullptr);
  EXPECT_EQ(other->freeState(&copy), kOK);
  (void)s;
}

TEST_P(FmuTest, CorruptOrForeignStatesAreRefused) {
  auto m = makeMaster(GetParam());
  start(*m, 1);
  ASSERT_EQ(m->doStep(spiral().time[0], 0.001), kOK);
  void* state = nullptr;
  ASSERT_EQ(m->getState(&state), kOK);
  std::vector<unsigned char> bytes;
  ASSERT_EQ(m->serialize(state, bytes), kOK);
  void* copy = nullptr;
  auto expect_refused = [&](std::vector<unsigned char> broken, const char* fragment) {
    m->messages.clear();
    EXPECT_EQ(m->deserialize(broken, &copy), kError) << fragment;
    EXPECT_EQ(copy, nullptr);
    EXPECT_TRUE(m->logged(fragment)) << m->log();
  };
  std::vector<unsigned char> flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x10;
  expect_refused(flipped, "checksum");
  expect_refused(std::vector<unsigned char>(bytes.begin(), bytes.begin() + bytes.size() / 2), "says it has");
  expect_refused(std::vector<unsigned char>(bytes.begin(), bytes.begin() + 3), "ends inside");
  expect_refused(std::vector<unsigned char>(200, 0x5a), "magic");
  EXPECT_EQ(m->deserialize(std::vector<unsigned char>(), &copy), kError);
  // Pointers that are not this instance's states are refused without being followed.
  double not_a_state[64] = {};
  m->messages.clear();
  EXPECT_EQ(m->setState(not_a_state), kError);
  EXPECT_TRUE(m->logged("not a state of this instance")) << m->log();
  void* foreign = not_a_state;
  EXPECT_EQ(m->freeState(&foreign), kError);
  EXPECT_EQ(m->setState(nullptr), kError);
  EXPECT_EQ(m->getState(nullptr), kError);
  auto other = makeMaster(GetParam());
  ASSERT_TRUE(other->instantiate("other"));
  EXPECT_EQ(other->setState(state), kError);  // a state belongs to the instance that made it
  std::vector<unsigned char> short_buffer(bytes.size() - 1);
  if (GetParam() == 2) {
    EXPECT_EQ(fmi2().fmi2SerializeFMUstate(m->handle(), state, reinterpret_cast<fmi2Byte*>(short_buffer.data()),
                                           short_buffer.size()),
              kError);
  } else {
    EXPECT_EQ(fmi3().fmi3SerializeFMUState(m->handle(), state, short_buffer.data(), short_buffer.size()), kError);
  }
  EXPECT_EQ(m->freeState(&state), kOK);
  // The instance is still fine.
  EXPECT_EQ(m->doStep(spiral().time[0] + 0.001, 0.001), kOK) << m->log();
}

// ---- Two instances at once -----------------------------------------------------------------------------

TEST_P(FmuTest, TwoInstancesInTwoThreadsGiveTheSingleThreadedNumbers) {
  const std::size_t end = 2500;
  auto alone = makeMaster(GetParam());
  start(*alone, 2);
  const Record reference = run(*alone, 0, end, false);
  alone->freeInstance();
  Record results[2];
  auto worker = [&](int i) {
    auto m = makeMaster(GetParam());
    start(*m, 2);
    results[i] = run(*m, 0, end, false);
  };
  std::thread a(worker, 0), b(worker, 1);
  a.join();
  b.join();
  EXPECT_EQ(results[0].outputs, reference.outputs);
  EXPECT_EQ(results[1].outputs, reference.outputs);
  EXPECT_EQ(results[0].outputs.size() + 1, end);
}

INSTANTIATE_TEST_SUITE_P(Fmi, FmuTest, ::testing::Values(2, 3), [](const ::testing::TestParamInfo<int>& param) {
  return "fmi" + std::to_string(param.param);
});

}  // namespace
}  // namespace jointcomp
