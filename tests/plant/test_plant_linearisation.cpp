// Linearisation of the flexible-joint plant about a static equilibrium, motors held, no controller and
// no damping: the links oscillate on the joint springs. The Jacobian of plant.derivative() by central
// differences must have the eigenvalues +-i w of the undamped modes, w^2 the eigenvalues of
// M(q)^-1 (K + d(load)/dq) (re-derived here from massMatrix and central differences of the gravity and
// balancer torques), and a simulated small free response started on the lowest mode must oscillate at
// the lowest frequency (period from the zero crossings of the joint that moves most).
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "tests/plant/plant_test_support.hpp"

#include "model/effects/compliance.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/effects/spring_balancer.hpp"
#include "model/io/parameter_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp {
namespace {

using namespace plant_testing;

struct Linearised {
  JointErrorModel model = loadParameterFile(kParameters, rx170());
  std::unique_ptr<FlexibleJointPlant> plant;
  PlantState equilibrium;

  Linearised() {
    std::vector<DriveParameters> drives = loadDriveParameters(kParameters, model.robot());
    for (DriveParameters& d : drives) d.transmission_damping_nms_per_rad = 0.0;
    PlantOptions options;
    options.control = false;
    options.motors_locked = true;
    options.relative_tolerance = 1e-10;
    options.absolute_tolerance = 1e-14;
    plant = std::make_unique<FlexibleJointPlant>(model, drives, options);
    JointVector command(6);
    command << 20.0, 45.0, 70.0, 30.0, 50.0, 10.0;
    plant->reset(command * kDegree);
    equilibrium = plant->saveState();
  }
};

// d(ydot)/dy at y by central differences.
Eigen::MatrixXd jacobianOf(FlexibleJointPlant& plant, double t, const std::vector<double>& y) {
  const int size = plant.stateSize();
  Eigen::MatrixXd jacobian(size, size);
  std::vector<double> shifted = y, plus(size), minus(size);
  for (int i = 0; i < size; ++i) {
    const double h = 1e-6 * std::max(1.0, std::abs(y[i]));
    shifted[i] = y[i] + h;
    plant.derivative(t, shifted.data(), plus.data());
    shifted[i] = y[i] - h;
    plant.derivative(t, shifted.data(), minus.data());
    shifted[i] = y[i];
    for (int r = 0; r < size; ++r) jacobian(r, i) = (plus[r] - minus[r]) / (2.0 * h);
  }
  return jacobian;
}

// The undamped frequencies (rad/s, ascending) and mode shapes from the link-side mechanics alone.
void independentModes(const JointErrorModel& model, const JointVector& q, Eigen::VectorXd& frequencies,
                      Eigen::MatrixXd& shapes) {
  const int n = model.robot().dof();
  const auto& compliance =
      dynamic_cast<const ComplianceEffect&>(model.effect(model.findEffect(ComplianceEffect::kType)));
  Eigen::MatrixXd stiffness = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < n; ++j) stiffness(j, j) = compliance.stiffness(j);
  for (int j = 0; j < n; ++j) {
    const double h = 1e-6;
    JointVector plus = q, minus = q;
    plus[j] += h;
    minus[j] -= h;
    stiffness.col(j) += (staticLoad(model, plus) - staticLoad(model, minus)) / (2.0 * h);
  }
  RobotWorkspace ws(model.robot());
  JointMatrix mass;
  massMatrix(model.robot(), ws, q, mass);
  // K_eff is not symmetric in general (the balancer and gravity are, but keep it general): solve
  // M^-1 K_eff with a general eigensolver.
  Eigen::EigenSolver<Eigen::MatrixXd> solver(mass.inverse() * stiffness);
  std::vector<std::pair<double, int>> order;
  for (int i = 0; i < n; ++i) order.emplace_back(std::sqrt(solver.eigenvalues()[i].real()), i);
  std::sort(order.begin(), order.end());
  frequencies.resize(n);
  shapes.resize(n, n);
  for (int i = 0; i < n; ++i) {
    frequencies[i] = order[i].first;
    shapes.col(i) = solver.eigenvectors().col(order[i].second).real().normalized();
  }
}

TEST(PlantLinearisation, JacobianEigenvaluesAreTheUndampedModes) {
  Linearised s;
  const Eigen::MatrixXd jacobian = jacobianOf(*s.plant, s.plant->time(), s.equilibrium.y);
  Eigen::EigenSolver<Eigen::MatrixXd> solver(jacobian);
  std::vector<double> oscillatory;
  double largest = 0.0;
  for (int i = 0; i < jacobian.rows(); ++i) largest = std::max(largest, std::abs(solver.eigenvalues()[i]));
  for (int i = 0; i < jacobian.rows(); ++i) {
    const std::complex<double> lambda = solver.eigenvalues()[i];
    // No damping: every eigenvalue on the imaginary axis (held motors and integrators: zero).
    EXPECT_LT(std::abs(lambda.real()), 1e-6 * largest) << lambda;
    if (lambda.imag() > 1e-6 * largest) oscillatory.push_back(lambda.imag());
  }
  std::sort(oscillatory.begin(), oscillatory.end());
  ASSERT_EQ(oscillatory.size(), 6U) << "one oscillating pair per link";

  Eigen::VectorXd frequencies;
  Eigen::MatrixXd shapes;
  independentModes(s.model, s.plant->linkPositions(), frequencies, shapes);
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(oscillatory[i], frequencies[i], 1e-6 * frequencies[i]) << "mode " << i;
  }
}

TEST(PlantLinearisation, FreeResponseOscillatesAtTheLowestFrequency) {
  Linearised s;
  const Eigen::MatrixXd jacobian = jacobianOf(*s.plant, s.plant->time(), s.equilibrium.y);
  Eigen::EigenSolver<Eigen::MatrixXd> solver(jacobian);
  double lowest = INFINITY;
  Eigen::VectorXcd mode;
  for (int i = 0; i < jacobian.rows(); ++i) {
    const std::complex<double> lambda = solver.eigenvalues()[i];
    if (lambda.imag() > 1.0 && lambda.imag() < lowest) {
      lowest = lambda.imag();
      mode = solver.eigenvectors().col(i);
    }
  }
  ASSERT_TRUE(std::isfinite(lowest));
  // Start on the mode: link displacement from the real part of the eigenvector (the velocity part is
  // then i w times it, 90 degrees later: start at rest at the turning point). 1 urad at the largest.
  Eigen::VectorXd shape = mode.head(6).real();
  if (shape.cwiseAbs().maxCoeff() < 1e-3 * mode.head(6).cwiseAbs().maxCoeff()) shape = mode.head(6).imag();
  Eigen::Index watched = 0;
  shape.cwiseAbs().maxCoeff(&watched);
  shape *= 1e-6 / shape[watched];
  PlantState start = s.equilibrium;
  for (int j = 0; j < 6; ++j) start.y[j] += shape[j];
  s.plant->restoreState(start);

  const double period = 2.0 * kPi / lowest;
  const double q0 = s.equilibrium.y[watched];
  const double dt = period / 200.0;
  std::vector<double> crossings;
  double previous = s.plant->linkPositions()[watched] - q0;
  for (int k = 1; k <= 200 * 10; ++k) {
    s.plant->advance(s.equilibrium.time + k * dt);
    const double now = s.plant->linkPositions()[watched] - q0;
    if ((previous < 0.0) != (now < 0.0))
      crossings.push_back(s.equilibrium.time + (k - 1 + previous / (previous - now)) * dt);
    previous = now;
  }
  ASSERT_GE(crossings.size(), 18U);
  const double measured = 2.0 * (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  // The brief asks for ~1 %; linear interpolation of 200 samples per period and a 1 urad amplitude
  // (nonlinear terms 1e-6 of the linear ones) give far better, so hold it to 0.1 %.
  EXPECT_NEAR(measured, period, 1e-3 * period) << "lowest mode " << lowest / (2 * kPi) << " Hz, joint " << watched + 1;
  RecordProperty("lowest_mode_hz", std::to_string(lowest / (2 * kPi)));
  RecordProperty("measured_period_relative_error", std::to_string(measured / period - 1.0));
}

}  // namespace
}  // namespace jointcomp
