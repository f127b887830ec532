// Discovery and calibration accept only physical effects: each family states its constraint
// (DiscoveryFamily::physicalProblem, ComplianceEffect::implausibility) and a fit that crosses it is refused,
// however well it fits: a cubic compliance whose softening turns the joint's deflection back inside the
// torques the fitted rows carried, a deflection or lost motion beyond kMaxPlausibleJointError, a negative
// lost motion, a stiffness below the plausible, a transmission error (harmonic or table) so large or so
// steep that the link would turn against its motor.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/effects/backlash.hpp"
#include "model/effects/compliance.hpp"
#include "model/effects/hysteresis.hpp"
#include "model/effects/nonlinear_compliance.hpp"
#include "model/effects/periodic_table.hpp"
#include "model/effects/transmission_error.hpp"
#include "model/identify/discovery.hpp"
#include "model/identify/geometric_calibration.hpp"
#include "tests/identify/identify_test_support.hpp"

namespace jointcomp {
namespace {

using namespace identify_test;

TEST(DiscoveryPhysical, ACubicComplianceMayNotTurnTheDeflectionBackInsideTheFittedTorques) {
  const JointErrorModel model = rx170Model();
  DiscoveryData data;
  data.robot = &model.robot();
  data.gears = &model.gears();
  for (double torque : {-100.0, 20.0, 60.0}) {
    JointVector tau = JointVector::Zero(6);
    tau[1] = torque;
    data.load_torque.push_back(tau);
    data.command.push_back(JointVector::Zero(6));
  }
  DiscoveryCandidate candidate;
  candidate.type = "nonlinear_compliance";
  candidate.joint = 1;
  JointVector compliance = JointVector::Zero(6);
  compliance[1] = 1e-6;  // rad/(N m)
  const NonlinearComplianceDiscovery family;
  auto problem = [&](double cubic) {
    return family.physicalProblem(data, candidate, Eigen::VectorXd::Constant(1, cubic), compliance);
  };
  EXPECT_EQ(problem(5e-11), "");   // stiffening: always physical
  EXPECT_EQ(problem(-1e-11), "");  // 1e-6 - 3e-11 * 100^2 = 7e-7 > 0
  // At the boundary the slope reaches zero at the largest fitted torque (100 N m): refused.
  const double boundary = -1e-6 / (3.0 * 100.0 * 100.0);
  EXPECT_NE(problem(boundary), "");
  EXPECT_EQ(problem(boundary * 0.99), "");
  const std::string message = problem(-1e-9);
  EXPECT_NE(message.find("turns back"), std::string::npos) << message;
  EXPECT_NE(message.find(model.robot().joints[1].name), std::string::npos) << message;
}

TEST(DiscoveryPhysical, AFitThatWouldTurnBackIsNotAccepted) {
  // The truth softens joint 2 so much that its deflection turns back within the arm's torques: the fit wants
  // exactly that cubic, and discovery refuses it.
  JointErrorModel truth = rx170Model();
  truth.addEffect(
      std::make_unique<NonlinearComplianceEffect>(truth.robot(), std::vector<double>{0, -1e-11, 0, 0, 0, 0}));
  DiscoveryOptions options;
  options.types = {"nonlinear_compliance"};
  options.max_steps = 2;
  const DiscoveryResult r =
      discoverEffects(rx170Model(), {randomCampaign(truth, 240, 71)}, {randomCampaign(truth, 120, 72)}, options);
  std::string rejected = r.rejected_at_stop;
  for (const DiscoveryStep& s : r.steps) rejected += " " + s.rejected;
  std::printf("[ physical ] steps %zu; rejected: %s\n", r.steps.size(), rejected.c_str());
  for (const DiscoveryStep& s : r.steps)
    for (const DiscoveredParameter& p : s.parameters)
      std::printf("[ physical ]   %s%s %s = %g\n", s.type.c_str(), s.detail.c_str(), p.name.c_str(), p.value);
  for (const DiscoveryStep& s : r.steps) {
    for (const DiscoveredParameter& p : s.parameters) EXPECT_GE(p.value, -1e-9) << p.name;  // no cubic near the truth's
    EXPECT_FALSE(s.type == "nonlinear_compliance" && s.joint == 1) << "the turning-back cubic of joint 2 was accepted";
  }
  EXPECT_NE(rejected.find("not physical"), std::string::npos) << rejected;
  // Accepted at its selection, joint 2's cubic went beyond the physical in the joint refit: the step was undone.
  EXPECT_NE(r.rejected_at_stop.find("undone after its refit"), std::string::npos) << r.rejected_at_stop;
}

// Rows whose joint-2 torque runs over `torques` (the others zero).
DiscoveryData joint2Data(const JointErrorModel& model, std::initializer_list<double> torques) {
  DiscoveryData data;
  data.robot = &model.robot();
  data.gears = &model.gears();
  for (double torque : torques) {
    JointVector tau = JointVector::Zero(6);
    tau[1] = torque;
    data.load_torque.push_back(tau);
    data.command.push_back(JointVector::Zero(6));
    data.approach.push_back(JointVector::Zero(6));
  }
  return data;
}

TEST(DiscoveryPhysical, ACubicComplianceMayNotDeflectBeyondThePlausible) {
  const JointErrorModel model = rx170Model();
  const DiscoveryData data = joint2Data(model, {-100.0, 20.0, 60.0});
  DiscoveryCandidate candidate;
  candidate.type = "nonlinear_compliance";
  candidate.joint = 1;
  JointVector compliance = JointVector::Zero(6);
  compliance[1] = 1e-6;  // rad/(N m): 1e-4 rad at 100 N m
  const NonlinearComplianceDiscovery family;
  auto problem = [&](double cubic) {
    return family.physicalProblem(data, candidate, Eigen::VectorXd::Constant(1, cubic), compliance);
  };
  // Stiffening, monotone: 1e-6 * 100 + c3 * 100^3 reaches the bound at c3 = (0.01 - 1e-4) / 1e6.
  const double boundary = (kMaxPlausibleJointError - 1e-4) / 1e6;
  EXPECT_EQ(problem(boundary * 0.99), "");
  const std::string message = problem(boundary * 1.01);
  EXPECT_NE(message.find("beyond the plausible"), std::string::npos) << message;
}

TEST(DiscoveryPhysical, ALostMotionLagsAndStaysSmall) {
  const JointErrorModel model = rx170Model();
  const DiscoveryData data = joint2Data(model, {-50.0, 20.0, 40.0});
  DiscoveryCandidate candidate;
  candidate.joint = 1;
  const BacklashDiscovery backlash;
  const HysteresisDiscovery hysteresis;
  const JointVector compliance = JointVector::Zero(6);
  auto backlashProblem = [&](double width) {
    return backlash.physicalProblem(data, candidate, Eigen::VectorXd::Constant(1, width), compliance);
  };
  auto hysteresisProblem = [&](double width) {
    return hysteresis.physicalProblem(data, candidate, Eigen::VectorXd::Constant(1, width), compliance);
  };
  EXPECT_EQ(backlashProblem(1e-4), "");
  EXPECT_NE(backlashProblem(-1e-5).find("negative"), std::string::npos);
  // The joint moves by half the width each way: the bound is at twice kMaxPlausibleJointError.
  EXPECT_EQ(backlashProblem(2.0 * kMaxPlausibleJointError * 0.99), "");
  EXPECT_NE(backlashProblem(2.0 * kMaxPlausibleJointError * 1.01), "");
  // Hysteresis moves it by h |tau| / 2, at most at the largest torque (50 N m).
  const double bound = 2.0 * kMaxPlausibleJointError / 50.0;
  EXPECT_EQ(hysteresisProblem(bound * 0.99), "");
  EXPECT_NE(hysteresisProblem(bound * 1.01).find("beyond the plausible"), std::string::npos);
  EXPECT_NE(hysteresisProblem(-1e-7).find("negative"), std::string::npos);
}

// Rows sweeping joint 2 (index 1) over +-1 rad, the others at rest, with the motor angles of `model`'s gears.
DiscoveryData sweptJoint2(const JointErrorModel& model) {
  DiscoveryData data;
  data.robot = &model.robot();
  data.gears = &model.gears();
  for (int i = 0; i < 400; ++i) {
    JointVector q = JointVector::Zero(6), motor(6);
    q[1] = -1.0 + 2.0 * i / 399.0;
    model.gears().motorAngles(q, motor);
    data.command.push_back(q);
    data.motor.push_back(motor);
    data.load_torque.push_back(JointVector::Zero(6));
  }
  return data;
}

// Joint 2's motor radians per joint radian, from the gear train's own motor angles of a unit joint turn.
double joint2MotorRatio(const JointErrorModel& model, int motor) {
  JointVector unit = JointVector::Zero(6), unit_motor(6);
  unit[1] = 1.0;
  model.gears().motorAngles(unit, unit_motor);
  return std::abs(model.gears().stageInputAngle(1, motor, unit_motor));
}

TEST(DiscoveryPhysical, AHarmonicStaysSmallAndNeverTurnsTheLinkAgainstTheMotor) {
  const JointErrorModel model = rx170Model();
  const DiscoveryData data = sweptJoint2(model);
  const int motor = model.gears().distinctParts(1).front();
  const double ratio = joint2MotorRatio(model, motor);
  ASSERT_GT(ratio, 10.0);
  DiscoveryCandidate candidate;
  candidate.type = "harmonic";
  candidate.joint = 1;
  candidate.stage = motor;
  candidate.cycles = 3;
  const HarmonicDiscovery family;
  const auto problem = [&](double amplitude) {  // split between the sine and the cosine at 3:4
    return family.physicalProblem(data, candidate, Eigen::Vector2d(0.6 * amplitude, 0.8 * amplitude),
                                  JointVector::Zero(6));
  };
  // The link stands still when the error's slope, amplitude * order * ratio, reaches 1.
  const double standing = 1.0 / (3.0 * ratio);
  EXPECT_EQ(problem(0.99 * standing), "");
  const std::string steep = problem(1.01 * standing);
  EXPECT_NE(steep.find("against the motor"), std::string::npos) << steep;
  EXPECT_NE(steep.find(model.robot().joints[1].name), std::string::npos) << steep;
  candidate.cycles = 1;
  candidate.stage = model.gears().distinctParts(1).back();  // the output: slope = amplitude
  EXPECT_EQ(problem(0.009), "");
  const std::string large = problem(0.011);
  EXPECT_NE(large.find("beyond the plausible"), std::string::npos) << large;
}

TEST(DiscoveryPhysical, APeriodicTableStaysSmallAndNeverTurnsTheLinkAgainstTheMotor) {
  const JointErrorModel model = rx170Model();
  const DiscoveryData data = sweptJoint2(model);
  const int motor = model.gears().distinctParts(1).front();
  const double ratio = joint2MotorRatio(model, motor);
  const int knots = 16;
  DiscoveryCandidate candidate;
  candidate.type = "periodic";
  candidate.joint = 1;
  candidate.stage = motor;
  candidate.cycles = knots;
  // A table of two cycles per motor turn, values A sin(4 pi k / 16) at every knot (the sweep visits them
  // all). Its steepest slope per motor radian, from the values alone by central differences of the spline.
  // The candidate's coefficients are the fitted knots' values (one knot is left at zero).
  const std::vector<int> kept = fittedTableKnots(data, 1, motor, knots);
  ASSERT_EQ(kept.size(), static_cast<std::size_t>(knots - 1));
  const auto full = [&](double amplitude) {
    Eigen::VectorXd values = Eigen::VectorXd::Zero(knots);
    for (int k : kept) values[k] = amplitude * std::sin(4.0 * M_PI * k / knots);
    return values;
  };
  const auto table = [&](double amplitude) {
    Eigen::VectorXd theta(static_cast<Eigen::Index>(kept.size()));
    for (std::size_t c = 0; c < kept.size(); ++c) theta[static_cast<Eigen::Index>(c)] = full(amplitude)[kept[c]];
    return theta;
  };
  const auto valueAt = [&](const Eigen::VectorXd& values, double angle) {
    const PeriodicSplineWeights w = periodicSplineWeights(knots, angle);
    double v = 0.0;
    for (int k = 0; k < 4; ++k) v += w.weight[k] * values[(w.first + k) % knots];
    return v;
  };
  double steepest = 0.0;
  const double h = 1e-6;
  for (int n = 0; n < 64 * knots; ++n) {
    const double angle = 2.0 * M_PI * (n + 0.5) / (64 * knots);
    steepest = std::max(steepest, std::abs(valueAt(full(1.0), angle + h) - valueAt(full(1.0), angle - h)) / (2 * h));
  }
  const double standing = 1.0 / (steepest * ratio);  // the amplitude at which the link stands still
  const PeriodicTableDiscovery family;
  const auto problem = [&](double amplitude) {
    return family.physicalProblem(data, candidate, table(amplitude), JointVector::Zero(6));
  };
  EXPECT_EQ(problem(0.98 * standing), "");
  const std::string steep = problem(1.02 * standing);
  EXPECT_NE(steep.find("against the motor"), std::string::npos) << steep;
  ASSERT_LT(standing, 0.008);
  // Larger than the plausible (the spline's largest value is 0.97 of the knots'), whatever its slope.
  const std::string large = problem(0.013);
  EXPECT_NE(large.find("beyond the plausible"), std::string::npos) << large;
}

TEST(CalibrationPhysical, AComplianceIsPositiveStiffEnoughAndDeflectsLittle) {
  const double min_stiffness = ComplianceEffect::kMinPlausibleStiffness;
  EXPECT_EQ(ComplianceEffect::implausibility(1.0 / (min_stiffness * 1.01), 0.0, "j"), "");
  EXPECT_NE(ComplianceEffect::implausibility(1.0 / (min_stiffness * 0.99), 0.0, "j").find("below the plausible"),
            std::string::npos);
  EXPECT_NE(ComplianceEffect::implausibility(-1e-6, 0.0, "j").find("not positive"), std::string::npos);
  EXPECT_NE(ComplianceEffect::implausibility(0.0, 0.0, "j").find("not positive"), std::string::npos);
  // 1e-4 rad/(N m) at 100 N m is 0.01 rad: the bound.
  const double deflection = ComplianceEffect::kMaxPlausibleDeflection;
  EXPECT_EQ(ComplianceEffect::implausibility(deflection / 100.0 * 0.99, 100.0, "j"), "");
  const std::string message = ComplianceEffect::implausibility(deflection / 100.0 * 1.01, 100.0, "joint_9");
  EXPECT_NE(message.find("deflects"), std::string::npos) << message;
  EXPECT_NE(message.find("joint_9"), std::string::npos) << message;
}

TEST(CalibrationPhysical, AStiffnessBelowThePlausibleIsNotIdentified) {
  // The truth's joint 5 is far softer than a real joint (60 N m/rad: it would turn by several 0.01 rad under
  // the wrist's weight): the calibration, tempted by the data, holds that compliance at the nominal value and
  // says why.
  const JointErrorModel nominal = rx170Model();
  std::vector<std::unique_ptr<Effect>> effects;
  for (int i = 0; i < nominal.effectCount(); ++i) {
    if (nominal.effect(i).type() != ComplianceEffect::kType) effects.push_back(nominal.effect(i).clone());
  }
  std::vector<double> stiffness;
  for (int j = 0; j < 6; ++j) stiffness.push_back(stiffnessOf(nominal, j));
  stiffness[4] = 60.0;
  effects.push_back(std::make_unique<ComplianceEffect>(nominal.robot(), stiffness));
  const JointErrorModel truth(rx170(), nominal.gears(), std::move(effects));
  const GeometricCalibrationResult result = calibrateGeometry(nominal, randomCampaign(truth, 200, 81));
  const std::string name = nominal.robot().joints[4].name + ".compliance_rad_per_nm";
  bool found = false;
  for (const ParameterEstimate& p : result.parameters) {
    if (p.name != name) continue;
    found = true;
    EXPECT_FALSE(p.identified) << p.value;
    EXPECT_NE(p.fixed_because.find("not physical"), std::string::npos) << p.fixed_because;
    EXPECT_DOUBLE_EQ(p.value, p.nominal);
  }
  EXPECT_TRUE(found);
  for (const ParameterEstimate& p : result.parameters) {
    if (p.identified && p.name.find("compliance") != std::string::npos) {
      EXPECT_GT(p.value, 0.0) << p.name;
      EXPECT_LT(p.value, 1.0 / ComplianceEffect::kMinPlausibleStiffness) << p.name;
    }
  }
}

}  // namespace
}  // namespace jointcomp
