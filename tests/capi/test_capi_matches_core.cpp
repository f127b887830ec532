// The C API returns what the C++ core computes, bit for bit: the same calls made on the core directly and
// through libjointcomp.so, compared with == on every double (memcmp, so that even NaN or -0 would count).
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <jointcomp/jointcomp.h>
#include <unistd.h>

#include "model/experiment/campaign_simulation.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "model/identify/calibration_report.hpp"
#include "model/identify/discovery.hpp"
#include "model/identify/identification_report.hpp"
#include "model/identify/kinematic_calibration.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/inverse_kinematics.hpp"
#include "model/robot/kinematics.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp {
namespace {

const std::string kUrdf = std::string(JOINTCOMP_DATA_DIR) + "/robots/rx170.urdf";
const std::string kParameters = std::string(JOINTCOMP_DATA_DIR) + "/params/rx170.json";
constexpr double kDegree = 3.14159265358979323846 / 180.0;

bool sameBits(const double* a, const double* b, std::size_t count) {
  return std::memcmp(a, b, count * sizeof(double)) == 0;
}

std::vector<double> flatten(const std::vector<JointVector>& rows) {
  std::vector<double> flat;
  for (const JointVector& row : rows) flat.insert(flat.end(), row.data(), row.data() + row.size());
  return flat;
}

std::vector<double> flatten(const std::vector<Eigen::Vector3d>& rows) {
  std::vector<double> flat;
  for (const Eigen::Vector3d& row : rows) flat.insert(flat.end(), row.data(), row.data() + 3);
  return flat;
}

std::vector<double> rowMajor(const Eigen::MatrixXd& matrix) {
  std::vector<double> flat;
  for (int r = 0; r < matrix.rows(); ++r) {
    for (int c = 0; c < matrix.cols(); ++c) flat.push_back(matrix(r, c));
  }
  return flat;
}

class CapiMatchesCore : public ::testing::Test {
protected:
  void SetUp() override {
    ASSERT_EQ(jc_robot_load(kUrdf.c_str(), kParameters.c_str(), &handle_), JC_OK) << jc_last_error();
    robot_ = std::make_shared<const Robot>(loadRobotFromUrdfFile(kUrdf));
    model_ = std::make_unique<JointErrorModel>(loadParameterFile(kParameters, robot_));
    drives_ = loadDriveParameters(kParameters, *robot_);
  }
  void TearDown() override { EXPECT_EQ(jc_robot_free(handle_), JC_OK); }

  std::vector<JointVector> postures() const {
    std::vector<JointVector> result;
    for (int k = 0; k < 5; ++k) {
      JointVector q(6);
      q << (-20 + 10 * k) * kDegree, (40 + 7 * k) * kDegree, (50 + 9 * k) * kDegree, (15 - 8 * k) * kDegree,
          (30 + 5 * k) * kDegree, (-40 + 20 * k) * kDegree;
      result.push_back(q);
    }
    return result;
  }

  jc_robot* handle_ = nullptr;
  std::shared_ptr<const Robot> robot_;
  std::unique_ptr<JointErrorModel> model_;
  std::vector<DriveParameters> drives_;
};

TEST_F(CapiMatchesCore, KinematicsAndGravity) {
  RobotWorkspace ws(*robot_);
  InverseKinematics ik(*robot_);
  for (const JointVector& q : postures()) {
    forwardKinematics(*robot_, ws, q);
    const std::vector<double> pose = rowMajor(ws.tool_pose.matrix());
    double api_pose[16];
    ASSERT_EQ(jc_forward_kinematics(handle_, q.data(), 6, api_pose, 16), JC_OK) << jc_last_error();
    EXPECT_TRUE(sameBits(pose.data(), api_pose, 16));

    Jacobian jacobian(6, 6);
    toolJacobian(*robot_, ws, jacobian);
    const std::vector<double> expected_jacobian = rowMajor(jacobian);
    double api_jacobian[36];
    ASSERT_EQ(jc_jacobian(handle_, q.data(), 6, api_jacobian, 36), JC_OK) << jc_last_error();
    EXPECT_TRUE(sameBits(expected_jacobian.data(), api_jacobian, 36));

    JointVector tau;
    gravityTorques(*robot_, ws, q, tau);
    double api_tau[6];
    ASSERT_EQ(jc_gravity_torques(handle_, q.data(), 6, api_tau, 6), JC_OK) << jc_last_error();
    EXPECT_TRUE(sameBits(tau.data(), api_tau, 6));

    // Inverse kinematics from a seed a little away from the posture.
    const JointVector seed = q + JointVector::Constant(6, 0.05);
    const IkSolution solution = ik.solve(ws.tool_pose, seed);
    double api_q[6];
    int32_t singular = -1;
    ASSERT_EQ(jc_inverse_kinematics(handle_, pose.data(), 16, seed.data(), 6, api_q, 6, &singular), JC_OK)
        << jc_last_error();
    EXPECT_TRUE(sameBits(solution.q.data(), api_q, 6));
    EXPECT_EQ(singular, solution.singular ? 1 : 0);

    std::array<IkSolution, 8> all;
    const int count = ik.allSolutions(ws.tool_pose, seed, all);
    double api_all[48];
    int32_t api_count = 0;
    ASSERT_EQ(jc_inverse_kinematics_all(handle_, pose.data(), 16, seed.data(), 6, api_all, 48, &api_count), JC_OK)
        << jc_last_error();
    ASSERT_EQ(api_count, count);
    for (int k = 0; k < count; ++k) EXPECT_TRUE(sameBits(all[k].q.data(), api_all + 6 * k, 6)) << "solution " << k;
  }
}

TEST_F(CapiMatchesCore, PredictionAndCompensation) {
  JointErrorWorkspace ws(*robot_);
  const JointVector velocity = (JointVector(6) << 0.1, -0.05, 0.02, 0.0, 0.3, -0.1).finished();
  const struct {
    const char* selection;
    EffectMask mask;
  } cases[] = {{nullptr, model_->allEffects()},
               {"", model_->loadsAnd({})},
               {"compliance", model_->loadsAnd({"compliance"})},
               {"compliance,transmission_error", model_->loadsAnd({"compliance", "transmission_error"})}};
  for (const auto& selection : cases) {
    const std::string label = selection.selection ? selection.selection : "NULL";
    for (const JointVector& q : postures()) {
      JointContext ctx(6);
      ctx.command = q;
      ctx.velocity = velocity;
      ASSERT_TRUE(settleStatically(*model_, selection.mask, ws, ctx).converged);
      const JointVector errors = ctx.q - ctx.command;
      double api_errors[6];
      ASSERT_EQ(jc_predict_joint_errors(handle_, selection.selection, q.data(), 6, velocity.data(), 6, api_errors, 6),
                JC_OK)
          << jc_last_error();
      EXPECT_TRUE(sameBits(errors.data(), api_errors, 6)) << label;

      Compensator compensator(*model_, selection.mask);
      JointContext planned(6);
      planned.q = q;
      planned.velocity = velocity;
      JointVector reference;
      const FixedPointReport report = compensator.compensate(planned, reference);
      double api_reference[6];
      int32_t iterations = 0;
      ASSERT_EQ(jc_compensate_point(handle_, selection.selection, q.data(), 6, velocity.data(), 6, api_reference, 6,
                                    &iterations),
                JC_OK)
          << jc_last_error();
      EXPECT_TRUE(sameBits(reference.data(), api_reference, 6)) << label;
      EXPECT_EQ(iterations, report.iterations);
    }
  }
}

TEST_F(CapiMatchesCore, ConditionsMatchTheContext) {
  const Eigen::Vector3d com(0.01, -0.02, 0.08);
  const Vector6 wrench = (Vector6() << 10.0, -20.0, -150.0, 1.0, 2.0, -3.0).finished();
  ASSERT_EQ(jc_robot_set_payload(handle_, 12.5, com.data(), 3), JC_OK);
  ASSERT_EQ(jc_robot_set_tool_wrench(handle_, wrench.data(), 6), JC_OK);
  const JointVector q = postures()[2];
  JointErrorWorkspace ws(*robot_);
  JointContext ctx(6);
  ctx.command = q;
  ctx.payload_mass = 12.5;
  ctx.payload_com = com;
  ctx.tool_wrench = wrench;
  ASSERT_TRUE(settleStatically(*model_, model_->allEffects(), ws, ctx).converged);
  const JointVector errors = ctx.q - ctx.command;
  double api_errors[6];
  ASSERT_EQ(jc_predict_joint_errors(handle_, nullptr, q.data(), 6, nullptr, 0, api_errors, 6), JC_OK);
  EXPECT_TRUE(sameBits(errors.data(), api_errors, 6));

  Compensator compensator(*model_, model_->allEffects());
  JointContext planned(6);
  planned.q = q;
  planned.payload_mass = 12.5;
  planned.payload_com = com;
  planned.tool_wrench = wrench;
  JointVector reference;
  compensator.compensate(planned, reference);
  double api_reference[6];
  ASSERT_EQ(jc_compensate_point(handle_, nullptr, q.data(), 6, nullptr, 0, api_reference, 6, nullptr), JC_OK);
  EXPECT_TRUE(sameBits(reference.data(), api_reference, 6));
  double api_trajectory_reference[6];
  ASSERT_EQ(jc_compensate_trajectory(handle_, nullptr, q.data(), 6, nullptr, 0, api_trajectory_reference, 6, nullptr,
                                     nullptr),
            JC_OK);
  EXPECT_TRUE(sameBits(reference.data(), api_trajectory_reference, 6));
}

TEST_F(CapiMatchesCore, SpiralPlanTrajectoryCompensationAndExperiment) {
  SpiralExperimentSpec spec;
  const SpiralExperimentResult core = runSpiralExperiment(*model_, spec);
  const JointTrajectory& plan = core.planned;
  const int32_t m = static_cast<int32_t>(plan.size());
  int32_t api_m = 0;
  ASSERT_EQ(jc_spiral_sample_count(handle_, &api_m), JC_OK) << jc_last_error();
  ASSERT_EQ(api_m, m);
  std::vector<double> time(m), positions(3 * m), q(6 * m), qd(6 * m);
  ASSERT_EQ(jc_spiral_plan(handle_, time.data(), m, positions.data(), 3 * m, q.data(), 6 * m, qd.data(), 6 * m), JC_OK)
      << jc_last_error();
  EXPECT_TRUE(sameBits(plan.time.data(), time.data(), m));
  EXPECT_TRUE(sameBits(flatten(plan.tool_position).data(), positions.data(), 3 * m));
  EXPECT_TRUE(sameBits(flatten(plan.q).data(), q.data(), 6 * m));
  EXPECT_TRUE(sameBits(flatten(plan.qd).data(), qd.data(), 6 * m));

  std::vector<JointVector> references;
  const TrajectoryCompensationReport report = compensateTrajectory(
      *model_, model_->loadsAnd({"compliance", "transmission_error"}), plan.q, plan.qd, references);
  std::vector<double> api_references(6 * m);
  int32_t max_iterations = 0;
  double max_correction = 0.0;
  ASSERT_EQ(jc_compensate_trajectory(handle_, "compliance,transmission_error", q.data(), 6 * m, qd.data(), 6 * m,
                                     api_references.data(), 6 * m, &max_iterations, &max_correction),
            JC_OK)
      << jc_last_error();
  EXPECT_TRUE(sameBits(flatten(references).data(), api_references.data(), 6 * m));
  EXPECT_EQ(max_iterations, report.max_iterations);
  EXPECT_TRUE(sameBits(&report.max_correction, &max_correction, 1));
  // The experiment's own compensation of run 3 is the same trajectory.
  EXPECT_TRUE(sameBits(flatten(core.runs[2].reference).data(), api_references.data(), 6 * m));

  for (int use_plant = 0; use_plant <= 1; ++use_plant) {
    SpiralExperimentSpec run_spec;
    if (use_plant) run_spec.drives = drives_;
    const SpiralExperimentResult expected = use_plant ? runSpiralExperiment(*model_, run_spec) : core;
    double metrics[15];
    std::vector<double> errors(9 * m);
    ASSERT_EQ(jc_spiral_experiment(handle_, use_plant, metrics, 15, errors.data(), 9 * m), JC_OK) << jc_last_error();
    for (int r = 0; r < 3; ++r) {
      const AccuracyMetrics& run = expected.runs[r].metrics;
      const double values[5] = {run.ra, run.rz, run.rms, run.max, run.mean};
      EXPECT_TRUE(sameBits(values, metrics + 5 * r, 5)) << "run " << r << ", plant " << use_plant;
      EXPECT_TRUE(sameBits(flatten(expected.runs[r].error).data(), errors.data() + 3 * m * r, 3 * m));
    }
  }
}

// jc_plant_create_with_options: the options of options_json reach the plant, by the names of PlantOptions;
// its run is the core plant's with those options, bit for bit, and not the default plant's.
TEST_F(CapiMatchesCore, PlantWithOptionsIsTheCorePlantWithThem) {
  PlantOptions options;
  options.step_past_updates_s = 0.01;
  options.relative_tolerance = 1e-7;
  options.max_order = 2;
  options.even_steps = false;
  options.tracking_envelope_rad = 0.3;
  FlexibleJointPlant plant(*model_, drives_, options);
  jc_plant* api_plant = nullptr;
  jc_plant* api_default = nullptr;
  ASSERT_EQ(jc_plant_create_with_options(handle_,
                                         "{\"step_past_updates_s\": 0.01, \"relative_tolerance\": 1e-7, "
                                         "\"max_order\": 2, \"even_steps\": false, \"tracking_envelope_rad\": 0.3}",
                                         &api_plant),
            JC_OK)
      << jc_last_error();
  ASSERT_EQ(jc_plant_create_with_options(handle_, "{}", &api_default), JC_OK) << jc_last_error();
  const JointVector start = postures()[1];
  const JointVector velocity = (JointVector(6) << 0.05, -0.03, 0.04, 0.1, -0.1, 0.2).finished();
  plant.reset(start, 0.0);
  ASSERT_EQ(jc_plant_reset(api_plant, start.data(), 6, 0.0), JC_OK);
  ASSERT_EQ(jc_plant_reset(api_default, start.data(), 6, 0.0), JC_OK);
  int differing_from_default = 0;
  for (int k = 1; k <= 300; ++k) {
    const JointVector reference = start + velocity * (k * 0.001);
    plant.setReference(reference, velocity);
    plant.advance(k * 0.001);
    double values[6], defaults[6];
    for (jc_plant* api : {api_plant, api_default}) {
      ASSERT_EQ(jc_plant_set_reference(api, reference.data(), 6, velocity.data(), 6), JC_OK);
      ASSERT_EQ(jc_plant_advance(api, k * 0.001), JC_OK) << jc_last_error();
      ASSERT_EQ(jc_plant_link_positions(api, api == api_plant ? values : defaults, 6), JC_OK);
    }
    ASSERT_TRUE(sameBits(plant.linkPositions().data(), values, 6)) << "update " << k;
    if (!sameBits(values, defaults, 6)) ++differing_from_default;
  }
  int64_t counts[5];
  ASSERT_EQ(jc_plant_statistics(api_plant, counts, 5), JC_OK);
  EXPECT_EQ(counts[0], plant.statistics().steps);
  EXPECT_GT(differing_from_default, 150);
  EXPECT_EQ(jc_plant_free(api_plant), JC_OK);
  EXPECT_EQ(jc_plant_free(api_default), JC_OK);
}

TEST_F(CapiMatchesCore, PlantSteppingAndSnapshots) {
  FlexibleJointPlant plant(*model_, drives_);
  jc_plant* api_plant = nullptr;
  ASSERT_EQ(jc_plant_create(handle_, &api_plant), JC_OK) << jc_last_error();
  const JointVector start = postures()[1];
  const JointVector velocity = (JointVector(6) << 0.05, -0.03, 0.04, 0.1, -0.1, 0.2).finished();
  plant.reset(start, 0.5);
  ASSERT_EQ(jc_plant_reset(api_plant, start.data(), 6, 0.5), JC_OK);
  const Vector6 wrench = (Vector6() << 0, 0, -30, 0, 1, 0).finished();
  const Eigen::Vector3d com(0, 0, 0.1);
  plant.setToolWrench(wrench);
  plant.setPayload(4.0, com);
  ASSERT_EQ(jc_plant_set_tool_wrench(api_plant, wrench.data(), 6), JC_OK);
  ASSERT_EQ(jc_plant_set_payload(api_plant, 4.0, com.data(), 3), JC_OK);

  auto compare = [&](const char* when) {
    double values[6];
    ASSERT_EQ(jc_plant_link_positions(api_plant, values, 6), JC_OK);
    EXPECT_TRUE(sameBits(plant.linkPositions().data(), values, 6)) << when;
    ASSERT_EQ(jc_plant_link_velocities(api_plant, values, 6), JC_OK);
    EXPECT_TRUE(sameBits(plant.linkVelocities().data(), values, 6)) << when;
    ASSERT_EQ(jc_plant_motor_positions(api_plant, values, 6), JC_OK);
    EXPECT_TRUE(sameBits(plant.motorPositions().data(), values, 6)) << when;
    ASSERT_EQ(jc_plant_motor_velocities(api_plant, values, 6), JC_OK);
    EXPECT_TRUE(sameBits(plant.motorVelocities().data(), values, 6)) << when;
    ASSERT_EQ(jc_plant_motor_torques(api_plant, values, 6), JC_OK);
    EXPECT_TRUE(sameBits(plant.motorTorques().data(), values, 6)) << when;
    double time = 0.0;
    ASSERT_EQ(jc_plant_time(api_plant, &time), JC_OK);
    EXPECT_EQ(time, plant.time()) << when;
    int64_t counts[5];
    ASSERT_EQ(jc_plant_statistics(api_plant, counts, 5), JC_OK);
    const PlantStatistics statistics = plant.statistics();
    EXPECT_EQ(counts[0], statistics.steps) << when;
    EXPECT_EQ(counts[1], statistics.rhs_evaluations) << when;
    EXPECT_EQ(counts[2], statistics.jacobian_evaluations) << when;
    EXPECT_EQ(counts[3], statistics.error_test_failures) << when;
    EXPECT_EQ(counts[4], statistics.nonlinear_convergence_failures) << when;
  };
  const double period = 0.004;
  for (int k = 1; k <= 50; ++k) {
    const JointVector reference = start + velocity * (k * period);
    plant.setReference(reference, velocity);
    ASSERT_EQ(jc_plant_set_reference(api_plant, reference.data(), 6, velocity.data(), 6), JC_OK);
    plant.advance(0.5 + k * period);
    ASSERT_EQ(jc_plant_advance(api_plant, 0.5 + k * period), JC_OK) << jc_last_error();
  }
  compare("after 50 periods");

  // The whole state, read without disturbing either run.
  double api_state[30];
  ASSERT_EQ(jc_plant_state(api_plant, api_state, 30), JC_OK);
  EXPECT_TRUE(sameBits(plant.state(), api_state, 30));

  int32_t size = 0;
  ASSERT_EQ(jc_plant_snapshot_size(api_plant, &size), JC_OK);
  std::vector<double> snapshot(size);
  ASSERT_EQ(jc_plant_save(api_plant, snapshot.data(), size), JC_OK);
  const PlantState saved = plant.saveState();
  EXPECT_EQ(snapshot[2], saved.time);
  EXPECT_TRUE(sameBits(saved.y.data(), snapshot.data() + 3, 30));
  plant.advance(0.75);
  ASSERT_EQ(jc_plant_advance(api_plant, 0.75), JC_OK);
  compare("after 0.75 s");
  plant.restoreState(saved);
  ASSERT_EQ(jc_plant_restore(api_plant, snapshot.data(), size), JC_OK) << jc_last_error();
  plant.advance(0.8);
  ASSERT_EQ(jc_plant_advance(api_plant, 0.8), JC_OK);
  compare("after restoring and advancing to 0.8 s");
  EXPECT_EQ(jc_plant_free(api_plant), JC_OK);
}

TEST_F(CapiMatchesCore, MetricsAndParameters) {
  std::vector<Eigen::Vector3d> errors;
  std::vector<double> z;
  for (int k = 0; k < 100; ++k) {
    errors.emplace_back(1e-4 * std::sin(0.3 * k), 2e-4 * std::cos(0.1 * k), 1e-4 * std::sin(0.05 * k * k));
    z.push_back(errors.back().z());
  }
  const AccuracyMetrics expected = accuracyMetrics(errors);
  const double values[5] = {expected.ra, expected.rz, expected.rms, expected.max, expected.mean};
  double metrics[5];
  ASSERT_EQ(jc_accuracy_metrics(flatten(errors).data(), 300, metrics, 5), JC_OK);
  EXPECT_TRUE(sameBits(values, metrics, 5));
  double ra = 0.0, rz = 0.0;
  ASSERT_EQ(jc_average_absolute_deviation(z.data(), 100, &ra), JC_OK);
  ASSERT_EQ(jc_peak_to_peak_deviation(z.data(), 100, &rz), JC_OK);
  EXPECT_EQ(ra, averageAbsoluteDeviation(z));
  EXPECT_EQ(rz, peakToPeakDeviation(z));

  const std::string json = parametersToJson(*model_, drives_);
  int32_t length = 0;
  ASSERT_EQ(jc_robot_parameters_json(handle_, nullptr, 0, &length), JC_OK);
  std::string api_json(static_cast<std::size_t>(length) + 1, '\0');
  ASSERT_EQ(jc_robot_parameters_json(handle_, api_json.data(), length + 1, &length), JC_OK);
  api_json.resize(static_cast<std::size_t>(length));
  EXPECT_EQ(api_json, json);

  char name[32];
  ASSERT_EQ(jc_robot_name(handle_, name, 32, &length), JC_OK);
  EXPECT_EQ(std::string(name), robot_->name);
  double lower[6], upper[6];
  ASSERT_EQ(jc_robot_joint_limits(handle_, lower, 6, upper, 6), JC_OK);
  EXPECT_TRUE(sameBits(robot_->lowerLimits().data(), lower, 6));
  EXPECT_TRUE(sameBits(robot_->upperLimits().data(), upper, 6));
}

std::string textOf(jc_report* report, bool summary) {
  std::int32_t length = 0;
  auto read = summary ? jc_report_summary : jc_report_json;
  EXPECT_EQ(read(report, nullptr, 0, &length), JC_OK) << jc_last_error();
  std::string text(static_cast<std::size_t>(length) + 1, '\0');
  EXPECT_EQ(read(report, text.data(), length + 1, &length), JC_OK) << jc_last_error();
  text.resize(static_cast<std::size_t>(length));
  return text;
}

std::string parametersOf(jc_robot* robot) {
  std::int32_t length = 0;
  EXPECT_EQ(jc_robot_parameters_json(robot, nullptr, 0, &length), JC_OK) << jc_last_error();
  std::string text(static_cast<std::size_t>(length) + 1, '\0');
  EXPECT_EQ(jc_robot_parameters_json(robot, text.data(), length + 1, &length), JC_OK) << jc_last_error();
  text.resize(static_cast<std::size_t>(length));
  return text;
}

std::string scratchPath(const std::string& stem) {
  return ::testing::TempDir() + "jointcomp_matches_core_" + stem + "_" + std::to_string(::getpid()) + ".csv";
}

// Simulation, identification and calibration give through the library the files, parameters and reports
// the core gives.
TEST_F(CapiMatchesCore, SimulationIdentificationAndCalibration) {
  const std::string sweep_path = scratchPath("sweep");
  ASSERT_EQ(
      jc_simulate_campaign(handle_, R"({"protocol": "joint2-sweep", "seed": 9, "step_deg": 0.5})", sweep_path.c_str()),
      JC_OK)
      << jc_last_error();
  CampaignSimulationSpec spec = defaultCampaignSpec(CampaignProtocol::JointSweep);
  spec.seed = 9;
  spec.sweep.step_rad = 0.5 * kDegree;
  spec.metadata["truth"] = "rx170 (a jc_robot handle), through jc_simulate_campaign";
  const MeasurementCampaign sweep = simulateCampaign(*model_, spec);
  EXPECT_EQ(readTextFile(sweep_path, "campaign"), campaignToText(sweep));

  jc_robot* identified = nullptr;
  jc_report* report = nullptr;
  ASSERT_EQ(
      jc_identify_transmission_error(handle_, sweep_path.c_str(), R"({"orders": [1, 2, 3]})", &identified, &report),
      JC_OK)
      << jc_last_error();
  TransmissionIdentificationOptions options;
  options.candidate_orders = {1, 2, 3};
  // The library reads the campaign back from its file (millimetres and degrees in text): so does the core.
  const TransmissionIdentificationResult result =
      identifyTransmissionError(*model_, readCampaignFile(sweep_path), options);
  EXPECT_EQ(parametersOf(identified), parametersToJson(withIdentifiedHarmonics(*model_, result, sweep_path), drives_));
  ReportSources sources;
  sources.campaign = sweep_path;
  sources.parameters = "rx170 (a jc_robot handle)";
  sources.robot = "rx170";
  EXPECT_EQ(textOf(report, false), transmissionReportJson(result, sources, nullptr).dump(2));
  EXPECT_EQ(textOf(report, true), transmissionSummary(result, sources, nullptr));
  EXPECT_EQ(jc_report_free(report), JC_OK);
  EXPECT_EQ(jc_robot_free(identified), JC_OK);

  const std::string poses_path = scratchPath("poses");
  ASSERT_EQ(jc_simulate_campaign(handle_, R"({"protocol": "random", "seed": 10, "count": 60})", poses_path.c_str()),
            JC_OK)
      << jc_last_error();
  jc_robot* calibrated = nullptr;
  ASSERT_EQ(jc_calibrate(handle_, poses_path.c_str(), nullptr, R"({"loss": "none"})", &calibrated, nullptr), JC_OK)
      << jc_last_error();
  GeometricCalibrationOptions calibration;
  calibration.loss = RobustLoss::None;
  const MeasurementCampaign poses = readCampaignFile(poses_path);
  const CalibrationRun run = runCalibration(*model_, poses, {}, calibration);
  const CalibratedFrames frames = calibratedFrames(model_->robot(), poses, run.result.estimate);
  EXPECT_EQ(parametersOf(calibrated),
            parametersToJson(run.calibrated, drives_, &frames.tool, frames.base_frame ? &*frames.base_frame : nullptr));
  // The fitted target through the handle, bit for bit; the identity and "none" for a base-frame campaign.
  double target[3];
  double base_pose[16];
  int32_t has_target = 0;
  int32_t has_base_frame = 1;
  ASSERT_EQ(jc_robot_tool_target(calibrated, target, 3, &has_target), JC_OK) << jc_last_error();
  ASSERT_EQ(jc_robot_base_frame(calibrated, base_pose, 16, &has_base_frame), JC_OK) << jc_last_error();
  EXPECT_EQ(has_target, 1);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(target[k], run.result.estimate.target[k]);
  EXPECT_EQ(has_base_frame, poses.frame == MeasurementFrame::Instrument ? 1 : 0);
  EXPECT_EQ(jc_robot_tool_target(calibrated, target, 2, &has_target), JC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(jc_robot_base_frame(calibrated, base_pose, 16, nullptr), JC_ERROR_INVALID_ARGUMENT);
  ASSERT_EQ(jc_robot_tool_target(handle_, target, 3, &has_target), JC_OK);
  EXPECT_EQ(has_target, 0);  // a maker's parameter file has no target
  double pose_capi[16];
  ASSERT_EQ(jc_forward_kinematics(calibrated, postures()[1].data(), 6, pose_capi, 16), JC_OK);
  RobotWorkspace ws(*run.calibrated_robot);
  forwardKinematics(*run.calibrated_robot, ws, postures()[1]);
  const Eigen::Isometry3d pose_core = ws.tool_pose;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) EXPECT_EQ(pose_capi[r * 4 + c], pose_core.matrix()(r, c));
  }
  EXPECT_EQ(jc_robot_free(calibrated), JC_OK);

  jc_robot* extended = nullptr;
  ASSERT_EQ(
      jc_discover(handle_, poses_path.c_str(), nullptr, R"({"max_steps": 1, "types": ["offset"]})", &extended, nullptr),
      JC_OK)
      << jc_last_error();
  DiscoveryOptions discovery;
  discovery.base_geometry = true;  // the C API's default, as the command's
  discovery.max_steps = 1;
  discovery.types = {"offset"};
  const DiscoveryResult found = discoverEffects(*model_, {readCampaignFile(poses_path)}, {}, discovery);
  const CalibratedFrames found_frames = calibratedFrames(model_->robot(), poses, found.calibration.estimate);
  EXPECT_EQ(parametersOf(extended), parametersToJson(found.model, drives_, &found_frames.tool,
                                                     found_frames.base_frame ? &*found_frames.base_frame : nullptr));
  EXPECT_EQ(jc_robot_free(extended), JC_OK);

  // The geometry limits reach the fit: the fitted joint offsets (of the noise, a few microradians) lie
  // beyond a limit of 1e-12 deg, so that both calls are refused naming an offset; a limit that is not a
  // positive number is refused naming its key.
  jc_robot* refused = nullptr;
  EXPECT_EQ(jc_calibrate(handle_, poses_path.c_str(), nullptr, R"({"max_offset_deg": 1e-12})", &refused, nullptr),
            JC_ERROR_INVALID_ARGUMENT);
  EXPECT_THAT(jc_last_error(), ::testing::HasSubstr(".offset_rad: the joint's zero moves by"));
  EXPECT_EQ(refused, nullptr);
  EXPECT_EQ(jc_discover(handle_, poses_path.c_str(), nullptr, R"({"max_steps": 1, "max_offset_deg": 1e-12})", &refused,
                        nullptr),
            JC_ERROR_INVALID_ARGUMENT);
  EXPECT_THAT(jc_last_error(), ::testing::HasSubstr(".offset_rad: the joint's zero moves by"));
  EXPECT_EQ(jc_calibrate(handle_, poses_path.c_str(), nullptr, R"({"max_placement_turn_deg": -1})", &refused, nullptr),
            JC_ERROR_INVALID_ARGUMENT);
  EXPECT_THAT(jc_last_error(), ::testing::HasSubstr("max_placement_turn_deg"));
  std::remove(sweep_path.c_str());
  std::remove(poses_path.c_str());
}

}  // namespace
}  // namespace jointcomp
