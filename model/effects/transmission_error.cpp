#include "model/effects/transmission_error.hpp"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"
#include "model/common/periodogram.hpp"
#include "model/common/sin_cos.hpp"
#include "model/effects/joint_error_model.hpp"

namespace jointcomp {
namespace {
constexpr double kDegree = 3.14159265358979323846 / 180.0;
constexpr double kPi = 3.14159265358979323846;
}  // namespace

TransmissionErrorEffect::TransmissionErrorEffect(const Robot& robot, GearTrain gears, std::vector<Harmonic> harmonics)
    : gears_(std::move(gears)), harmonics_(std::move(harmonics)) {
  for (const Joint& joint : robot.joints) joint_names_.push_back(joint.name);
  for (const Harmonic& h : harmonics_) {
    if (h.joint < 0 || h.joint >= robot.dof()) throw ParameterError("transmission_error: joint index out of range");
    if (h.stage < 1 || h.stage > gears_.stageCount(h.joint) + 1) {
      throw ParameterError("transmission_error: " + joint_names_[h.joint] + " has no stage " + std::to_string(h.stage));
    }
  }
  for (const Harmonic& h : harmonics_) {
    phase_per_motor_.push_back(h.cycles_per_revolution * gears_.stageInputPerMotor(h.joint, h.stage));
  }
  setParameters(parameters());
}

std::string TransmissionErrorEffect::partName(int joint, int stage) const { return gears_.partName(joint, stage); }

std::unique_ptr<Effect> TransmissionErrorEffect::fromJson(const nlohmann::json& json, const Robot& robot,
                                                          const GearTrain& gears, const std::string& path) {
  JsonFields fields(json, path);
  fields.text("type");
  std::vector<Harmonic> harmonics;
  const nlohmann::json& list = fields.array("harmonics");
  if (list.size() > kMaxHarmonics) {  // 100k harmonics in a 14.8 MB file kept `paper` busy for minutes
    fields.fail("harmonics", "has " + std::to_string(list.size()) + " entries; at most " +
                                 std::to_string(kMaxHarmonics) + " are read");
  }
  for (std::size_t i = 0; i < list.size(); ++i) {
    JsonFields entry(list[i], fields.pathOf("harmonics[" + std::to_string(i) + "]"));
    Harmonic h;
    h.joint = readJoint(entry, robot);
    h.stage = readPart(entry, gears, h.joint, robot.joints[h.joint].name);
    h.cycles_per_revolution = entry.positiveNumber("cycles_per_revolution");
    if (h.cycles_per_revolution > kMaxCyclesPerRevolution) {  // order 1e9: "compensation did not converge"
      entry.fail("cycles_per_revolution", "is beyond " + std::to_string(static_cast<int>(kMaxCyclesPerRevolution)) +
                                              " cycles per revolution of its part");
    }
    // People write degrees; programs write radians, which round-trip exactly. One of the two.
    if (entry.has("amplitude_deg") == entry.has("amplitude_rad")) {
      entry.fail("amplitude_deg", "give exactly one of amplitude_deg and amplitude_rad");
    }
    h.amplitude_rad = entry.has("amplitude_rad") ? entry.nonNegativeNumber("amplitude_rad")
                                                 : entry.nonNegativeNumber("amplitude_deg") * kDegree;
    if (h.amplitude_rad > kMaxStatedJointError) {
      entry.fail(entry.has("amplitude_rad") ? "amplitude_rad" : "amplitude_deg",
                 "is " + shortNumber(h.amplitude_rad) + " rad, beyond the plausible " +
                     shortNumber(kMaxStatedJointError) + " rad of a joint error");
    }
    h.phase_rad = entry.number("phase_rad");
    entry.rejectUnknownKeys();
    harmonics.push_back(h);
  }
  const std::string note = fields.textOr("estimate", "");
  fields.rejectUnknownKeys();
  auto effect = std::make_unique<TransmissionErrorEffect>(robot, gears, harmonics);
  effect->estimate_note = note;
  return effect;
}

void TransmissionErrorEffect::addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const {
  for (const Harmonic& h : harmonics_) {
    const double angle = gears_.stageInputAngle(h.joint, h.stage, ctx.motor);
    double sine, cosine;
    sinCos(h.cycles_per_revolution * angle + h.phase_rad, sine, cosine);
    dq[h.joint] += h.amplitude_rad * sine;
  }
}

bool TransmissionErrorEffect::addMotorSlope(const Robot&, const JointContext& ctx, JointVector& slope) const {
  for (const Harmonic& h : harmonics_) {
    const double angle = gears_.stageInputAngle(h.joint, h.stage, ctx.motor);
    double sine, cosine;
    sinCos(h.cycles_per_revolution * angle + h.phase_rad, sine, cosine);
    slope[h.joint] += h.amplitude_rad * h.cycles_per_revolution * gears_.stageInputPerMotor(h.joint, h.stage) * cosine;
  }
  return true;
}

bool TransmissionErrorEffect::addJointErrorAndMotorSlope(const Robot&, const JointContext& ctx, JointVector& dq,
                                                         JointVector& slope) const {
  for (const Harmonic& h : harmonics_) {
    const double angle = gears_.stageInputAngle(h.joint, h.stage, ctx.motor);
    double sine, cosine;
    sinCos(h.cycles_per_revolution * angle + h.phase_rad, sine, cosine);
    dq[h.joint] += h.amplitude_rad * sine;
    slope[h.joint] += h.amplitude_rad * h.cycles_per_revolution * gears_.stageInputPerMotor(h.joint, h.stage) * cosine;
  }
  return true;
}

void TransmissionErrorEffect::markCommandJoints(int, bool* joints) const {
  for (const Harmonic& h : harmonics_) joints[h.joint] = true;
}

bool TransmissionErrorEffect::continueJointErrorAndMotorSlope(const Robot&, const JointContext& ctx,
                                                              SinCosAnchor* anchors, bool reuse_anchors,
                                                              JointVector& dq, JointVector& slope) const {
  for (std::size_t i = 0; i < harmonics_.size(); ++i) {
    const Harmonic& h = harmonics_[i];
    SinCosAnchor& anchor = anchors[i];
    const double phase = ctx.motor[h.joint] * phase_per_motor_[i] + h.phase_rad;
    double sine, cosine;
    sinCosNear(phase, reuse_anchors, anchor, sine, cosine);
    dq[h.joint] += h.amplitude_rad * sine;
    slope[h.joint] += h.amplitude_rad * phase_per_motor_[i] * cosine;
  }
  return true;
}

void TransmissionErrorEffect::continueJointErrorAndMotorDerivatives(const Robot&, const JointContext& ctx,
                                                                    SinCosAnchor* anchors, bool reuse_anchors,
                                                                    JointVector& dq, JointVector& slope,
                                                                    JointVector& second, JointVector& third) const {
  for (std::size_t i = 0; i < harmonics_.size(); ++i) {
    const Harmonic& h = harmonics_[i];
    const double rate = phase_per_motor_[i];
    const double phase = ctx.motor[h.joint] * rate + h.phase_rad;
    double sine, cosine;
    sinCosNear(phase, reuse_anchors, anchors[i], sine, cosine);
    const double amplitude_sine = h.amplitude_rad * sine, amplitude_cosine = h.amplitude_rad * rate * cosine;
    dq[h.joint] += amplitude_sine;
    slope[h.joint] += amplitude_cosine;
    second[h.joint] -= amplitude_sine * (rate * rate);
    third[h.joint] -= amplitude_cosine * (rate * rate);
  }
}

std::vector<std::string> TransmissionErrorEffect::parameterNames() const {
  std::vector<std::string> names;
  for (const Harmonic& h : harmonics_) {
    char order[32];
    std::snprintf(order, sizeof order, "%g", h.cycles_per_revolution);
    const std::string prefix = joint_names_[h.joint] + ".harmonic_" + partName(h.joint, h.stage) + "_x" + order + ".";
    names.push_back(prefix + "amplitude_rad");
    names.push_back(prefix + "phase_rad");
  }
  return names;
}

std::vector<double> TransmissionErrorEffect::parameters() const {
  std::vector<double> values;
  for (const Harmonic& h : harmonics_) {
    values.push_back(h.amplitude_rad);
    values.push_back(h.phase_rad);
  }
  return values;
}

void TransmissionErrorEffect::setParameters(const std::vector<double>& values) {
  if (values.size() != 2 * harmonics_.size()) throw ParameterError("transmission_error: wrong number of parameters");
  for (std::size_t i = 0; i < harmonics_.size(); ++i) {
    if (!std::isfinite(values[2 * i]) || !std::isfinite(values[2 * i + 1])) {
      throw ParameterError("transmission_error: harmonic " + std::to_string(i) + " has a value that is not finite");
    }
    // The reader's bound, so that a fit never makes an effect whose parameter file would be refused. A
    // negative amplitude (a Monte Carlo draw, a perturbation) is the harmonic with its phase turned by pi,
    // and toJson writes it so.
    const double amplitude = values[2 * i];
    if (std::abs(amplitude) > kMaxStatedJointError) {
      throw ParameterError("transmission_error: " + parameterNames()[2 * i] + " is " + shortNumber(amplitude) +
                           " rad, beyond the plausible +-" + shortNumber(kMaxStatedJointError) +
                           " rad of a joint error");
    }
  }
  for (std::size_t i = 0; i < harmonics_.size(); ++i) {
    harmonics_[i].amplitude_rad = values[2 * i];
    harmonics_[i].phase_rad = values[2 * i + 1];
  }
}

nlohmann::json TransmissionErrorEffect::toJson() const {
  nlohmann::json list = nlohmann::json::array();
  for (const Harmonic& h : harmonics_) {
    // The reader takes amplitudes >= 0: a negative one is written as the same harmonic, phase turned by pi.
    const bool negative = h.amplitude_rad < 0.0;
    list.push_back({{"joint", joint_names_[h.joint]},
                    {"of", partName(h.joint, h.stage)},
                    {"cycles_per_revolution", h.cycles_per_revolution},
                    {"amplitude_rad", negative ? -h.amplitude_rad : h.amplitude_rad},
                    {"phase_rad", negative ? h.phase_rad + (h.phase_rad > 0.0 ? -kPi : kPi) : h.phase_rad}});
  }
  nlohmann::json json = {{"type", kType}, {"harmonics", list}};
  if (!estimate_note.empty()) json["estimate"] = estimate_note;
  return json;
}

void HarmonicDiscovery::offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const {
  if (joint < 0) return;
  const GearTrain& gears = *data.gears;
  const int n = data.robot->dof();
  const int rows = data.rows();
  std::vector<double> frequencies;  // cycles per joint revolution already offered
  const int stages = gears.stageCount(joint);
  JointVector unit = JointVector::Zero(n), unit_motor(n);
  unit[joint] = 1.0;
  gears.motorAngles(unit, unit_motor);
  for (const int s : gears.distinctParts(joint)) {
    const double ratio = gears.stageInputAngle(joint, s, unit_motor);  // part angle per joint angle
    const std::string part = gears.partName(joint, s);
    // `why` says how an order beyond the default range came to be offered.
    auto offerOrder = [&](int order, const std::string& why) {
      const double frequency = std::abs(ratio) * order;
      bool duplicate = false;
      for (double fr : frequencies) duplicate = duplicate || std::abs(fr - frequency) <= 1e-9 * std::max(1.0, fr);
      if (duplicate) return;
      frequencies.push_back(frequency);
      DiscoveryCandidate candidate;
      candidate.type = name();
      candidate.joint = joint;
      candidate.stage = s;
      candidate.part = part;
      candidate.cycles = order;
      candidate.detail = " " + part + " order " + std::to_string(order) + (why.empty() ? "" : " (" + why + ")");
      candidate.report_fields = {{"part", part}, {"stage", s}, {"order", candidate.cycles}};
      if (!why.empty()) candidate.report_fields["proposed_by"] = why;
      candidate.columns.resize(rows, 2);
      for (int i = 0; i < rows; ++i) {
        const double x = order * gears.stageInputAngle(joint, s, data.motor[i]);
        candidate.columns(i, 0) = std::sin(x);
        candidate.columns(i, 1) = std::cos(x);
      }
      candidates.push_back(std::move(candidate));
    };
    for (int order = 1; order <= data.max_harmonic_order; ++order) offerOrder(order, "");
    // The gear mesh of the stage (its input gear's teeth per revolution of its input shaft).
    if (s <= stages) {
      const int teeth = gears.stageInputTeeth(joint, s);
      if (teeth > data.max_harmonic_order) offerOrder(teeth, "gear mesh");
    }
    // Orders beyond the range, where the base fit's residual of this joint repeats with the part's angle:
    // a spectrum scan proposes the strongest when it stands out of the rest.
    if (static_cast<int>(data.joint_residual.size()) > joint && rows >= 8) {
      std::vector<double> angle(static_cast<std::size_t>(rows));
      for (int i = 0; i < rows; ++i)
        angle[static_cast<std::size_t>(i)] = gears.stageInputAngle(joint, s, data.motor[i]);
      const OrderPeak peak = strongestOrder(data.joint_residual[static_cast<std::size_t>(joint)], angle,
                                            data.max_harmonic_order + 1, kMaxScannedHarmonicOrder);
      if (peak.stands_out) offerOrder(peak.order, "spectrum scan");
    }
  }
}

std::unique_ptr<Effect> HarmonicDiscovery::makeEffect(const DiscoveryData& data,
                                                      const std::vector<FittedCandidate>& accepted) const {
  std::vector<Harmonic> harmonics;
  for (const FittedCandidate& a : accepted) {
    Harmonic h;
    h.joint = a.candidate->joint;
    h.stage = a.candidate->stage;
    h.cycles_per_revolution = a.candidate->cycles;
    // a sin x + b cos x = A sin(x + phi), A cos phi = a, A sin phi = b.
    h.amplitude_rad = std::hypot(a.theta[0], a.theta[1]);
    h.phase_rad = std::atan2(a.theta[1], a.theta[0]);
    harmonics.push_back(h);
  }
  return std::make_unique<TransmissionErrorEffect>(*data.robot, *data.gears, harmonics);
}

std::vector<NamedEstimate> HarmonicDiscovery::describe(const FittedCandidate& fitted,
                                                       const JointErrorModel& model) const {
  const DiscoveryCandidate& c = *fitted.candidate;
  const Eigen::VectorXd& a = fitted.theta;
  const Eigen::VectorXd& s = fitted.sigma;
  const double amp = std::hypot(a[0], a[1]);
  const double amp_sigma = amp > 0.0 ? std::hypot(a[0] * s[0], a[1] * s[1]) / amp : s[0];
  const std::string stem = model.robot().joints[static_cast<std::size_t>(c.joint)].name + "." + c.part + ".harmonic_" +
                           std::to_string(static_cast<int>(c.cycles));
  return {{stem + ".amplitude_rad", amp, amp_sigma},
          {stem + ".phase_rad", std::atan2(a[1], a[0]), amp > 0.0 ? amp_sigma / amp : kPi}};
}

std::string HarmonicDiscovery::physicalProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                                               const Eigen::VectorXd& theta, const JointVector&) const {
  if (candidate.joint < 0 || theta.size() != 2) return {};
  const double amplitude = std::hypot(theta[0], theta[1]);
  return transmissionProblem(data, candidate, amplitude, amplitude * candidate.cycles);
}

}  // namespace jointcomp
