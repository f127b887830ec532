#include "model/effects/periodic_table.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"
#include "model/effects/joint_error_model.hpp"

namespace jointcomp {
namespace {

constexpr double kTwoPi = 2.0 * 3.14159265358979323846;
// A knot is fitted only where the rows give it this much weight (a row at its centre gives 2/3).
constexpr double kMinimumSupport = 2.0;

// The angle ranges (deg, within one revolution of the part) where the fitted knots shape the table.
nlohmann::ordered_json coveredRanges(const std::vector<int>& kept, int knots) {
  std::vector<bool> segment(static_cast<std::size_t>(knots), false);  // segment s: u in [s, s + 1)
  for (int k : kept) {
    for (int s = k; s < k + 4; ++s) segment[static_cast<std::size_t>(s % knots)] = true;  // support of knot k
  }
  nlohmann::ordered_json ranges = nlohmann::ordered_json::array();
  const double step = 360.0 / knots;
  for (int s = 0; s < knots; ++s) {
    if (!segment[static_cast<std::size_t>(s)] || (s > 0 && segment[static_cast<std::size_t>(s - 1)])) continue;
    int end = s;
    while (end + 1 < knots && segment[static_cast<std::size_t>(end + 1)]) ++end;
    ranges.push_back({s * step, (end + 1) * step});
  }
  return ranges;
}

}  // namespace

// The knots of a table of `knots` for (joint, stage) that the rows support, but for the most supported
// one: the B-splines sum to one, so all of them together would repeat the joint's offset; leaving one at
// zero spans the same functions with the offset and keeps the fit regular.
std::vector<int> fittedTableKnots(const DiscoveryData& data, int joint, int stage, int knots) {
  std::vector<double> support(static_cast<std::size_t>(knots), 0.0);
  for (int i = 0; i < data.rows(); ++i) {
    const PeriodicSplineWeights w =
        periodicSplineWeights(knots, data.gears->stageInputAngle(joint, stage, data.motor[i]));
    for (int k = 0; k < 4; ++k) support[static_cast<std::size_t>((w.first + k) % knots)] += w.weight[k];
  }
  std::vector<int> kept;
  for (int k = 0; k < knots; ++k) {
    if (support[static_cast<std::size_t>(k)] >= kMinimumSupport) kept.push_back(k);
  }
  if (!kept.empty()) {
    const auto most = std::max_element(kept.begin(), kept.end(), [&](int a, int b) {
      return support[static_cast<std::size_t>(a)] < support[static_cast<std::size_t>(b)];
    });
    kept.erase(most);
  }
  return kept;
}

PeriodicSplineWeights periodicSplineWeights(int knots, double angle) {
  double u = angle / kTwoPi * knots;
  u -= std::floor(u / knots) * knots;  // [0, knots)
  int segment = static_cast<int>(u);
  if (segment >= knots) segment = knots - 1;  // rounding at the top of the range
  const double t = u - segment;
  const double s = 1.0 - t;
  PeriodicSplineWeights w;
  w.first = segment;
  w.weight[0] = s * s * s / 6.0;
  w.weight[1] = (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0;
  w.weight[2] = (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0;
  w.weight[3] = t * t * t / 6.0;
  const double du = knots / kTwoPi;
  w.slope[0] = -0.5 * s * s * du;
  w.slope[1] = (1.5 * t * t - 2.0 * t) * du;
  w.slope[2] = (-1.5 * t * t + t + 0.5) * du;
  w.slope[3] = 0.5 * t * t * du;
  return w;
}

std::vector<double> periodicTableSpectrum(const std::vector<double>& coefficients, int max_order) {
  const int knots = static_cast<int>(coefficients.size());
  const int samples = 16 * std::max(knots, max_order);
  std::vector<double> amplitude(static_cast<std::size_t>(std::max(0, max_order)), 0.0);
  if (knots == 0) return amplitude;
  std::vector<double> value(static_cast<std::size_t>(samples));
  for (int n = 0; n < samples; ++n) {
    const PeriodicSplineWeights w = periodicSplineWeights(knots, kTwoPi * n / samples);
    double f = 0.0;
    for (int k = 0; k < 4; ++k) f += w.weight[k] * coefficients[static_cast<std::size_t>((w.first + k) % knots)];
    value[static_cast<std::size_t>(n)] = f;
  }
  for (int order = 1; order <= max_order; ++order) {
    double a = 0.0, b = 0.0;
    for (int n = 0; n < samples; ++n) {
      const double x = kTwoPi * order * n / samples;
      a += value[static_cast<std::size_t>(n)] * std::cos(x);
      b += value[static_cast<std::size_t>(n)] * std::sin(x);
    }
    amplitude[static_cast<std::size_t>(order - 1)] = 2.0 * std::hypot(a, b) / samples;
  }
  return amplitude;
}

PeriodicTableEffect::PeriodicTableEffect(const Robot& robot, GearTrain gears, std::vector<PeriodicTable> tables)
    : gears_(std::move(gears)), tables_(std::move(tables)) {
  for (const Joint& joint : robot.joints) joint_names_.push_back(joint.name);
  for (const PeriodicTable& t : tables_) {
    if (t.joint < 0 || t.joint >= robot.dof()) throw ParameterError("periodic_table: joint index out of range");
    if (t.stage < 1 || t.stage > gears_.stageCount(t.joint) + 1) {
      throw ParameterError("periodic_table: " + joint_names_[t.joint] + " has no stage " + std::to_string(t.stage));
    }
    const int knots = static_cast<int>(t.coefficients_rad.size());
    if (knots < kMinKnots || knots > kMaxKnots) {
      throw ParameterError("periodic_table: the table of " + joint_names_[t.joint] + " has " + std::to_string(knots) +
                           " coefficients; it needs " + std::to_string(kMinKnots) + " to " + std::to_string(kMaxKnots));
    }
  }
  setParameters(parameters());
}

std::unique_ptr<Effect> PeriodicTableEffect::fromJson(const nlohmann::json& json, const Robot& robot,
                                                      const GearTrain& gears, const std::string& path) {
  JsonFields fields(json, path);
  fields.text("type");
  std::vector<PeriodicTable> tables;
  const nlohmann::json& list = fields.array("tables");
  for (std::size_t i = 0; i < list.size(); ++i) {
    JsonFields entry(list[i], fields.pathOf("tables[" + std::to_string(i) + "]"));
    PeriodicTable table;
    table.joint = readJoint(entry, robot);
    table.stage = readPart(entry, gears, table.joint, robot.joints[table.joint].name);
    const nlohmann::json& values = entry.array("coefficients_rad");
    if (values.size() < static_cast<std::size_t>(kMinKnots) || values.size() > static_cast<std::size_t>(kMaxKnots)) {
      entry.fail("coefficients_rad", "expected " + std::to_string(kMinKnots) + " to " + std::to_string(kMaxKnots) +
                                         " coefficients, found " + std::to_string(values.size()));
    }
    for (std::size_t k = 0; k < values.size(); ++k) {
      if (!values[k].is_number() || !std::isfinite(values[k].get<double>())) {
        entry.fail("coefficients_rad", "coefficient " + std::to_string(k) + " is not a finite number");
      }
      if (std::abs(values[k].get<double>()) > kMaxStatedJointError) {
        entry.fail("coefficients_rad", "coefficient " + std::to_string(k) + " is " +
                                           shortNumber(values[k].get<double>()) + " rad, beyond the plausible +-" +
                                           shortNumber(kMaxStatedJointError) + " rad of a joint error");
      }
      table.coefficients_rad.push_back(values[k].get<double>());
    }
    entry.rejectUnknownKeys();
    tables.push_back(std::move(table));
  }
  const std::string note = fields.textOr("estimate", "");
  fields.rejectUnknownKeys();
  auto effect = std::make_unique<PeriodicTableEffect>(robot, gears, tables);
  effect->estimate_note = note;
  return effect;
}

double PeriodicTableEffect::valueAt(std::size_t t, double angle) const {
  const std::vector<double>& c = tables_[t].coefficients_rad;
  const int knots = static_cast<int>(c.size());
  const PeriodicSplineWeights w = periodicSplineWeights(knots, angle);
  double value = 0.0;
  for (int k = 0; k < 4; ++k) value += w.weight[k] * c[static_cast<std::size_t>((w.first + k) % knots)];
  return value;
}

void PeriodicTableEffect::addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const {
  for (std::size_t t = 0; t < tables_.size(); ++t) {
    const PeriodicTable& table = tables_[t];
    dq[table.joint] += valueAt(t, gears_.stageInputAngle(table.joint, table.stage, ctx.motor));
  }
}

bool PeriodicTableEffect::addMotorSlope(const Robot&, const JointContext& ctx, JointVector& slope) const {
  for (const PeriodicTable& table : tables_) {
    const std::vector<double>& c = table.coefficients_rad;
    const int knots = static_cast<int>(c.size());
    const PeriodicSplineWeights w =
        periodicSplineWeights(knots, gears_.stageInputAngle(table.joint, table.stage, ctx.motor));
    double per_angle = 0.0;
    for (int k = 0; k < 4; ++k) per_angle += w.slope[k] * c[static_cast<std::size_t>((w.first + k) % knots)];
    slope[table.joint] += per_angle * gears_.stageInputPerMotor(table.joint, table.stage);
  }
  return true;
}

bool PeriodicTableEffect::addJointErrorAndMotorSlope(const Robot&, const JointContext& ctx, JointVector& dq,
                                                     JointVector& slope) const {
  for (const PeriodicTable& table : tables_) {
    const std::vector<double>& c = table.coefficients_rad;
    const int knots = static_cast<int>(c.size());
    const PeriodicSplineWeights w =
        periodicSplineWeights(knots, gears_.stageInputAngle(table.joint, table.stage, ctx.motor));
    double value = 0.0, per_angle = 0.0;
    for (int k = 0; k < 4; ++k) {
      const double coefficient = c[static_cast<std::size_t>((w.first + k) % knots)];
      value += w.weight[k] * coefficient;
      per_angle += w.slope[k] * coefficient;
    }
    dq[table.joint] += value;
    slope[table.joint] += per_angle * gears_.stageInputPerMotor(table.joint, table.stage);
  }
  return true;
}

void PeriodicTableEffect::markCommandJoints(int, bool* joints) const {
  for (const PeriodicTable& table : tables_) joints[table.joint] = true;
}

std::vector<std::string> PeriodicTableEffect::parameterNames() const {
  std::vector<std::string> names;
  for (const PeriodicTable& t : tables_) {
    const std::string prefix = joint_names_[t.joint] + ".periodic_" + gears_.partName(t.joint, t.stage) + ".c";
    for (std::size_t k = 0; k < t.coefficients_rad.size(); ++k) names.push_back(prefix + std::to_string(k) + "_rad");
  }
  return names;
}

std::vector<double> PeriodicTableEffect::parameters() const {
  std::vector<double> values;
  for (const PeriodicTable& t : tables_)
    values.insert(values.end(), t.coefficients_rad.begin(), t.coefficients_rad.end());
  return values;
}

void PeriodicTableEffect::setParameters(const std::vector<double>& values) {
  std::size_t count = 0;
  for (const PeriodicTable& t : tables_) count += t.coefficients_rad.size();
  if (values.size() != count) {
    throw ParameterError("periodic_table: expected " + std::to_string(count) + " parameters, found " +
                         std::to_string(values.size()));
  }
  for (std::size_t k = 0; k < values.size(); ++k) {
    if (!std::isfinite(values[k])) throw ParameterError("periodic_table: " + parameterNames()[k] + " is not finite");
    // The reader's bound, so that a fit never makes an effect whose parameter file would be refused.
    if (std::abs(values[k]) > kMaxStatedJointError) {
      throw ParameterError("periodic_table: " + parameterNames()[k] + " is " + shortNumber(values[k]) +
                           " rad, beyond the plausible +-" + shortNumber(kMaxStatedJointError) +
                           " rad of a joint error");
    }
  }
  std::size_t at = 0;
  for (PeriodicTable& t : tables_) {
    for (double& c : t.coefficients_rad) c = values[at++];
  }
}

nlohmann::json PeriodicTableEffect::toJson() const {
  nlohmann::json list = nlohmann::json::array();
  for (const PeriodicTable& t : tables_) {
    list.push_back({{"joint", joint_names_[t.joint]},
                    {"of", gears_.partName(t.joint, t.stage)},
                    {"coefficients_rad", t.coefficients_rad}});
  }
  nlohmann::json json = {{"type", kType}, {"tables", list}};
  if (!estimate_note.empty()) json["estimate"] = estimate_note;
  return json;
}

void PeriodicTableDiscovery::offer(const DiscoveryData& data, int joint,
                                   std::vector<DiscoveryCandidate>& candidates) const {
  if (joint < 0) return;
  const GearTrain& gears = *data.gears;
  for (const int s : gears.distinctParts(joint)) {
    const std::string part = gears.partName(joint, s);
    for (const int knots : data.table_knots) {
      if (knots < PeriodicTableEffect::kMinKnots || knots > PeriodicTableEffect::kMaxKnots) continue;
      const std::vector<int> kept = fittedTableKnots(data, joint, s, knots);
      const int columns = static_cast<int>(kept.size());
      if (columns < 2 || data.rows() < 4 * columns) continue;
      DiscoveryCandidate candidate;
      candidate.type = name();
      candidate.joint = joint;
      candidate.stage = s;
      candidate.part = part;
      candidate.cycles = knots;
      candidate.detail = " " + part + " table of " + std::to_string(knots) + " knots";
      candidate.report_fields = {{"part", part},
                                 {"stage", s},
                                 {"knots", knots},
                                 {"fitted_knots", columns},
                                 {"covered_deg", coveredRanges(kept, knots)}};
      candidate.columns = Eigen::MatrixXd::Zero(data.rows(), columns);
      std::vector<int> column_of(static_cast<std::size_t>(knots), -1);
      for (int c = 0; c < columns; ++c) column_of[static_cast<std::size_t>(kept[static_cast<std::size_t>(c)])] = c;
      for (int i = 0; i < data.rows(); ++i) {
        const PeriodicSplineWeights w = periodicSplineWeights(knots, gears.stageInputAngle(joint, s, data.motor[i]));
        for (int k = 0; k < 4; ++k) {
          const int column = column_of[static_cast<std::size_t>((w.first + k) % knots)];
          if (column >= 0) candidate.columns(i, column) += w.weight[k];
        }
      }
      // Smoothness prior: the table's periodic second differences, over every knot (those not visited
      // stay at zero, so the prior on the fitted ones is the full one's principal part).
      Eigen::MatrixXd second = Eigen::MatrixXd::Zero(knots, knots);
      for (int k = 0; k < knots; ++k) {
        second(k, k) = -2.0;
        second(k, (k + 1) % knots) = 1.0;
        second(k, (k + knots - 1) % knots) = 1.0;
      }
      const Eigen::MatrixXd roughness = second.transpose() * second;
      candidate.prior.resize(columns, columns);
      for (int a = 0; a < columns; ++a)
        for (int b = 0; b < columns; ++b)
          candidate.prior(a, b) = roughness(kept[static_cast<std::size_t>(a)], kept[static_cast<std::size_t>(b)]);
      candidates.push_back(std::move(candidate));
    }
  }
}

std::unique_ptr<Effect> PeriodicTableDiscovery::makeEffect(const DiscoveryData& data,
                                                           const std::vector<FittedCandidate>& accepted) const {
  std::vector<PeriodicTable> tables;
  for (const FittedCandidate& a : accepted) {
    const DiscoveryCandidate& c = *a.candidate;
    const int knots = static_cast<int>(c.cycles);
    const std::vector<int> kept = fittedTableKnots(data, c.joint, c.stage, knots);
    if (static_cast<Eigen::Index>(kept.size()) != a.theta.size()) {
      throw SolverError("periodic table of joint " + std::to_string(c.joint + 1) + ": " +
                        std::to_string(a.theta.size()) + " coefficients for " + std::to_string(kept.size()) +
                        " fitted knots");
    }
    PeriodicTable table;
    table.joint = c.joint;
    table.stage = c.stage;
    table.coefficients_rad.assign(static_cast<std::size_t>(knots), 0.0);  // knots never visited stay at zero
    for (std::size_t k = 0; k < kept.size(); ++k)
      table.coefficients_rad[static_cast<std::size_t>(kept[k])] = a.theta[static_cast<Eigen::Index>(k)];
    tables.push_back(std::move(table));
  }
  return std::make_unique<PeriodicTableEffect>(*data.robot, *data.gears, tables);
}

std::vector<NamedEstimate> PeriodicTableDiscovery::describe(const FittedCandidate& fitted,
                                                            const JointErrorModel& model) const {
  const DiscoveryCandidate& c = *fitted.candidate;
  const int knots = static_cast<int>(c.cycles);
  const std::string stem = model.robot().joints[static_cast<std::size_t>(c.joint)].name + "." + c.part + ".periodic";
  std::vector<NamedEstimate> estimates;
  // The spectrum of the fitted shape: the three strongest orders per revolution of the part, so that a
  // reader sees which physical part repeats. The coefficients, with their sigmas, follow.
  const PeriodicTableEffect* effect = nullptr;
  for (int e = 0; e < model.effectCount() && !effect; ++e)
    effect = dynamic_cast<const PeriodicTableEffect*>(&model.effect(e));
  if (effect) {
    for (const PeriodicTable& table : effect->tables()) {
      if (table.joint != c.joint || table.stage != c.stage || static_cast<int>(table.coefficients_rad.size()) != knots)
        continue;
      const std::vector<double> spectrum = periodicTableSpectrum(table.coefficients_rad, knots / 2);
      std::vector<int> order(spectrum.size());
      for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<int>(k);
      std::sort(order.begin(), order.end(), [&](int a, int b) {
        return spectrum[static_cast<std::size_t>(a)] > spectrum[static_cast<std::size_t>(b)];
      });
      for (std::size_t k = 0; k < std::min<std::size_t>(3, order.size()); ++k) {
        estimates.push_back({stem + ".order_" + std::to_string(order[k] + 1) + ".amplitude_rad",
                             spectrum[static_cast<std::size_t>(order[k])], 0.0});
      }
    }
  }
  for (Eigen::Index k = 0; k < fitted.theta.size(); ++k) {
    estimates.push_back({stem + ".fitted_knot_" + std::to_string(k) + "_rad", fitted.theta[k], fitted.sigma[k]});
  }
  return estimates;
}

std::string PeriodicTableDiscovery::physicalProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                                                    const Eigen::VectorXd& theta, const JointVector&) const {
  const int knots = static_cast<int>(candidate.cycles);
  if (candidate.joint < 0 || knots < PeriodicTableEffect::kMinKnots) return {};
  const std::vector<int> kept = fittedTableKnots(data, candidate.joint, candidate.stage, knots);
  if (static_cast<Eigen::Index>(kept.size()) != theta.size()) return {};
  std::vector<double> value(static_cast<std::size_t>(knots), 0.0);  // the unvisited knots stay at zero
  for (std::size_t c = 0; c < kept.size(); ++c)
    value[static_cast<std::size_t>(kept[c])] = theta[static_cast<Eigen::Index>(c)];
  double largest = 0.0;
  for (int i = 0; i < data.rows(); ++i) {
    const PeriodicSplineWeights w =
        periodicSplineWeights(knots, data.gears->stageInputAngle(candidate.joint, candidate.stage, data.motor[i]));
    double at = 0.0;
    for (int k = 0; k < 4; ++k) at += w.weight[k] * value[static_cast<std::size_t>((w.first + k) % knots)];
    largest = std::max(largest, std::abs(at));
  }
  double steepest = 0.0;  // rad per rad of the part's angle, over the whole period (32 samples per knot)
  for (int n = 0; n < 32 * knots; ++n) {
    const PeriodicSplineWeights w = periodicSplineWeights(knots, kTwoPi * n / (32.0 * knots));
    double slope = 0.0;
    for (int k = 0; k < 4; ++k) slope += w.slope[k] * value[static_cast<std::size_t>((w.first + k) % knots)];
    steepest = std::max(steepest, std::abs(slope));
  }
  return transmissionProblem(data, candidate, largest, steepest);
}

}  // namespace jointcomp
