// jc_identify_and_compensate: the paper's whole method on a caller-given truth (model/experiment/
// paper_identification.hpp): the identification campaigns measured on the truth, the stiffnesses and joint 2's
// transmission error identified, the spiral compensated with the identified model and followed by the truth.
// The same functions as `jointcomp paper`, so that both give the same numbers.
#include <cmath>
#include <memory>

#include "api_support.hpp"
#include "json_options.hpp"
#include "model/experiment/paper_identification.hpp"
#include "model/experiment/spiral_experiment.hpp"

using namespace jointcomp;
using namespace jointcomp::capi;

namespace {

constexpr double kPaperFeedRate = 0.03;  // m/s, as `jointcomp paper`
constexpr double kMinFeedRate = 0.003;
constexpr double kMaxFeedRate = 2.0;

struct MethodOptions {
  std::uint64_t seed = 2012;
  bool use_plant = false;
  bool dynamic_correction = false;
  double feed_rate = kPaperFeedRate;
};

MethodOptions readMethodOptions(const char* options_json, bool has_drives) {
  MethodOptions o;
  readOptions(options_json, [&](JsonFields& fields) {
    if (fields.has("seed")) {
      const double seed = fields.number("seed");
      if (seed < 0.0 || seed != std::floor(seed) || seed > 9.007199254740992e15)
        fields.fail("seed", "must be a whole number from 0 to 2^53");
      o.seed = static_cast<std::uint64_t>(seed);
    }
    o.use_plant = fields.flagOr("use_plant", false);
    o.dynamic_correction = fields.flagOr("dynamic_correction", false);
    if (fields.has("feed_rate_m_per_s")) {
      o.feed_rate = fields.number("feed_rate_m_per_s");
      if (!(o.feed_rate >= kMinFeedRate && o.feed_rate <= kMaxFeedRate))
        fields.fail("feed_rate_m_per_s", "must be from 0.003 to 2 m/s");
    }
    if (o.use_plant && !has_drives)
      fields.fail("use_plant", "needs drives: the truth's parameters have no \"plant\" object");
    if (o.dynamic_correction && !o.use_plant)
      fields.fail("dynamic_correction", "needs the plant (\"use_plant\": true)");
  });
  return o;
}

}  // namespace

extern "C" {

jc_status jc_identify_and_compensate(jc_robot* nominal, jc_robot* truth, const char* options_json, double* metrics,
                                     int32_t metrics_len, jc_robot** identified, jc_report** report) {
  return CAPI_ENTRY({
    const jc_robot& model = robotHandle(nominal, "nominal");
    const jc_robot& real = robotHandle(truth, "truth");
    if (real.robot->dof() != model.robot->dof()) {
      invalid("truth has " + std::to_string(real.robot->dof()) + " joints, nominal " +
              std::to_string(model.robot->dof()));
    }
    const MethodOptions o = readMethodOptions(options_json, !real.drives.empty());
    const int runs = o.dynamic_correction ? 4 : 3;
    requireOutput(metrics, metrics_len, 5 * runs, "metrics",
                  o.dynamic_correction ? "4 runs x Ra, Rz, RMS, max, mean" : "3 runs x Ra, Rz, RMS, max, mean");

    PaperIdentificationSpec identification_spec;
    identification_spec.seed = o.seed;
    const PaperIdentification identification =
        identifyFromSimulatedCampaigns(model.model, real.model, identification_spec);
    SpiralExperimentSpec spec;
    if (o.use_plant) spec.drives = real.drives;
    spec.dynamic_correction = o.dynamic_correction;
    const double scale = o.feed_rate / kPaperFeedRate;  // the ramps take the paper's time, as in `paper`
    spec.feed_rate.speed = o.feed_rate;
    spec.feed_rate.acceleration *= scale;
    spec.feed_rate.jerk *= scale;
    // Both models are immutable once loaded: no handle lock is needed to read them.
    const SpiralExperimentResult result = runSpiralExperiment(*identification.identified, real.model, spec);
    for (int r = 0; r < runs; ++r) {
      const AccuracyMetrics& m = result.runs[r].metrics;
      const double values[5] = {m.ra, m.rz, m.rms, m.max, m.mean};
      for (int i = 0; i < 5; ++i) metrics[5 * r + i] = values[i];
    }
    std::unique_ptr<jc_robot> identified_robot;
    if (identified)
      identified_robot = std::make_unique<jc_robot>(model.robot, *identification.identified, model.drives);
    std::unique_ptr<jc_report> made;
    if (report) {
      const PaperIdentificationSources sources{model.robot->name + " (the nominal jc_robot handle)", model.robot->name,
                                               identification.stiffness_campaign.source,
                                               identification.sweep_campaign.source, "the identified jc_robot handle"};
      const PaperIdentificationReport r = paperIdentificationReport(identification, sources, &real.model);
      made = std::make_unique<jc_report>(r.both.dump(2), r.summary);
    }
    // Handed over only now, when nothing can fail any more.
    if (identified) *identified = publish(std::move(identified_robot));
    if (report) *report = publish(std::move(made));
  });
}

}  // extern "C"
