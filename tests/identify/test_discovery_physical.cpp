// Discovery accepts only physical effects: a cubic compliance whose softening turns the joint's deflection back
// inside the torques the fitted rows carried is refused, however well it fits (DiscoveryFamily::physicalProblem).
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/effects/nonlinear_compliance.hpp"
#include "model/identify/discovery.hpp"
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

}  // namespace
}  // namespace jointcomp
