// What a co-simulation master relies on beyond the calls themselves (issue 39, the FMU's step semantics):
// the ModelStructure declares every direct dependency of an output on an input, a discarded step tells
// its reason to a user who did not switch debug logging on and lets the master terminate, the bounds
// the modelDescription declares are values initialisation accepts.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/fmu/fmu_master.hpp"

namespace jointcomp {
namespace {

using namespace fmutest;  // NOLINT(google-build-using-namespace): the master of fmu_master.hpp

// ---- What modelDescription.xml declares ---------------------------------------------------------------

struct Declared {
  std::map<std::uint32_t, std::set<std::uint32_t>> depends;  // output vr -> the input vrs it depends on
  std::map<std::uint32_t, std::string> name;                 // vr -> name
  std::map<std::uint32_t, std::string> causality;
  struct Bound {
    std::string name, type;
    bool has_min = false, has_max = false;
    double min = 0.0, max = 0.0;
  };
  std::vector<Bound> parameter_bounds;  // Real and Integer parameters with a min or a max
};

std::vector<std::uint32_t> numbers(const std::string& list) {
  std::vector<std::uint32_t> result;
  std::istringstream in(list);
  for (std::uint32_t n = 0; in >> n;) result.push_back(n);
  return result;
}

// The variables in file order (FMI 2 indices are 1-based positions in it) and the ModelStructure's outputs.
Declared readDeclared(int version) {
  const std::string xml = readFile(unzipped(version) + "/modelDescription.xml");
  Declared d;
  std::vector<std::uint32_t> by_position;
  const std::size_t variables_end = xml.find("</ModelVariables>");
  for (std::size_t at = xml.find("<ModelVariables>"); (at = xml.find('<', at + 1)) < variables_end;) {
    const std::size_t end = xml.find('>', at);
    const std::string vr_text = attribute(xml, at, end, "valueReference");
    if (vr_text.empty()) continue;
    const auto vr = static_cast<std::uint32_t>(std::stoul(vr_text));
    by_position.push_back(vr);
    d.name[vr] = attribute(xml, at, end, "name");
    d.causality[vr] = attribute(xml, at, end, "causality");
    // The type element: the variable's own (FMI 3) or its child (FMI 2).
    const std::size_t type_at = version == 3 ? at : xml.find('<', end);
    const std::size_t type_end = xml.find('>', type_at);
    std::string type = xml.substr(type_at + 1, xml.find_first_of(" />", type_at + 1) - type_at - 1);
    const std::string min = attribute(xml, type_at, type_end, "min"), max = attribute(xml, type_at, type_end, "max");
    if (d.causality[vr] == "parameter" && (!min.empty() || !max.empty()) && type != "Enumeration") {
      Declared::Bound b{d.name[vr], type, !min.empty(), !max.empty(), 0.0, 0.0};
      if (b.has_min) b.min = std::stod(min);
      if (b.has_max) b.max = std::stod(max);
      d.parameter_bounds.push_back(b);
    }
  }
  const std::size_t structure = xml.find("<ModelStructure>");
  const std::size_t structure_end = xml.find("</ModelStructure>");
  const std::string tag = version == 2 ? "<Unknown " : "<Output ";
  const std::size_t outputs_end = version == 2 ? xml.find("</Outputs>", structure) : structure_end;
  for (std::size_t at = structure; (at = xml.find(tag, at + 1)) < outputs_end;) {
    const std::size_t end = xml.find('>', at);
    std::uint32_t output = 0;
    if (version == 2) {
      output = by_position.at(std::stoul(attribute(xml, at, end, "index")) - 1);
    } else {
      output = static_cast<std::uint32_t>(std::stoul(attribute(xml, at, end, "valueReference")));
    }
    std::set<std::uint32_t>& inputs = d.depends[output];
    for (std::uint32_t k : numbers(attribute(xml, at, end, "dependencies"))) {
      inputs.insert(version == 2 ? by_position.at(k - 1) : k);
    }
  }
  return d;
}

// The input's role: its name without the joint number or the wrench component.
std::string role(const std::string& name) {
  if (name.rfind("tool_wrench.", 0) == 0) return "tool_wrench";
  return name.substr(0, name.find_last_of('_'));
}

// ---- The probe ---------------------------------------------------------------------------------------

struct Setting {
  long compensation;
  bool use_velocity_inputs, compensate_wrench;
};

// After ten steps of a slow move, each input moved alone (from an FMU state taken there, so that each probe
// starts from the same point): the outputs that change before any doStep depend on it directly.
void probe(int version, const Setting& s, std::map<std::uint32_t, std::set<std::uint32_t>>& found) {
  auto m = makeMaster(version);
  ASSERT_TRUE(m->instantiate()) << m->log();
  ASSERT_EQ(m->enterInitialization(), kOK) << m->log();
  ASSERT_EQ(m->setEnumeration(m->vr("reference"), 1), kOK) << m->log();  // the inputs
  ASSERT_EQ(m->setEnumeration(m->vr("compensation"), s.compensation), kOK) << m->log();
  ASSERT_EQ(m->setBoolean(m->vr("use_velocity_inputs"), s.use_velocity_inputs), kOK) << m->log();
  ASSERT_EQ(m->setBoolean(m->vr("compensate_wrench"), s.compensate_wrench), kOK) << m->log();
  const auto q = m->vrs("q_desired_", kDof), qd = m->vrs("qd_desired_", kDof), qdd = m->vrs("qdd_desired_", kDof);
  const std::vector<std::uint32_t> wrench = {m->vr("tool_wrench.force_x"),  m->vr("tool_wrench.force_y"),
                                             m->vr("tool_wrench.force_z"),  m->vr("tool_wrench.moment_x"),
                                             m->vr("tool_wrench.moment_y"), m->vr("tool_wrench.moment_z")};
  const std::vector<double> pose = {0.1, 60 * kDegree, 60 * kDegree, 0.1, 60 * kDegree, 0.1};
  const double h = 0.001;
  for (int k = 0; k <= 10; ++k) {
    std::vector<double> position(kDof), velocity(kDof, 0.05), acceleration(kDof, 0.5);
    for (int j = 0; j < kDof; ++j) position[j] = pose[j] + 0.05 * k * h + 0.25 * (k * h) * (k * h);
    ASSERT_EQ(m->setReals(q, position), kOK) << m->log();
    ASSERT_EQ(m->setReals(qd, velocity), kOK) << m->log();
    ASSERT_EQ(m->setReals(qdd, acceleration), kOK) << m->log();
    ASSERT_EQ(m->setReals(wrench, {10.0, -20.0, -50.0, 2.0, -3.0, 1.0}), kOK) << m->log();
    if (k == 0) {
      ASSERT_EQ(m->exitInitialization(), kOK) << m->log();
    }
    if (k < 10) {
      ASSERT_EQ(m->doStep(k * h, h), kOK) << m->log();
    }
  }
  void* here = nullptr;
  ASSERT_EQ(m->getState(&here), kOK) << m->log();
  std::vector<double> before, after, value;
  ASSERT_EQ(m->getReals(m->md.outputs, before), kOK) << m->log();
  std::vector<std::uint32_t> inputs = q;
  for (const auto* list : {&qd, &qdd, &wrench}) inputs.insert(inputs.end(), list->begin(), list->end());
  for (std::uint32_t input : inputs) {
    ASSERT_EQ(m->getReals({input}, value), kOK) << m->log();
    const bool position = std::find(q.begin(), q.end(), input) != q.end();
    const bool force = std::find(wrench.begin(), wrench.end(), input) != wrench.end();
    ASSERT_EQ(m->setReals({input}, {value[0] + (position ? 1e-3 : force ? 40.0 : 5.0)}), kOK) << m->log();
    ASSERT_EQ(m->getReals(m->md.outputs, after), kOK) << m->log();
    for (std::size_t i = 0; i < after.size(); ++i) {
      if (after[i] != before[i]) found[m->md.outputs[i]].insert(input);
    }
    ASSERT_EQ(m->setState(here), kOK) << m->log();
  }
  ASSERT_EQ(m->freeState(&here), kOK);
}

class FmuSemantics : public ::testing::TestWithParam<int> {};

// Every output that moves with an input before the next doStep is declared to depend on it, and every input
// role an output is declared to depend on moves it in some setting (q_ref on qdd_desired with compensation
// = dynamic: issue 39).
TEST_P(FmuSemantics, TheModelStructureDeclaresEveryDirectDependencyAProbeFinds) {
  const Declared declared = readDeclared(GetParam());
  std::map<std::uint32_t, std::set<std::uint32_t>> found;
  for (long compensation = 0; compensation <= 3; ++compensation) {
    for (bool velocities : {false, true}) {
      for (bool wrench : {false, true}) {
        SCOPED_TRACE("compensation " + std::to_string(compensation) + ", use_velocity_inputs " +
                     std::to_string(velocities) + ", compensate_wrench " + std::to_string(wrench));
        probe(GetParam(), {compensation, velocities, wrench}, found);
        if (HasFatalFailure()) return;
      }
    }
  }
  ASSERT_FALSE(declared.depends.empty());
  for (const auto& [output, inputs] : declared.depends) {
    const std::string& name = declared.name.at(output);
    const std::set<std::uint32_t>& moved = found[output];
    for (std::uint32_t input : moved) {
      EXPECT_TRUE(inputs.count(input)) << name << " moves with " << declared.name.at(input)
                                       << " before any doStep, but the ModelStructure does not declare it";
    }
    std::set<std::string> declared_roles, moved_roles;
    for (std::uint32_t input : inputs) declared_roles.insert(role(declared.name.at(input)));
    for (std::uint32_t input : moved) moved_roles.insert(role(declared.name.at(input)));
    EXPECT_EQ(declared_roles, moved_roles) << name << ": the roles declared and the roles a probe moves it with";
  }
  // The finding of issue 39 itself.
  bool q_ref_2_on_qdd_2 = false;
  for (const auto& [vr, name] : declared.name) {
    if (name != "q_ref.joint_2") continue;
    for (std::uint32_t input : found[vr]) q_ref_2_on_qdd_2 |= declared.name.at(input) == "qdd_desired.joint_2";
  }
  EXPECT_TRUE(q_ref_2_on_qdd_2);
}

// ---- A discarded step ---------------------------------------------------------------------------------

// A watchdog trip with debug logging off (loggingOn = false, as fmusim and FMPy instantiate by default): the
// reason reaches the logger, the last successful time is the start of the discarded step, the FMU asks to
// terminate and fmi2Terminate / fmi3Terminate follow.
TEST_P(FmuSemantics, ADiscardTellsItsReasonWithoutDebugLoggingAndTerminateFollows) {
  auto m = makeMaster(GetParam());
  ASSERT_TRUE(m->instantiate("robot", "", "", false));
  ASSERT_EQ(m->enterInitialization(), kOK) << m->log();
  ASSERT_EQ(m->setEnumeration(m->vr("reference"), 1), kOK) << m->log();
  ASSERT_EQ(m->exitInitialization(), kOK) << m->log();
  ASSERT_EQ(m->doStep(0.0, 0.01), kOK) << m->log();
  EXPECT_FALSE(m->terminateRequested());
  ASSERT_EQ(m->setReals({m->vr("q_desired.joint_1")}, {-0.5}), kOK);  // 0.5 rad beyond the 0.2 rad envelope
  m->messages.clear();
  EXPECT_EQ(m->doStep(0.01, 0.01), kDiscard);
  EXPECT_TRUE(m->logged("logStatusDiscard")) << m->log();
  EXPECT_TRUE(m->logged("tracking envelope")) << m->log();
  EXPECT_TRUE(m->logged("joint_1")) << m->log();
  EXPECT_EQ(m->lastSuccessfulTime(), 0.01);  // the end of the last successful step
  EXPECT_TRUE(m->terminateRequested());
  std::vector<double> time;
  EXPECT_EQ(m->getReals({m->vr("time")}, time), kOK) << m->log();
  EXPECT_EQ(time.at(0), 0.01);
  EXPECT_EQ(m->terminate(), kOK) << m->log();
}

// An error's reason reaches the logger with debug logging off too, and so does a value refused with Discard.
TEST_P(FmuSemantics, RefusalsTellTheirReasonWithoutDebugLogging) {
  auto m = makeMaster(GetParam());
  ASSERT_TRUE(m->instantiate("robot", "", "", false));
  EXPECT_EQ(m->setReals({m->vr("q_desired.joint_2")}, {100.0}), kDiscard);
  EXPECT_TRUE(m->logged("q_desired.joint_2")) << m->log();
  m->messages.clear();
  EXPECT_EQ(m->doStep(0.0, 0.001), kError);
  EXPECT_TRUE(m->logged("not allowed in state Instantiated")) << m->log();
}

// ---- Declared bounds ----------------------------------------------------------------------------------

// Every parameter at its declared min and at its declared max initialises: a bound the modelDescription
// declares is a value the FMU accepts (a min of 0 on a stiffness that must be positive is not).
TEST_P(FmuSemantics, EveryDeclaredBoundOfAParameterInitialises) {
  const Declared declared = readDeclared(GetParam());
  ASSERT_GT(declared.parameter_bounds.size(), 20u);
  for (const Declared::Bound& b : declared.parameter_bounds) {
    for (int side = 0; side < 2; ++side) {
      if (!(side == 0 ? b.has_min : b.has_max)) continue;
      const double value = side == 0 ? b.min : b.max;
      auto m = makeMaster(GetParam());
      ASSERT_TRUE(m->instantiate()) << m->log();
      ASSERT_EQ(m->enterInitialization(), kOK) << m->log();
      const int set = b.type == "Real" || b.type == "Float64" ? m->setReals({m->vr(b.name)}, {value})
                                                              : m->setInteger(m->vr(b.name), static_cast<int>(value));
      EXPECT_EQ(set, kOK) << b.name << " = " << value << "\n" << m->log();
      EXPECT_EQ(m->exitInitialization(), kOK)
          << b.name << " at its declared " << (side == 0 ? "min " : "max ") << value << " is refused:\n"
          << m->log();
    }
  }
}

// ---- A step of q_desired -----------------------------------------------------------------------------

struct StepResponse {
  int status = 0;              // of the first step that was not OK, else OK
  std::string log;             // the FMU's messages then
  std::vector<double> link;    // joint 2's link position after each step
  double highest_link = -1e9;  // rad, after the step
};

// Joint 2 held at 0 rad, then stepped by `size` (compensation none: the reference is q_desired), at
// communication steps of h for `duration`; with velocity_inputs, the master says qd_desired = 0 (a held
// step by construction), else the FMU estimates the velocities from q_desired.
StepResponse stepOfJoint2(int version, double size, double h, double duration, double envelope, bool velocity_inputs) {
  StepResponse r;
  auto m = makeMaster(version);
  EXPECT_TRUE(m->instantiate()) << m->log();
  EXPECT_EQ(m->enterInitialization(), kOK) << m->log();
  EXPECT_EQ(m->setEnumeration(m->vr("compensation"), 0), kOK) << m->log();
  EXPECT_EQ(m->setBoolean(m->vr("use_velocity_inputs"), velocity_inputs), kOK) << m->log();
  EXPECT_EQ(m->setReals({m->vr("watchdog.tracking_envelope")}, {envelope}), kOK) << m->log();
  const auto q = m->vrs("q_desired_", kDof);
  std::vector<double> desired = {0.0, 0.0, 0.5, 0.0, 0.5, 0.0};
  EXPECT_EQ(m->setReals(q, desired), kOK) << m->log();
  EXPECT_EQ(m->exitInitialization(), kOK) << m->log();
  std::vector<double> link;
  const int steps = static_cast<int>(std::lround(duration / h));
  for (int k = 0; k < steps; ++k) {
    if (k == 5) desired[1] += size;
    EXPECT_EQ(m->setReals(q, desired), kOK) << m->log();
    r.status = m->doStep(k * h, h);
    if (r.status != kOK) {
      r.log = m->log();
      return r;
    }
    EXPECT_EQ(m->getReals({m->vr("q_link.joint_2")}, link), kOK);
    r.link.push_back(link[0]);
    if (k >= 5) r.highest_link = std::max(r.highest_link, link[0]);
  }
  return r;
}

// A step of q_desired is held over the communication steps after it, not extrapolated to 3.25 times its
// size: the run is the one in which the master says the velocity is zero (a held step by construction), a
// 0.07 rad step stays inside the 0.2 rad tracking envelope, and a 1.5 rad step (the envelope widened)
// stays inside the joint's 2.4 rad limit instead of asking for 4.87 rad.
TEST_P(FmuSemantics, AStepOfQDesiredIsHeldNotExtrapolated) {
  for (double h : {0.01, 0.001}) {
    for (double size : {0.07, 1.5}) {
      SCOPED_TRACE("a step of " + std::to_string(size) + " rad at communication steps of " + std::to_string(h) + " s");
      const double envelope = size < 0.1 ? 0.2 : 5.0;
      const StepResponse held = stepOfJoint2(GetParam(), size, h, 2.0, envelope, true);
      ASSERT_EQ(held.status, kOK) << held.log;
      const StepResponse r = stepOfJoint2(GetParam(), size, h, 2.0, envelope, false);
      ASSERT_EQ(r.status, kOK) << r.log;
      ASSERT_EQ(r.link.size(), held.link.size());
      double largest = 0.0;
      for (std::size_t k = 0; k < r.link.size(); ++k) largest = std::max(largest, std::abs(r.link[k] - held.link[k]));
      std::printf(
          "step of %g rad at h = %g s: link off the held step's run by %.3g rad at most; the link's own "
          "overshoot (the controller's) %.3g rad\n",
          size, h, largest, r.highest_link - size);
      EXPECT_LT(largest, 2e-5 * size);  // the integrator's tolerance (the velocity estimate's rounding moves it)
      EXPECT_LT(r.highest_link, 2.4);
    }
  }
}

// ---- The demo move ------------------------------------------------------------------------------------

// The demo move starts from rest with no jump of its acceleration (before: 0.069 rad/s^2 at once), so the
// links start without a transient of their own.
TEST_P(FmuSemantics, TheDemoMoveStartsAtRestWithContinuousDerivatives) {
  auto m = makeMaster(GetParam());
  ASSERT_TRUE(m->instantiate()) << m->log();
  ASSERT_EQ(m->enterInitialization(), kOK) << m->log();
  ASSERT_EQ(m->setEnumeration(m->vr("reference"), 2), kOK) << m->log();  // demo
  ASSERT_EQ(m->exitInitialization(), kOK) << m->log();
  const auto planned = m->vrs("q_planned_", kDof), link = m->vrs("q_link_", kDof);
  std::vector<std::vector<double>> q;
  std::vector<double> values, links;
  double worst_acceleration = 0.0, worst_transient = 0.0;
  const double h = 0.001;
  for (int k = 0; k <= 500; ++k) {
    ASSERT_EQ(m->getReals(planned, values), kOK) << m->log();
    ASSERT_EQ(m->getReals(link, links), kOK) << m->log();
    q.push_back(values);
    for (int j = 0; j < kDof; ++j) worst_transient = std::max(worst_transient, std::abs(links[j] - values[j]));
    if (k < 500) {
      ASSERT_EQ(m->doStep(k * h, h), kOK) << m->log();
    }
  }
  for (int j = 0; j < kDof; ++j) {
    worst_acceleration = std::max(worst_acceleration, std::abs(q[2][j] - 2.0 * q[1][j] + q[0][j]) / (h * h));
  }
  std::printf(
      "demo start: acceleration over the first 2 ms %.3g rad/s^2, links off the plan by %.3g rad at most "
      "in the first 0.5 s\n",
      worst_acceleration, worst_transient);
  EXPECT_LT(worst_acceleration, 1e-4) << "rad/s^2 over the first 2 ms";
  EXPECT_LT(worst_transient, 3e-5) << "rad: the links' start-up transient (6.7e-5 rad before)";
}

INSTANTIATE_TEST_SUITE_P(Fmi, FmuSemantics, ::testing::Values(2, 3), [](const ::testing::TestParamInfo<int>& param) {
  return "Fmi" + std::to_string(param.param);
});

}  // namespace
}  // namespace jointcomp
