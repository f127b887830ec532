// Misuse and failure of the flexible-joint plant: wrong calls throw InvalidArgument naming what is wrong,
// an integration CVODE cannot complete throws SolverError carrying CVODE's reason (never an abort), and
// the plant is left at its last good time, still usable.
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/plant/plant_test_support.hpp"

#include "model/common/errors.hpp"
#include "model/effects/compliance.hpp"
#include "model/io/parameter_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp {
namespace {

using namespace plant_testing;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

JointErrorModel rx170Model() { return loadParameterFile(kParameters, rx170()); }
std::vector<DriveParameters> rx170Drives() { return loadDriveParameters(kParameters, *rx170()); }

JointVector home() {
  JointVector q(6);
  q << 0.0, 60.0, 60.0, 0.0, 60.0, 0.0;
  return q * kDegree;
}

TEST(PlantMisuse, AdvanceMustGoForward) {
  FlexibleJointPlant plant(rx170Model(), rx170Drives());
  plant.reset(home(), 1.0);
  EXPECT_THROW(plant.advance(1.0), InvalidArgument);
  EXPECT_THROW(plant.advance(0.5), InvalidArgument);
  EXPECT_THROW(plant.advance(kNaN), InvalidArgument);
  EXPECT_THROW(plant.advance(std::numeric_limits<double>::infinity()), InvalidArgument);
  EXPECT_EQ(plant.time(), 1.0);
  plant.advance(1.01);
  EXPECT_THROW(plant.advance(1.01), InvalidArgument);
  EXPECT_THROW(plant.advance(1.005), InvalidArgument);
  EXPECT_EQ(plant.time(), 1.01);
  plant.advance(1.02);  // still usable
  EXPECT_EQ(plant.time(), 1.02);
}

TEST(PlantMisuse, NonFiniteOrMisSizedInputsAreRejected) {
  FlexibleJointPlant plant(rx170Model(), rx170Drives());
  plant.reset(home());
  JointVector bad = home();
  bad[2] = kNaN;
  const JointVector zero = JointVector::Zero(6);
  expectThrowMentioning<InvalidArgument>([&] { plant.setReference(bad, zero); }, {"joint_3"}, "NaN reference");
  expectThrowMentioning<InvalidArgument>([&] { plant.setReference(home(), bad); }, {"joint_3"}, "NaN velocity");
  EXPECT_THROW(plant.setReference(JointVector::Zero(5), zero), InvalidArgument);
  EXPECT_THROW(plant.reset(bad), InvalidArgument);
  EXPECT_THROW(plant.reset(home(), kNaN), InvalidArgument);
  Vector6 wrench = Vector6::Zero();
  wrench[4] = kNaN;
  EXPECT_THROW(plant.setToolWrench(wrench), InvalidArgument);
  EXPECT_THROW(plant.setPayload(-1.0, Eigen::Vector3d::Zero()), InvalidArgument);
  EXPECT_THROW(plant.setPayload(kNaN, Eigen::Vector3d::Zero()), InvalidArgument);
  // Nothing of that reached the plant: it still sits at home and integrates.
  plant.advance(0.05);
  EXPECT_TRUE(plant.linkPositions().allFinite());
  EXPECT_LT((plant.motorPositions() - home()).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(PlantMisuse, RestoreRejectsAForeignState) {
  FlexibleJointPlant plant(rx170Model(), rx170Drives());
  plant.reset(home());
  const PlantState good = plant.saveState();

  PlantState shorter = good;
  shorter.y.pop_back();
  EXPECT_THROW(plant.restoreState(shorter), InvalidArgument);
  PlantState longer = good;
  longer.y.push_back(0.0);
  EXPECT_THROW(plant.restoreState(longer), InvalidArgument);
  PlantState empty;
  EXPECT_THROW(plant.restoreState(empty), InvalidArgument);
  PlantState reference = good;
  reference.reference = JointVector::Zero(5);
  EXPECT_THROW(plant.restoreState(reference), InvalidArgument);
  PlantState not_finite = good;
  not_finite.y[7] = kNaN;
  EXPECT_THROW(plant.restoreState(not_finite), InvalidArgument);
  // The plant kept its own state.
  const PlantState after = plant.saveState();
  EXPECT_EQ(after.y, good.y);
  EXPECT_EQ(after.time, good.time);
}

TEST(PlantMisuse, ConstructionChecksTheModelAndTheDrives) {
  const JointErrorModel full = rx170Model();
  std::vector<std::unique_ptr<Effect>> effects;
  for (int i = 0; i < full.effectCount(); ++i) {
    if (full.effect(i).type() != ComplianceEffect::kType) effects.push_back(full.effect(i).clone());
  }
  const JointErrorModel no_springs(full.sharedRobot(), full.gears(), std::move(effects));
  ASSERT_EQ(no_springs.findEffect(ComplianceEffect::kType), -1);
  expectThrowMentioning<InvalidArgument>([&] { FlexibleJointPlant plant(no_springs, rx170Drives()); }, {"compliance"},
                                         "model without compliance");

  std::vector<DriveParameters> five = rx170Drives();
  five.pop_back();
  EXPECT_THROW(FlexibleJointPlant(full, five), InvalidArgument);

  PlantOptions options;
  options.relative_tolerance = 0.0;
  EXPECT_THROW(FlexibleJointPlant(full, rx170Drives(), options), InvalidArgument);
  options = PlantOptions();
  options.max_order = 6;
  EXPECT_THROW(FlexibleJointPlant(full, rx170Drives(), options), InvalidArgument);
  options = PlantOptions();
  options.max_steps_per_advance = 0;
  EXPECT_THROW(FlexibleJointPlant(full, rx170Drives(), options), InvalidArgument);
  options = PlantOptions();
  options.jacobian_reuse_steps = 0;
  expectThrowMentioning<InvalidArgument>([&] { FlexibleJointPlant plant(full, rx170Drives(), options); },
                                         {"jacobian_reuse_steps", "0"}, "no Jacobian steps");
  options = PlantOptions();
  options.newton_setup_steps = -3;
  expectThrowMentioning<InvalidArgument>([&] { FlexibleJointPlant plant(full, rx170Drives(), options); },
                                         {"newton_setup_steps", "-3"}, "negative setup steps");
  for (double change : {0.0, -1.0, 11.0, std::numeric_limits<double>::quiet_NaN()}) {
    options = PlantOptions();
    options.newton_setup_gamma_change = change;
    expectThrowMentioning<InvalidArgument>([&] { FlexibleJointPlant plant(full, rx170Drives(), options); },
                                           {"newton_setup_gamma_change"}, "gamma change " + std::to_string(change));
  }
}

// Asserts that advancing `plant` by `span` throws SolverError naming one of CVODE's return flags, and
// that the plant is then left at a time between where it was and where it was asked to go, finite.
void expectSolverFailure(FlexibleJointPlant& plant, double span, const std::vector<std::string>& reasons,
                         const std::string& what) {
  const double start = plant.time();
  try {
    plant.advance(start + span);
    ADD_FAILURE() << what << ": advance() did not fail";
    return;
  } catch (const SolverError& e) {
    const std::string message = e.what();
    bool named = false;
    for (const std::string& reason : reasons) named = named || message.find(reason) != std::string::npos;
    EXPECT_TRUE(named) << what << ": no CVODE reason in: " << message;
  }
  EXPECT_GE(plant.time(), start) << what;
  EXPECT_LT(plant.time(), start + span) << what;
  EXPECT_TRUE(plant.linkPositions().allFinite()) << what;
  EXPECT_TRUE(plant.motorPositions().allFinite()) << what;
}

TEST(PlantMisuse, TooFewStepsIsASolverErrorNamingTheBudget) {
  PlantOptions options;
  options.max_steps_per_advance = 5;
  FlexibleJointPlant plant(rx170Model(), rx170Drives(), options);
  plant.reset(home());
  JointVector target = home();
  target[1] += 0.2;
  plant.setReference(target, JointVector::Zero(6));
  expectSolverFailure(plant, 1.0, {"CV_TOO_MUCH_WORK"}, "max_steps_per_advance = 5");
  expectSolverFailure(plant, 1.0, {"work budget"}, "max_steps_per_advance = 5");
  // The plant still checks its calls afterwards: its time is the last good one, not the target.
  EXPECT_THROW(plant.advance(plant.time()), InvalidArgument);
}

// Gains no drive can have (kp 1e12 ran `jointcomp paper` for minutes) are refused when the plant is built,
// naming the joint and the gain; a sane drive needs a fraction of the per-advance work budget, so any plant
// that can be integrated is, and one that cannot fails within that budget.
TEST(PlantMisuse, AbsurdGainsAreRefusedAndTheWorkIsBounded) {
  PlantOptions options;
  options.max_steps_per_advance = 5000;
  JointVector target = home();
  target[1] += 0.01;
  FlexibleJointPlant sane(rx170Model(), rx170Drives(), options);
  sane.reset(home());
  sane.setReference(target, JointVector::Zero(6));
  sane.advance(0.2);
  EXPECT_LT(sane.statistics().steps, (kStepBudgetFloor + kStepBudgetPerSecond * 0.2) / 10);

  const JointErrorModel model = rx170Model();
  for (const double kp : {1e12, 1e14, 1e300}) {
    std::vector<DriveParameters> drives = rx170Drives();
    drives[0].kp_nm_per_rad = kp;
    expectThrowMentioning<InvalidArgument>([&] { FlexibleJointPlant plant(model, drives); },
                                           {"joint_1", "kp_nm_per_rad", "rad/s"}, "kp = " + std::to_string(kp));
  }
  std::vector<DriveParameters> drives = rx170Drives();
  drives[3].kd_nms_per_rad = 1e9;
  expectThrowMentioning<InvalidArgument>([&] { FlexibleJointPlant plant(model, drives); },
                                         {"joint_4", "kd_nms_per_rad"}, "kd = 1e9");
  drives = rx170Drives();
  drives[5].ki_nm_per_rad_s = 1e20;
  expectThrowMentioning<InvalidArgument>([&] { FlexibleJointPlant plant(model, drives); },
                                         {"joint_6", "ki_nm_per_rad_s"}, "ki = 1e20");
  // At the bound the plant is built.
  drives = rx170Drives();
  drives[0].kp_nm_per_rad = 0.99 * kMaxLoopFrequency * kMaxLoopFrequency * drives[0].motor_inertia_kgm2;
  EXPECT_NO_THROW(FlexibleJointPlant plant(model, drives));
}

// A drive without inertia makes the motor's acceleration infinite: the right-hand side cannot be
// evaluated, which must come out as a SolverError (or be refused at construction), never a NaN state.
TEST(PlantMisuse, MasslessMotorIsRefusedOrASolverError) {
  std::vector<DriveParameters> drives = rx170Drives();
  drives[1].motor_inertia_kgm2 = 0.0;
  try {
    FlexibleJointPlant plant(rx170Model(), drives);
    plant.reset(home());
    JointVector target = home();
    target[1] += 0.01;
    plant.setReference(target, JointVector::Zero(6));
    expectSolverFailure(plant, 0.1, {"CV_"}, "motor inertia 0");
  } catch (const InvalidArgument&) {
    SUCCEED();
  }
}

// Drives that mean nothing physically: the plant is told them in code (the C API, the FMU, tests), not
// only through the parameter file whose reader refuses them. The constructor must refuse them too,
// naming the drive, as it refuses a wrong drive count: today a zero inertia only surfaces as CVODE's
// CV_FIRST_RHSFUNC_ERR at the first advance, and a negative inertia makes CVODE thrash through
// max_steps_per_advance steps before CV_TOO_MUCH_WORK.
TEST(PlantMisuse, NonPhysicalDrivesAreRefusedAtConstruction) {
  const JointErrorModel model = rx170Model();
  const auto refused = [&](const std::string& what, void (*spoil)(DriveParameters&)) {
    std::vector<DriveParameters> drives = rx170Drives();
    spoil(drives[2]);
    expectThrowMentioning<InvalidArgument>([&] { FlexibleJointPlant plant(model, drives); }, {"joint_3"}, what);
  };
  refused("zero motor inertia", [](DriveParameters& d) { d.motor_inertia_kgm2 = 0.0; });
  refused("negative motor inertia", [](DriveParameters& d) { d.motor_inertia_kgm2 = -1.0; });
  refused("NaN position gain", [](DriveParameters& d) { d.kp_nm_per_rad = kNaN; });
  refused("zero Coulomb velocity scale", [](DriveParameters& d) { d.coulomb_velocity_scale_rad_per_s = 0.0; });
  refused("negative viscous friction", [](DriveParameters& d) { d.viscous_friction_nms_per_rad = -5.0; });
}

}  // namespace
}  // namespace jointcomp
