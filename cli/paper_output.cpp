// `jointcomp paper`'s table, CSV and summary.json over the runs of the nominal, identified and perfect models.
#include "cli/paper_output.hpp"

#include <cstdio>
#include <sstream>

namespace jointcomp::cli {
namespace {

// Table II of Olabi et al. (IEEE ICIT 2012), in mm.
constexpr double kPaperRa[3] = {0.2032, 0.0459, 0.0312};
constexpr double kPaperRz[3] = {0.2882, 0.2097, 0.1502};
constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

struct Labelled {
  const char* model;  // "nominal", "identified", "perfect"
  const SpiralExperimentResult* result;
};

std::vector<Labelled> labelled(const PaperRuns& runs) {
  std::vector<Labelled> all = {{"nominal", runs.nominal}};
  if (runs.identified) all.push_back({"identified", runs.identified});
  if (runs.perfect) all.push_back({"perfect", runs.perfect});
  return all;
}

// A run's row label: the nominal model's runs keep the paper's names alone when there is nothing beside them.
std::string modelLabel(const std::string& model, bool alone) {
  if (alone) return "";
  if (model == "perfect") return "perfect model (floor)";
  return model + " model";
}

void csvRun(std::ostringstream& csv, const JointTrajectory& planned, const SpiralRun& run, const char* model) {
  const int dof = planned.q.front().size();
  for (std::size_t k = 0; k < run.error.size(); ++k) {
    const Eigen::Vector3d p = planned.tool_position[k] * 1e3;
    const Eigen::Vector3d m = run.measured[k] * 1e3;
    const Eigen::Vector3d e = run.error[k] * 1e3;
    csv << run.index << ',' << model << ',' << planned.time[k] << ',' << p.x() << ',' << p.y() << ',' << p.z() << ','
        << m.x() << ',' << m.y() << ',' << m.z() << ',' << e.x() << ',' << e.y() << ',' << e.z();
    for (int j = 0; j < dof; ++j) csv << ',' << planned.q[k][j] * kRadToDeg;
    for (int j = 0; j < dof; ++j) csv << ',' << run.reference[k][j] * kRadToDeg;
    csv << "\n";
  }
}

nlohmann::ordered_json runJson(const SpiralRun& run, const char* model) {
  nlohmann::ordered_json entry = {{"name", run.name},
                                  {"model", model},
                                  {"ra_mm", run.metrics.ra * 1e3},
                                  {"rz_mm", run.metrics.rz * 1e3},
                                  {"rms_3d_mm", run.metrics.rms * 1e3},
                                  {"max_3d_mm", run.metrics.max * 1e3}};
  if (run.index < 3) {
    entry["paper_ra_mm"] = kPaperRa[run.index];
    entry["paper_rz_mm"] = kPaperRz[run.index];
    entry["compensation_max_iterations"] = run.compensation.max_iterations;
    entry["compensation_max_correction_deg"] = run.compensation.max_correction * kRadToDeg;
  } else {
    const DynamicCompensationReport& d = run.dynamic_compensation;
    entry["plant_runs"] = d.iterations;
    entry["closed_form_max_link_error_rad"] = d.initial_error_rad;
    entry["nominal_plant_max_link_error_rad"] = d.max_error_rad;
    entry["compensation_max_correction_deg"] = d.max_correction_rad * kRadToDeg;
  }
  return entry;
}

const SpiralRun* findRun(const SpiralExperimentResult* result, int index) {
  if (!result) return nullptr;
  for (const SpiralRun& run : result->runs)
    if (run.index == index) return &run;
  return nullptr;
}

void printPlantStatistics(const PaperRuns& runs) {
  for (const Labelled& l : labelled(runs)) {
    const SpiralExperimentResult& result = *l.result;
    const PlantStatistics& st = result.plant_statistics;
    std::printf(
        "  plant (%s model's runs): %.1fx real time (%.3f s for %zu x %.1f s of motion); CVODE %ld steps, %ld "
        "right-hand sides, %ld Jacobians\n",
        l.model, static_cast<double>(result.runs.size()) * result.planned.time.back() / result.simulation_seconds,
        result.simulation_seconds, result.runs.size(), result.planned.time.back(), st.steps, st.rhs_evaluations,
        st.jacobian_evaluations);
    if (const SpiralRun* dynamic = findRun(l.result, 3)) {
      const DynamicCompensationReport& d = dynamic->dynamic_compensation;
      std::printf(
          "  dynamic correction (%s model): %.2f s; largest link error of its plant %.2g rad in closed form, %.2g "
          "rad after %d runs\n",
          l.model, dynamic->compensation_seconds, d.initial_error_rad, d.max_error_rad, d.iterations);
    }
  }
}

void printReduction(const PaperRuns& runs) {
  const AccuracyMetrics& none = runs.nominal->runs[0].metrics;
  std::printf("reduction against the uncorrected run with both corrections (paper Ra %.0f %%, Rz %.0f %%):\n",
              (1 - kPaperRa[2] / kPaperRa[0]) * 100, (1 - kPaperRz[2] / kPaperRz[0]) * 100);
  for (const Labelled& l : labelled(runs)) {
    const SpiralRun* both = findRun(l.result, 2);
    const SpiralRun* dynamic = findRun(l.result, 3);
    std::printf("  %-22s Ra %.1f %%, Rz %.1f %%", (std::string(l.model) + " model").c_str(),
                (1 - both->metrics.ra / none.ra) * 100, (1 - both->metrics.rz / none.rz) * 100);
    if (dynamic) {
      std::printf("; dynamic over static: Ra x %.2f, Rz x %.2f", dynamic->metrics.ra / both->metrics.ra,
                  dynamic->metrics.rz / both->metrics.rz);
    }
    std::printf("\n");
  }
}

}  // namespace

std::string runsCsv(const PaperRuns& runs) {
  std::ostringstream csv;
  csv.precision(9);
  csv << "run,model,t_s,planned_x_mm,planned_y_mm,planned_z_mm,measured_x_mm,measured_y_mm,measured_z_mm,"
         "error_x_mm,error_y_mm,error_z_mm";
  const int dof = runs.nominal->planned.q.front().size();
  for (int j = 1; j <= dof; ++j) csv << ",q_theo" << j << "_deg";
  for (int j = 1; j <= dof; ++j) csv << ",q_ref" << j << "_deg";
  csv << "\n";
  for (const Labelled& l : labelled(runs))
    for (const SpiralRun& run : l.result->runs) csvRun(csv, l.result->planned, run, l.model);
  return csv.str();
}

std::string summaryJson(const PaperRuns& runs, const SpiralExperimentSpec& spec, const std::string& robot_name,
                        const nlohmann::ordered_json& identification) {
  const SpiralExperimentResult& result = *runs.nominal;
  nlohmann::ordered_json summary;
  summary["experiment"] = "Olabi et al. 2012 spiral, simulated " + robot_name;
  summary["robot"] = robot_name;
  summary["samples"] = result.planned.size();
  summary["duration_s"] = result.planned.time.back();
  summary["truth_seed"] = spec.truth.seed;
  summary["simulated_robot"] = result.dynamic ? "flexible-joint plant (CVODE)" : "quasi-static";
  summary["feed_rate_m_per_s"] = spec.feed_rate.speed;  // (no timings: the same inputs give the same file)
  // "runs": the nominal model's (as before the identification existed); the others beside them.
  for (const SpiralRun& run : result.runs) summary["runs"].push_back(runJson(run, "nominal"));
  if (runs.identified) {
    for (const SpiralRun& run : runs.identified->runs)
      summary["identified_model_runs"].push_back(runJson(run, "identified"));
  }
  if (runs.perfect) {
    for (const SpiralRun& run : runs.perfect->runs) summary["perfect_model_runs"].push_back(runJson(run, "perfect"));
  }
  if (!identification.is_null()) summary["identification"] = identification;
  return summary.dump(2) + "\n";
}

void printTable(const PaperRuns& runs) {
  const SpiralExperimentResult& result = *runs.nominal;
  if (result.dynamic) printPlantStatistics(runs);
  const bool alone = !runs.identified && !runs.perfect;
  std::printf("\nTable II analogue (%zu samples, %.1f s of motion; errors measured by a simulated tracker)\n",
              result.planned.size(), result.planned.time.back());
  std::printf("%-44s %-22s %9s %9s %11s %11s %10s %10s\n", "run", alone ? "" : "model", "Ra [mm]", "Rz [mm]",
              "RMS3D [mm]", "max3D [mm]", "paper Ra", "paper Rz");
  for (int index = 0; index < 4; ++index) {
    for (const Labelled& l : labelled(runs)) {
      const SpiralRun* run = findRun(l.result, index);
      if (!run) continue;
      const AccuracyMetrics& m = run->metrics;
      const std::string model = index == 0 ? "" : modelLabel(l.model, alone);
      char paper_ra[16] = "-", paper_rz[16] = "-";
      if (index < 3) {
        std::snprintf(paper_ra, sizeof paper_ra, "%.4f", kPaperRa[index]);
        std::snprintf(paper_rz, sizeof paper_rz, "%.4f", kPaperRz[index]);
      }
      std::printf("%-44s %-22s %9.4f %9.4f %11.4f %11.4f %10s %10s\n", run->name.c_str(), model.c_str(), m.ra * 1e3,
                  m.rz * 1e3, m.rms * 1e3, m.max * 1e3, paper_ra, paper_rz);
    }
  }
  printReduction(runs);
}

}  // namespace jointcomp::cli
