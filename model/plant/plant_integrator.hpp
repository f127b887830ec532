// The CVODE integration of the flexible-joint plant: BDF with the plant's own Jacobian and the structured
// Newton solver (plant_newton_solver.hpp), the project's vector operations (plant_vector_operations.hpp),
// stop times at every advance's end (or stepping past them, PlantOptions::step_past_updates_s), and a work
// budget per advance. It integrates plantDerivative (flexible_joint_dynamics.hpp) of one model and workspace.
#pragma once

#include <memory>
#include <string>

#include "model/plant/plant_data.hpp"
#include "model/plant/plant_model.hpp"

namespace jointcomp {

class PlantIntegrator {
public:
  // CVODE set up for the model's state; `model` and `data` outlive the integrator. Throws SolverError when
  // SUNDIALS cannot be set up.
  PlantIntegrator(const PlantModel& model, PlantData& data);
  ~PlantIntegrator();
  PlantIntegrator(const PlantIntegrator&) = delete;
  PlantIntegrator& operator=(const PlantIntegrator&) = delete;

  // The state where CVODE stopped (written by the plant before a restart), and the state interpolated at the
  // plant's time when CVODE stepped past it.
  double* state();
  const double* state(bool ahead) const;
  // Restarts CVODE at `time` with a fresh history, from the interpolated state when `ahead`.
  void restart(double time, bool ahead);
  // CVODE's time (the end of its last step); false before it has one.
  bool cvodeTime(double& time) const;
  // Integrates from `time` (CVODE ahead of it when `ahead`) to end_time within `budget` steps. Returns
  // CVODE's flag; `past` tells that CVODE stepped past end_time (the state there is state(true)), `reached`
  // how far it got. On failure the state is CVODE's last good step.
  int advance(double time, double end_time, bool ahead, long budget, bool& past, double& reached);
  // CVODE's counts since the plant was built, with the plant's own (`own`: updates stepped past, restarted).
  PlantStatistics statistics(const PlantStatistics& own) const;
  // CVODE's message for the last failure of advance ("" if it gave none), and a flag's name.
  const std::string& lastError() const;
  static std::string flagName(long flag);
  // True for CVODE's flag of a spent work budget (CV_TOO_MUCH_WORK).
  static bool budgetSpent(int flag);

  // CVODE's linear-system function with the structured solver: evaluates the Jacobian into the solver's copy
  // unless CVODE may reuse the last one, and hands gamma over; 0, or 1 (recoverable) when the Jacobian is not
  // finite. Not for other callers.
  int prepareNewtonSystem(double t, const double* y, bool jacobian_ok, double gamma, int* jacobian_current);
  const PlantModel& model() const { return model_; }
  PlantData& data() { return data_; }

private:
  struct Solver;
  void configure();
  int integrateEvenly(double time, double end_time, bool ahead, long budget, double& reached);
  int integratePast(double end_time, double cvode_time, long budget, double& reached);
  bool stepsPast(double time, double end_time, double& cvode_time) const;

  const PlantModel& model_;
  PlantData& data_;
  std::unique_ptr<Solver> solver_;
};

}  // namespace jointcomp
