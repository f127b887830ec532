// jc_spiral_job_*: the paper's spiral planned and compensated once with the nominal parameters, then
// followed by many truths (Monte Carlo draws, jointcomp.distributed): a draw costs its simulation only.
#include <algorithm>
#include <mutex>

#include <nlohmann/json.hpp>

#include "api_support.hpp"
#include "model/effects/perturbation.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "spiral_outputs.hpp"

using namespace jointcomp;
using namespace jointcomp::capi;

namespace {

// Where one of the truth's parameters goes: value k of effect `effect`, or component `component` of the
// geometry of joint `joint` (0: offset, 1-3: placement translation, 4-6: placement rotation).
struct ParameterSlot {
  int effect = -1;
  int index = 0;
  int joint = -1;
  int component = 0;
};

const char* const kGeometryNames[7] = {"offset_rad",       "placement_dx_m",   "placement_dy_m",  "placement_dz_m",
                                       "placement_rx_rad", "placement_ry_rad", "placement_rz_rad"};

}  // namespace

struct jc_spiral_job : HandleHeader {
  static constexpr HandleKind kKind = HandleKind::SpiralJob;
  jc_spiral_job(const jc_robot& nominal, bool use_plant)
      : model(nominal.model), drives(use_plant ? nominal.drives : std::vector<DriveParameters>{}) {
    spec.drives = drives;
    prepared = prepareSpiralRuns(model, spec);
    listParameters();
  }

  const JointErrorModel model;
  const std::vector<DriveParameters> drives;
  SpiralExperimentSpec spec;
  PreparedSpiral prepared;
  std::vector<ParameterSlot> slots;
  nlohmann::json parameters = nlohmann::json::array();  // name, nominal value and law of each slot
  mutable std::mutex draws_mutex;
  mutable std::vector<std::unique_ptr<SpiralDraw>> idle_draws;

  // The truth: the nominal model with every parameter replaced by `values` (in the order of `slots`).
  JointErrorModel truth(const double* values) const;

  // The memory of the draws under way: a run takes a SpiralDraw (a kept one when there is one) and gives it
  // back, so that a draw reuses the path's vectors of an earlier one instead of allocating them (and faulting
  // their pages in) again. As many are kept as runs were ever under way at once.
  std::unique_ptr<SpiralDraw> takeDraw() const {
    const std::lock_guard<std::mutex> lock(draws_mutex);
    if (idle_draws.empty()) return std::make_unique<SpiralDraw>();
    std::unique_ptr<SpiralDraw> draw = std::move(idle_draws.back());
    idle_draws.pop_back();
    return draw;
  }
  void keepDraw(std::unique_ptr<SpiralDraw> draw) const {
    const std::lock_guard<std::mutex> lock(draws_mutex);
    idle_draws.push_back(std::move(draw));
  }

private:
  void listParameters();
};

void jc_spiral_job::listParameters() {
  const PerturbationSpec perturbation;  // the main job's (jc_spiral_experiment's) law
  std::vector<std::string> effect_names;
  for (int i = 0; i < model.effectCount(); ++i) {
    const std::vector<std::string> names = model.effect(i).parameterNames();
    const std::vector<double> values = model.effect(i).parameters();
    for (std::size_t k = 0; k < names.size(); ++k) {
      const PerturbationLaw law = perturbationLaw(names[k], perturbation);
      slots.push_back({i, static_cast<int>(k), -1, 0});
      parameters.push_back(
          {{"name", names[k]}, {"value", values[k]}, {"law", {{"scale", law.scale}, {"relative", law.relative}}}});
      effect_names.push_back(names[k]);
    }
  }
  const Robot& robot = model.robot();
  for (int j = 0; j < robot.dof(); ++j) {
    for (int c = 0; c < 7; ++c) {
      const std::string name = robot.joints[static_cast<std::size_t>(j)].name + "." + kGeometryNames[c];
      if (std::find(effect_names.begin(), effect_names.end(), name) != effect_names.end()) continue;
      slots.push_back({-1, 0, j, c});
      parameters.push_back({{"name", name}, {"value", 0.0}, {"law", nullptr}});
    }
  }
}

JointErrorModel jc_spiral_job::truth(const double* values) const {
  std::vector<std::vector<double>> effect_values(static_cast<std::size_t>(model.effectCount()));
  for (int i = 0; i < model.effectCount(); ++i)
    effect_values[static_cast<std::size_t>(i)] = model.effect(i).parameters();
  const int n = model.robot().dof();
  std::vector<double> geometry(static_cast<std::size_t>(7 * n), 0.0);  // per joint: offset, d, r
  bool moved = false;
  for (std::size_t s = 0; s < slots.size(); ++s) {
    const ParameterSlot& slot = slots[s];
    if (slot.effect >= 0) {
      effect_values[static_cast<std::size_t>(slot.effect)][static_cast<std::size_t>(slot.index)] = values[s];
    } else {
      geometry[static_cast<std::size_t>(7 * slot.joint + slot.component)] = values[s];
      moved = moved || values[s] != 0.0;
    }
  }
  std::vector<std::unique_ptr<Effect>> effects;
  for (int i = 0; i < model.effectCount(); ++i) {
    std::unique_ptr<Effect> effect = model.effect(i).clone();
    try {
      effect->setParameters(effect_values[static_cast<std::size_t>(i)]);
    } catch (const ParameterError& error) {
      invalid(std::string("values: ") + error.what());
    }
    effects.push_back(std::move(effect));
  }
  if (!moved) return JointErrorModel(model.sharedRobot(), model.gears(), std::move(effects));
  auto robot = std::make_shared<Robot>(model.robot());
  for (int j = 0; j < n; ++j) {
    const double* d = &geometry[static_cast<std::size_t>(7 * j)];
    Joint& joint = robot->joints[static_cast<std::size_t>(j)];
    const Eigen::Vector3d rotation(d[4], d[5], d[6]);
    Eigen::Isometry3d correction = Eigen::Isometry3d::Identity();
    correction.translation() = Eigen::Vector3d(d[1], d[2], d[3]);
    if (rotation.norm() > 0.0) correction.linear() = Eigen::AngleAxisd(rotation.norm(), rotation.normalized()).matrix();
    joint.placement = joint.placement * correction * Eigen::Isometry3d(Eigen::AngleAxisd(d[0], joint.axis));
  }
  return JointErrorModel(robot, model.gears(), std::move(effects));
}

namespace {

jc_spiral_job& jobHandle(jc_spiral_job* job) { return useHandle(job, "job"); }

}  // namespace

extern "C" {

jc_status jc_spiral_job_create(jc_robot* nominal, int32_t use_plant, jc_spiral_job** job) {
  return CAPI_ENTRY({
    const jc_robot& model = robotHandle(nominal, "nominal");
    requirePointer(job, "job");
    if (use_plant != 0 && use_plant != 1) invalid("use_plant is " + std::to_string(use_plant) + ", must be 0 or 1");
    if (use_plant && model.drives.empty()) {
      invalid("use_plant is 1 but the parameters have no \"plant\" object (drives and controller gains)");
    }
    auto created = std::make_unique<jc_spiral_job>(model, use_plant == 1);
    if (static_cast<std::int64_t>(created->prepared.planned.size()) > INT32_MAX / 16) {
      invalid("the spiral has too many samples for int32_t lengths");
    }
    *job = publish(std::move(created));
  });
}

jc_status jc_spiral_job_free(jc_spiral_job* job) {
  return CAPI_ENTRY({ freeHandle(job, "job"); });
}

jc_status jc_spiral_job_sizes(jc_spiral_job* job, int32_t* samples, int32_t* parameters) {
  return CAPI_ENTRY({
    const jc_spiral_job& handle = jobHandle(job);
    requirePointer(samples, "samples");
    requirePointer(parameters, "parameters");
    *samples = static_cast<int32_t>(handle.prepared.planned.size());
    *parameters = static_cast<int32_t>(handle.slots.size());
  });
}

jc_status jc_spiral_job_time(jc_spiral_job* job, double* time, int32_t time_len) {
  return CAPI_ENTRY({
    const jc_spiral_job& handle = jobHandle(job);
    const std::vector<double>& planned = handle.prepared.planned.time;
    requireOutput(time, time_len, static_cast<std::int64_t>(planned.size()), "time", "the spiral's sample count");
    std::copy(planned.begin(), planned.end(), time);
  });
}

jc_status jc_spiral_job_parameters(jc_spiral_job* job, char* buffer, int32_t capacity, int32_t* length) {
  return CAPI_ENTRY({ copyText(jobHandle(job).parameters.dump(), buffer, capacity, length); });
}

jc_status jc_spiral_job_run(jc_spiral_job* job, const double* values, int32_t values_len, int64_t noise_seed,
                            double* metrics, int32_t metrics_len, double* errors, int32_t errors_len) {
  return CAPI_ENTRY({
    const jc_spiral_job& handle = jobHandle(job);
    requirePointer(values, "values");
    requireLength(values_len, static_cast<std::int64_t>(handle.slots.size()), "values",
                  "the job's parameters, jc_spiral_job_sizes");
    requireFinite(values, values_len, "values");
    if (noise_seed < 0) invalid("noise_seed is " + std::to_string(noise_seed) + ", must be >= 0");
    requireOutput(metrics, metrics_len, 15, "metrics", "3 runs x Ra, Rz, RMS, max, mean");
    const std::int64_t m = static_cast<std::int64_t>(handle.prepared.planned.size());
    const bool want_errors = optionalOutput(errors, errors_len, 9 * m, "errors", "3 runs x the spiral's samples x 3");
    const JointErrorModel truth = handle.truth(values);
    SpiralExperimentSpec spec = handle.spec;
    spec.noise_seed = static_cast<std::uint64_t>(noise_seed);
    std::unique_ptr<SpiralDraw> draw = handle.takeDraw();
    drawSpiralRuns(handle.prepared, truth, spec, *draw);  // a draw that throws is dropped with its memory
    writeSpiralRuns(*draw, m, metrics, want_errors ? errors : nullptr);
    handle.keepDraw(std::move(draw));
  });
}

}  // extern "C"
