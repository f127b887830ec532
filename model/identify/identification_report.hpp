// Reports of the identifications: JSON (every number in SI units and, where people read them, in degrees
// or N m / rad, with the series the plots need) and a short human summary. When the true parameters are
// known (simulated campaigns), both compare each estimate with the truth.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "model/identify/stiffness_identification.hpp"
#include "model/identify/transmission_identification.hpp"

namespace jointcomp {

struct ReportSources {
  std::string campaign;  // file names, as given
  std::string parameters;
  std::string robot;
  std::string updated_parameters;
  std::string method_used;  // stiffness: "local" or "global" (which one went into the parameter file)
};

// `truth` may be null.
nlohmann::ordered_json stiffnessReportJson(const StiffnessIdentificationResult& result, const ReportSources& sources,
                                           const JointErrorModel* truth);
std::string stiffnessSummary(const StiffnessIdentificationResult& result, const ReportSources& sources,
                             const JointErrorModel* truth);

nlohmann::ordered_json transmissionReportJson(const TransmissionIdentificationResult& result,
                                              const ReportSources& sources, const JointErrorModel* truth);
std::string transmissionSummary(const TransmissionIdentificationResult& result, const ReportSources& sources,
                                const JointErrorModel* truth);

// The truth's harmonic of that joint, stage and order: true and its amplitude and phase, else false.
bool trueHarmonic(const JointErrorModel& truth, int joint, int stage, double order, double& amplitude_rad,
                  double& phase_rad);
// a - b wrapped into (-pi, pi].
double wrappedAngleDifference(double a, double b);

}  // namespace jointcomp
