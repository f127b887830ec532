// The plant's own Jacobian (what CVODE's Newton iterations use) against central differences of the whole
// right-hand side, on the RX170 with its shipped parameters (joint springs, transmission error, spring
// balancer): at random moving states, near the joint limits, with a payload and a tool wrench, with two
// drives saturated, and with the motors locked or the controller off. Tolerance per entry: 1e-6 relative
// plus 1e-10 of the row's largest entry (1e-8 before the link dynamics' q and qd columns became analytic:
// they were forward differences, which a load without its rate still falls back to); the worst entry uses
// 0.06 of it. Broken once on purpose, each of these failed it: the curvature term of the
// damper with the wrong sign, the curvature's reaction on the motors left out, the Coulomb slope left out,
// the anti-windup's kd term with the wrong sign, the motors' S^T K taken as K, the loads not moved with q.
// A Jacobian that overflows makes jacobian() throw, and the integration then fails with SolverError. The
// structured Newton solver ends a tightly integrated move where SUNDIALS' dense LU does.
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Core>
#include <Eigen/LU>

#include "tests/plant/plant_test_support.hpp"

#include "model/common/errors.hpp"
#include "model/effects/transmission_error.hpp"
#include "model/io/parameter_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp {
namespace {

using namespace plant_testing;

constexpr double kRelativeTolerance = 1e-6;
constexpr double kRowFloor = 1e-10;
constexpr double kDifferencesRowFloor = 1e-8;  // for link columns by forward differences (a load without its rate)

// d(ydot)/dy at (t, y) by central differences of derivative().
Eigen::MatrixXd centralDifferences(FlexibleJointPlant& plant, double t, const std::vector<double>& y) {
  const int size = plant.stateSize();
  Eigen::MatrixXd jacobian(size, size);
  std::vector<double> shifted = y, plus(static_cast<std::size_t>(size)), minus(static_cast<std::size_t>(size));
  for (int i = 0; i < size; ++i) {
    const auto c = static_cast<std::size_t>(i);
    const double h = 1e-6 * std::max(1.0, std::abs(y[c]));
    shifted[c] = y[c] + h;
    plant.derivative(t, shifted.data(), plus.data());
    shifted[c] = y[c] - h;
    plant.derivative(t, shifted.data(), minus.data());
    shifted[c] = y[c];
    for (int r = 0; r < size; ++r) {
      const auto rr = static_cast<std::size_t>(r);
      jacobian(r, i) = (plus[rr] - minus[rr]) / (2.0 * h);
    }
  }
  return jacobian;
}

Eigen::MatrixXd analyticJacobian(FlexibleJointPlant& plant, double t, const std::vector<double>& y) {
  Eigen::MatrixXd jacobian(plant.stateSize(), plant.stateSize());
  plant.jacobian(t, y.data(), jacobian.data());
  return jacobian;
}

// Worst |analytic - reference| over its tolerance, and where.
struct Agreement {
  double worst = 0.0;
  int row = -1, column = -1;
};

Agreement compare(const Eigen::MatrixXd& analytic, const Eigen::MatrixXd& reference, double row_floor) {
  Agreement agreement;
  for (int r = 0; r < reference.rows(); ++r) {
    const double row_scale = reference.row(r).cwiseAbs().maxCoeff();
    for (int c = 0; c < reference.cols(); ++c) {
      const double tolerance = kRelativeTolerance * std::abs(reference(r, c)) + row_floor * row_scale + 1e-12;
      const double ratio = std::abs(analytic(r, c) - reference(r, c)) / tolerance;
      if (ratio > agreement.worst) agreement = {ratio, r, c};
    }
  }
  return agreement;
}

const char* blockName(int index, int n) {
  static const char* names[] = {"q", "qd", "p", "pd", "integral"};
  return names[index / n];
}

void expectAgreement(FlexibleJointPlant& plant, double t, const std::vector<double>& y, const std::string& what,
                     double row_floor = kRowFloor) {
  const Eigen::MatrixXd reference = centralDifferences(plant, t, y);
  const Eigen::MatrixXd analytic = analyticJacobian(plant, t, y);
  const Agreement a = compare(analytic, reference, row_floor);
  const int n = plant.dof();
  EXPECT_LE(a.worst, 1.0) << what << ": d(" << blockName(a.row, n) << "_" << a.row % n + 1 << ")'/d("
                          << blockName(a.column, n) << "_" << a.column % n + 1 << ") is " << analytic(a.row, a.column)
                          << ", central differences give " << reference(a.row, a.column);
}

struct Rx170 {
  JointErrorModel model = loadParameterFile(kParameters, rx170());
  std::vector<DriveParameters> drives = loadDriveParameters(kParameters, *rx170());
};

// The plant at rest at `command`, then a state moved from there: links and motors displaced together by
// `spread` rad and moving at up to `speed` rad/s, springs stretched by up to 1e-4 rad, the reference
// following with its own velocity so that the drives work without saturating.
std::vector<double> movingState(FlexibleJointPlant& plant, const JointVector& command, double spread, double speed,
                                std::mt19937& rng) {
  std::normal_distribution<double> unit(0.0, 1.0);
  const int n = plant.dof();
  plant.reset(command);
  std::vector<double> y(plant.state(), plant.state() + plant.stateSize());
  JointVector position(n), velocity(n);
  for (int j = 0; j < n; ++j) {
    const auto u = static_cast<std::size_t>(j);
    const double shift = spread * unit(rng);
    const double rate = speed * unit(rng);
    y[u] += shift;
    y[u + n] = rate;
    y[u + 2 * n] += shift + 1e-4 * unit(rng);
    y[u + 3 * n] = rate + 0.02 * unit(rng);
    position[j] = y[u + 2 * n] + 1e-4 * unit(rng);
    velocity[j] = rate;
  }
  plant.setReference(position, velocity);
  return y;
}

// The right-hand side's transmission rates without forming E = diag(s) G give the bits of the matrix
// expressions they replaced (pd + E pd, tau + E^T tau), for every chain length, coupled gears and zeros;
// the plant's stored regressions rest on it.
TEST(PlantJacobian, TransmissionRatesWithoutTheMatrixKeepItsBits) {
  std::mt19937 rng(1717u);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int n = 1; n <= kMaxJoints; ++n) {
    for (int sample = 0; sample < 200; ++sample) {
      JointVector slope(n), pd(n), torque(n);
      JointMatrix gears = JointMatrix::Zero(n, n);
      for (int i = 0; i < n; ++i) {
        slope[i] = sample % 10 == 0 && i % 2 == 0 ? 0.0 : 1e-3 * unit(rng);
        pd[i] = unit(rng);
        torque[i] = 1e3 * unit(rng);
        gears(i, i) = 100.0 * unit(rng);
      }
      for (int c = 0; c < n; ++c) {
        if (unit(rng) > 0.5) gears(static_cast<int>(rng() % static_cast<unsigned>(n)), c) = 50.0 * unit(rng);
      }
      const JointMatrix matrix = slope.asDiagonal() * gears;
      const JointVector expected_rate = pd + matrix * pd;
      const JointVector expected_reaction = torque + matrix.transpose() * torque;
      JointVector rate, reaction;
      transmissionOutputRate(slope, gears, pd, rate);
      transmissionReaction(slope, gears, torque, reaction);
      EXPECT_EQ(rate, expected_rate) << n << " joints, sample " << sample;
      EXPECT_EQ(reaction, expected_reaction) << n << " joints, sample " << sample;
    }
  }
}

TEST(PlantJacobian, HasTheAnalyticJacobianWithTheShippedEffects) {
  Rx170 rx;
  FlexibleJointPlant plant(rx.model, rx.drives);
  EXPECT_TRUE(plant.hasAnalyticJacobian());
  ASSERT_GE(rx.model.findEffect(TransmissionErrorEffect::kType), 0);
}

TEST(PlantJacobian, MatchesCentralDifferencesAtRandomMovingStates) {
  Rx170 rx;
  FlexibleJointPlant plant(rx.model, rx.drives);
  std::mt19937 rng(17);
  const JointVector commands[] = {joints({20.0, 45.0, 70.0, 30.0, 50.0, 10.0}),
                                  joints({-60.0, 10.0, -30.0, 90.0, -40.0, 120.0}),
                                  joints({100.0, -70.0, 110.0, -150.0, 80.0, -200.0})};
  int sample = 0;
  for (const JointVector& command : commands) {
    for (int k = 0; k < 4; ++k, ++sample) {
      const std::vector<double> y = movingState(plant, command, 0.02, 0.5, rng);
      expectAgreement(plant, 1e-3, y, "sample " + std::to_string(sample));
    }
  }
}

TEST(PlantJacobian, MatchesCentralDifferencesNearTheJointLimits) {
  Rx170 rx;
  FlexibleJointPlant plant(rx.model, rx.drives);
  const Robot& robot = *rx170();
  std::mt19937 rng(5);
  for (int side = 0; side < 2; ++side) {
    JointVector command(robot.dof());
    for (int j = 0; j < robot.dof(); ++j) {
      const Joint& joint = robot.joints[j];
      command[j] = side == 0 ? joint.lower + 0.02 : joint.upper - 0.02;
    }
    const std::vector<double> y = movingState(plant, command, 0.002, 0.3, rng);
    expectAgreement(plant, 1e-3, y, side == 0 ? "near the lower limits" : "near the upper limits");
  }
}

TEST(PlantJacobian, MatchesCentralDifferencesWithPayloadAndToolWrench) {
  Rx170 rx;
  FlexibleJointPlant plant(rx.model, rx.drives);
  std::mt19937 rng(23);
  const JointVector command = joints({30.0, 60.0, 40.0, -20.0, 70.0, 45.0});
  plant.setPayload(6.0, Eigen::Vector3d(0.03, -0.02, 0.08));
  std::vector<double> y = movingState(plant, command, 0.02, 0.5, rng);
  expectAgreement(plant, 1e-3, y, "with a payload");
  Vector6 wrench;
  wrench << 40.0, -25.0, 60.0, 3.0, -2.0, 1.5;
  plant.setToolWrench(wrench);
  y = movingState(plant, command, 0.02, 0.5, rng);
  expectAgreement(plant, 1e-3, y, "with a payload and a tool wrench");
}

TEST(PlantJacobian, MatchesCentralDifferencesWithASaturatedDrive) {
  Rx170 rx;
  FlexibleJointPlant plant(rx.model, rx.drives);
  std::mt19937 rng(3);
  std::vector<double> y = movingState(plant, joints({20.0, 45.0, 70.0, 30.0, 50.0, 10.0}), 0.02, 0.5, rng);
  const int n = plant.dof();
  y[static_cast<std::size_t>(4 * n + 1)] += 5000.0 / rx.drives[1].ki_nm_per_rad_s;  // joint 2 asks 5 kN m more
  y[static_cast<std::size_t>(4 * n + 5)] -= 500.0 / rx.drives[5].ki_nm_per_rad_s;
  PlantState saturated = plant.saveState();  // to read the drives' torques at y
  saturated.y = y;
  saturated.time = 1e-3;
  plant.restoreState(saturated);
  const JointVector torque = plant.motorTorques();
  ASSERT_DOUBLE_EQ(std::abs(torque[1]), rx170()->joints[1].effort_limit);
  ASSERT_DOUBLE_EQ(std::abs(torque[5]), rx170()->joints[5].effort_limit);
  expectAgreement(plant, 1e-3, y, "joints 2 and 6 saturated");
}

TEST(PlantJacobian, MatchesCentralDifferencesWithMotorsLockedOrControlOff) {
  Rx170 rx;
  std::mt19937 rng(11);
  for (int variant = 0; variant < 2; ++variant) {
    PlantOptions options;
    options.control = variant == 1;
    options.motors_locked = variant == 0;
    FlexibleJointPlant plant(rx.model, rx.drives, options);
    const std::vector<double> y = movingState(plant, joints({20.0, 45.0, 70.0, 30.0, 50.0, 10.0}), 0.02, 0.5, rng);
    expectAgreement(plant, 1e-3, y, variant == 0 ? "motors locked, no control" : "control on, motors free");
  }
  PlantOptions options;
  options.control = false;
  FlexibleJointPlant plant(rx.model, rx.drives, options);
  const std::vector<double> y = movingState(plant, joints({-40.0, 30.0, 20.0, 60.0, -30.0, 90.0}), 0.02, 0.5, rng);
  expectAgreement(plant, 1e-3, y, "no control, motors free");
}

// The link dynamics' q and qd columns by tangent passes of inverse dynamics and the loads' rates against the
// forward differences of the link dynamics they replaced (PlantOptions::analytic_link_derivatives false):
// the same within those differences' own error (sqrt(eps) steps: ~1e-8 of the entry's scale), and every
// other entry the same bits.
TEST(PlantJacobian, LinkColumnsMatchTheirDifferenceQuotients) {
  Rx170 rx;
  PlantOptions by_differences;
  by_differences.analytic_link_derivatives = false;
  FlexibleJointPlant analytic(rx.model, rx.drives), reference(rx.model, rx.drives, by_differences);
  std::mt19937 rng(1717);
  const int n = analytic.dof();
  analytic.setPayload(6.0, Eigen::Vector3d(0.03, -0.02, 0.08));
  reference.setPayload(6.0, Eigen::Vector3d(0.03, -0.02, 0.08));
  for (int sample = 0; sample < 6; ++sample) {
    const std::vector<double> y = movingState(analytic, joints({20.0, 45.0, 70.0, 30.0, 50.0, 10.0}), 0.3, 1.0, rng);
    reference.restoreState(analytic.saveState());
    const Eigen::MatrixXd a = analyticJacobian(analytic, 1e-3, y), d = analyticJacobian(reference, 1e-3, y);
    for (int r = 0; r < a.rows(); ++r) {
      const double row_scale = d.row(r).cwiseAbs().maxCoeff();
      for (int c = 0; c < a.cols(); ++c) {
        const bool link_column = r >= n && r < 2 * n && c < 2 * n;
        if (link_column) {
          EXPECT_NEAR(a(r, c), d(r, c), 1e-6 * std::abs(d(r, c)) + 1e-7 * row_scale)
              << "sample " << sample << ", d(" << blockName(r, n) << "_" << r % n + 1 << ")'/d(" << blockName(c, n)
              << "_" << c % n + 1 << ")";
        } else {
          EXPECT_EQ(a(r, c), d(r, c)) << "sample " << sample << ", entry (" << r << ", " << c << ")";
        }
      }
    }
  }
}

// What a test effect without parameters leaves as it is.
template <class Derived>
class ParameterlessEffect : public Effect {
public:
  std::vector<std::string> parameterNames() const override { return {}; }
  std::vector<double> parameters() const override { return {}; }
  void setParameters(const std::vector<double>&) override {}
  nlohmann::json toJson() const override { return {}; }
  std::unique_ptr<Effect> clone() const override { return std::make_unique<Derived>(); }
};

// The RX170's model with one more effect.
JointErrorModel withEffect(const JointErrorModel& model, std::unique_ptr<Effect> extra) {
  std::vector<std::unique_ptr<Effect>> effects;
  for (int i = 0; i < model.effectCount(); ++i) effects.push_back(model.effect(i).clone());
  effects.push_back(std::move(extra));
  return JointErrorModel(model.sharedRobot(), model.gears(), std::move(effects));
}

// A load that does not know its rate: the link columns fall back to differences, and still match.
class LoadWithoutRate : public ParameterlessEffect<LoadWithoutRate> {
public:
  std::string type() const override { return "load_without_rate"; }
  EffectRole role() const override { return EffectRole::Load; }
  void addLoadTorque(const Robot&, const RobotWorkspace&, JointContext& ctx) const override {
    ctx.load_torque[1] += 40.0 * std::sin(ctx.q[1] + 0.5 * ctx.q[2]);
  }
};

TEST(PlantJacobian, ALoadWithoutItsRateFallsBackToDifferences) {
  Rx170 rx;
  const JointErrorModel model = withEffect(rx.model, std::make_unique<LoadWithoutRate>());
  FlexibleJointPlant plant(model, rx.drives);
  std::mt19937 rng(41);
  const std::vector<double> y = movingState(plant, joints({20.0, 45.0, 70.0, 30.0, 50.0, 10.0}), 0.02, 0.5, rng);
  expectAgreement(plant, 1e-3, y, "a load without its rate", kDifferencesRowFloor);
}

// The structured Newton solver (elimination down to qd and pd) against a dense LU of I - gamma J, at moving
// states, a saturated one and with the motors locked, for the step sizes CVODE takes and larger.
TEST(PlantJacobian, StructuredNewtonSolveMatchesADenseLu) {
  Rx170 rx;
  std::mt19937 rng(29);
  std::normal_distribution<double> unit(0.0, 1.0);
  for (int variant = 0; variant < 3; ++variant) {
    PlantOptions options;
    options.motors_locked = variant == 2;
    FlexibleJointPlant plant(rx.model, rx.drives, options);
    std::vector<double> y = movingState(plant, joints({-30.0, 60.0, 20.0, 45.0, 80.0, -60.0}), 0.02, 0.5, rng);
    if (variant == 1) y[static_cast<std::size_t>(4 * plant.dof())] += 5000.0 / rx.drives[0].ki_nm_per_rad_s;
    const int size = plant.stateSize();
    const Eigen::MatrixXd jacobian = analyticJacobian(plant, 1e-3, y);
    for (double gamma : {1e-5, 1e-3, 0.1}) {
      const Eigen::MatrixXd newton = Eigen::MatrixXd::Identity(size, size) - gamma * jacobian;
      Eigen::VectorXd b(size);
      for (int i = 0; i < size; ++i) b[i] = unit(rng);
      const Eigen::VectorXd dense = newton.fullPivLu().solve(b);
      Eigen::VectorXd structured(size);
      plant.solveNewtonSystem(1e-3, y.data(), gamma, b.data(), structured.data());
      EXPECT_LE((structured - dense).norm(), 1e-9 * dense.norm())
          << "variant " << variant << ", gamma " << gamma << ": residual of the structured solution "
          << (newton * structured - b).norm();
    }
  }
}

// From rest, every drive moves at its own constant speed for 0.2 s, the reference updated every 4 ms.
void moveEveryDrive(FlexibleJointPlant& plant) {
  const JointVector start = joints({20.0, 45.0, 70.0, 30.0, 50.0, 10.0});
  plant.reset(start);
  const JointVector velocity = joints({30.0, -20.0, 25.0, 60.0, -45.0, 90.0});
  for (int k = 1; k <= 50; ++k) {
    plant.setReference(start + velocity * (0.004 * k), velocity);
    plant.advance(0.004 * k);
  }
}

// The structured Newton solver (elimination down to qd and pd) against SUNDIALS' dense LU of the same
// Jacobian: a move of every drive, integrated tightly both ways, ends in the same state, and Newton needs
// as many iterations per step (a wrong solve would still converge, but slower).
TEST(PlantJacobian, StructuredSolverFollowsTheDenseLu) {
  Rx170 rx;
  PlantOptions options;
  options.relative_tolerance = 1e-10;
  options.absolute_tolerance = 1e-12;
  std::vector<std::vector<double>> ends;
  std::vector<double> iterations_per_step;
  for (bool structured : {false, true}) {
    options.structured_linear_solver = structured;
    FlexibleJointPlant plant(rx.model, rx.drives, options);
    moveEveryDrive(plant);
    ends.emplace_back(plant.state(), plant.state() + plant.stateSize());
    const PlantStatistics statistics = plant.statistics();
    iterations_per_step.push_back(static_cast<double>(statistics.nonlinear_iterations) / statistics.steps);
  }
  EXPECT_LE(iterations_per_step[1], 1.05 * iterations_per_step[0]);
  for (std::size_t i = 0; i < ends[0].size(); ++i) {
    EXPECT_NEAR(ends[1][i], ends[0][i], 1e-7 * (1.0 + std::abs(ends[0][i]))) << "state " << i;
  }
}

// The reuse knobs reach CVODE: on the same move, a fresh Jacobian and Newton matrix every step cost far more
// Jacobians and setups than the defaults; the end states agree within the tolerances.
TEST(PlantJacobian, ReuseKnobsReachCvode) {
  Rx170 rx;
  std::vector<PlantStatistics> statistics;
  std::vector<JointVector> ends;
  for (bool every_step : {true, false}) {
    PlantOptions options;
    if (every_step) {
      options.jacobian_reuse_steps = 1;
      options.newton_setup_steps = 1;
    }
    FlexibleJointPlant plant(rx.model, rx.drives, options);
    moveEveryDrive(plant);
    statistics.push_back(plant.statistics());
    ends.push_back(plant.linkPositions());
  }
  EXPECT_GE(statistics[0].jacobian_evaluations, statistics[0].steps / 2);
  EXPECT_LT(statistics[1].jacobian_evaluations, statistics[0].jacobian_evaluations / 4);
  EXPECT_GT(statistics[0].linear_solver_setups, 2 * statistics[1].linear_solver_setups);
  EXPECT_LE((ends[0] - ends[1]).cwiseAbs().maxCoeff(), 1e-6);
}

// A transmission error with an enormous slope and no error of its own: at rest the right-hand side stays
// finite (the slope multiplies motor rates that are zero), the Jacobian (slope squared) does not.
class OverflowingSlope : public ParameterlessEffect<OverflowingSlope> {
public:
  std::string type() const override { return "overflowing_slope"; }
  EffectRole role() const override { return EffectRole::JointError; }
  bool dependsOnCommand() const override { return true; }
  void addJointError(const Robot&, const JointContext&, JointVector&) const override {}
  bool addMotorSlope(const Robot&, const JointContext&, JointVector& slope) const override {
    slope[0] += 1e200;
    return true;
  }
};

TEST(PlantJacobian, ANonFiniteJacobianStopsTheIntegration) {
  Rx170 rx;
  const JointErrorModel model = withEffect(rx.model, std::make_unique<OverflowingSlope>());
  PlantOptions options;
  options.control = false;
  FlexibleJointPlant plant(model, rx.drives, options);
  ASSERT_TRUE(plant.hasAnalyticJacobian());
  plant.reset(joints({20.0, 45.0, 70.0, 30.0, 50.0, 10.0}));
  const std::vector<double> y(plant.state(), plant.state() + plant.stateSize());
  std::vector<double> ydot(y.size());
  plant.derivative(0.0, y.data(), ydot.data());
  for (double v : ydot) ASSERT_TRUE(std::isfinite(v));
  std::vector<double> jacobian(y.size() * y.size());
  EXPECT_THROW(plant.jacobian(0.0, y.data(), jacobian.data()), SolverError);
  expectThrowMentioning<SolverError>([&] { plant.advance(0.01); }, {"CVODE"}, "advance with a non-finite Jacobian");
}

}  // namespace
}  // namespace jointcomp
