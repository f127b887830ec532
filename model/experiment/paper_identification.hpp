// The paper's whole method on a simulated robot (Olabi et al. 2012): measure the robot first (the stiffness
// protocol under known loads, tracker and levels; the joint-2 sweep, tracker), identify the joint
// stiffnesses and joint 2's transmission error from those measurements with model/identify, and hand back
// the identified model that the spiral is then compensated with (runSpiralExperiment with it as the
// nominal). The campaigns are simulated on the truth (quasi-static: the stiffness protocol is static and the
// sweep settles at each step) with the instruments' stated noise, seeded from `seed` alone.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "model/experiment/campaign_simulation.hpp"
#include "model/experiment/sweep_load_refit.hpp"
#include "model/identify/stiffness_identification.hpp"
#include "model/identify/transmission_identification.hpp"

namespace jointcomp {

struct PaperIdentificationSpec {
  // The campaigns' own noise seeds are drawn from this one (stiffness and sweep apart), so that one number
  // fixes everything, as the spiral experiment's truth seed does.
  std::uint64_t seed = 2012;
  CampaignSimulationSpec stiffness_campaign = defaultCampaignSpec(CampaignProtocol::Stiffness);
  CampaignSimulationSpec sweep_campaign = defaultCampaignSpec(CampaignProtocol::JointSweep);  // joint 2
  StiffnessIdentificationOptions stiffness;
  TransmissionIdentificationOptions transmission;  // joint 2, harmonics of the second stage's input
  bool use_global = false;                         // the global stiffness estimates go into the model
  // What the sweep reveals beyond the harmonics: the swept joint's load effects (the spring balancer)
  // refitted to it (sweep_load_refit.hpp), then the harmonics identified again against that model.
  bool refit_loads = true;
  SweepLoadRefitOptions load_refit;
};

struct PaperIdentification {
  MeasurementCampaign stiffness_campaign;
  MeasurementCampaign sweep_campaign;
  StiffnessIdentificationResult stiffness;
  TransmissionIdentificationResult transmission;
  SweepLoadRefit load_refit;  // empty when not asked for
  // The nominal model with the identified stiffnesses, the refitted loads and the identified harmonics of the
  // swept joint.
  std::shared_ptr<const JointErrorModel> identified;
  double seconds = 0.0;  // CPU time of simulation and identification
};

// The two campaigns measured on `truth`, identified against `nominal` (the stiffness first; the sweep's
// transmission error then with the identified stiffness, whose deflection it subtracts). Both models must
// be of one robot (same joints). Throws what the simulation and the identifications throw (InvalidArgument,
// MeasurementError naming the campaign, SolverError).
PaperIdentification identifyFromSimulatedCampaigns(const JointErrorModel& nominal, const JointErrorModel& truth,
                                                   const PaperIdentificationSpec& spec,
                                                   const std::function<void(const std::string&)>& progress = {});

// Where the identification's inputs and outputs are, as its report names them (file names or descriptions).
struct PaperIdentificationSources {
  std::string nominal_parameters, robot, stiffness_campaign, sweep_campaign, updated_parameters;
};

// Both identifications' reports (identification_report.hpp) in one document, {"format":
// "jointcomp-identification-reports/1", "parameters": the updated parameters, "reports": [stiffness,
// transmission]}, which `jointcomp montecarlo --report` takes; and both summaries. `truth` may be null.
struct PaperIdentificationReport {
  nlohmann::ordered_json stiffness, transmission, both;
  std::string summary;
};
PaperIdentificationReport paperIdentificationReport(const PaperIdentification& identification,
                                                    const PaperIdentificationSources& sources,
                                                    const JointErrorModel* truth);

// The refitted load parameters (name, nominal, value, standard error) and the sweep's residual before and after.
nlohmann::ordered_json sweepLoadRefitJson(const SweepLoadRefit& refit);

// The campaign seeds identifyFromSimulatedCampaigns uses for `seed`: (stiffness, sweep).
std::pair<std::uint64_t, std::uint64_t> paperCampaignSeeds(std::uint64_t seed);

}  // namespace jointcomp
