#include "model/experiment/sweep_load_refit.hpp"

#include <cmath>

#include <Eigen/Cholesky>

#include "model/common/errors.hpp"

namespace jointcomp {
namespace {

struct Candidate {
  int effect = 0;
  std::size_t parameter = 0;
};

// The swept joint's deflection (link minus command) at each row's command, by the model's loads and joint
// springs (found by their role, Effect::isJointSpring).
Eigen::VectorXd deflections(const JointErrorModel& model, const MeasurementCampaign& sweep, int joint) {
  EffectMask mask = model.loadsAnd({});
  if (model.jointSprings() >= 0) mask |= EffectMask(1) << model.jointSprings();
  JointErrorWorkspace ws(model.robot());
  JointContext ctx(model.robot().dof());
  Eigen::VectorXd d(static_cast<Eigen::Index>(sweep.size()));
  for (std::size_t k = 0; k < sweep.size(); ++k) {
    ctx.command = sweep.command[k];
    const FixedPointReport settled = settleStatically(model, mask, ws, ctx);
    if (!settled.converged)
      throw SolverError("sweep load refit: the model does not settle at row " + std::to_string(k));
    d[static_cast<Eigen::Index>(k)] = ctx.q[joint] - ctx.command[joint];
  }
  return d;
}

void setParameter(JointErrorModel& model, const Candidate& c, double value) {
  std::vector<double> values = model.effect(c.effect).parameters();
  values[c.parameter] = value;
  try {
    model.effect(c.effect).setParameters(values);
  } catch (const ParameterError& error) {
    throw SolverError(std::string("sweep load refit: a step left the parameters' valid range: ") + error.what());
  }
}

// r_k: what the harmonics leave of the kinematic error.
Eigen::VectorXd residualOf(const TransmissionIdentificationResult& t) {
  Eigen::VectorXd r(static_cast<Eigen::Index>(t.kinematic_error.size()));
  for (std::size_t k = 0; k < t.kinematic_error.size(); ++k) {
    double harmonics = 0.0;
    for (const HarmonicEstimate& h : t.harmonics)
      harmonics += h.amplitude_rad * std::sin(h.order * t.stage_angle[k] + h.phase_rad);
    r[static_cast<Eigen::Index>(k)] = t.kinematic_error[k] - harmonics;
  }
  return r;
}

}  // namespace

SweepLoadRefit refitSweptJointLoads(JointErrorModel& model, const MeasurementCampaign& sweep,
                                    const TransmissionIdentificationResult& transmission,
                                    const SweepLoadRefitOptions& options) {
  const int joint = transmission.joint;
  if (transmission.kinematic_error.size() != sweep.size() || transmission.stage_angle.size() != sweep.size())
    throw InvalidArgument("sweep load refit: the transmission identification has " +
                          std::to_string(transmission.kinematic_error.size()) + " samples, the sweep " +
                          std::to_string(sweep.size()) + " rows");
  if (joint < 0 || joint >= model.robot().dof()) throw InvalidArgument("sweep load refit: joint out of range");
  if (!(options.prior_relative > 0.0) || options.iterations < 1)
    throw InvalidArgument("sweep load refit: prior_relative must be positive and iterations at least 1");
  SweepLoadRefit refit;
  refit.rows = static_cast<int>(sweep.size());
  const Eigen::VectorXd r0 = residualOf(transmission);
  refit.rms_before_rad = std::sqrt(r0.squaredNorm() / static_cast<double>(r0.size()));
  const double sigma = std::max(transmission.residual_rms_rad, 1e-12);
  const Eigen::VectorXd d0 = deflections(model, sweep, joint);

  // The candidates: the load effects' non-zero parameters that move the swept joint's deflection.
  std::vector<Candidate> candidates;
  std::vector<double> scale;
  for (int e = 0; e < model.effectCount(); ++e) {
    if (model.effect(e).role() != EffectRole::Load) continue;
    const std::vector<double> values = model.effect(e).parameters();
    const std::vector<std::string> names = model.effect(e).parameterNames();
    for (std::size_t p = 0; p < values.size(); ++p) {
      if (values[p] == 0.0 || !std::isfinite(values[p])) continue;
      const Candidate c{e, p};
      setParameter(model, c, values[p] * (1.0 + 1e-4));
      const Eigen::VectorXd moved = deflections(model, sweep, joint);
      setParameter(model, c, values[p]);
      if ((moved - d0).norm() < 1e-3 * sigma) continue;  // does not reach the swept joint
      candidates.push_back(c);
      scale.push_back(options.prior_relative * std::abs(values[p]));
      refit.names.push_back(names[p]);
      refit.nominal.push_back(values[p]);
    }
  }
  const Eigen::Index n = static_cast<Eigen::Index>(candidates.size());
  Eigen::VectorXd z = Eigen::VectorXd::Zero(n);  // (p - p0) / scale
  Eigen::MatrixXd posterior = Eigen::MatrixXd::Identity(n, n);
  Eigen::VectorXd r = r0;
  for (int iteration = 0; iteration < options.iterations && n > 0; ++iteration) {
    const Eigen::VectorXd d = deflections(model, sweep, joint);
    r = r0 - (d - d0);
    Eigen::MatrixXd jacobian(r.size(), n);  // d(deflection) / dz
    for (Eigen::Index c = 0; c < n; ++c) {
      const double value = refit.nominal[c] + z[c] * scale[c];
      const double step = 1e-3 * scale[c];
      setParameter(model, candidates[c], value + step);
      jacobian.col(c) = (deflections(model, sweep, joint) - d) / (step / scale[c]);
      setParameter(model, candidates[c], value);
    }
    const Eigen::MatrixXd a = jacobian.transpose() * jacobian / (sigma * sigma) + Eigen::MatrixXd::Identity(n, n);
    const Eigen::LDLT<Eigen::MatrixXd> solve(a);
    const Eigen::VectorXd delta = solve.solve(jacobian.transpose() * r / (sigma * sigma) - z);
    if (!delta.allFinite()) throw SolverError("sweep load refit: the step is not finite");
    z += delta;
    for (Eigen::Index c = 0; c < n; ++c) setParameter(model, candidates[c], refit.nominal[c] + z[c] * scale[c]);
    posterior = solve.solve(Eigen::MatrixXd::Identity(n, n));
  }
  r = r0 - (deflections(model, sweep, joint) - d0);
  refit.rms_after_rad = std::sqrt(r.squaredNorm() / static_cast<double>(r.size()));
  for (Eigen::Index c = 0; c < n; ++c) {
    refit.value.push_back(refit.nominal[c] + z[c] * scale[c]);
    refit.se.push_back(std::sqrt(posterior(c, c)) * scale[c]);
  }
  return refit;
}

}  // namespace jointcomp
