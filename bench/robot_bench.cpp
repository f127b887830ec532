// Per-call cost of the robot algorithms against KDL, the peer, on the RX170 (model/robots/rx170.urdf),
// in one binary and one run. Every call has a pair BM_Ours_<Call> / BM_Kdl_<Call>[_<variant>] so that
// bench/run-benchmarks.sh can pair them (for KDL the fastest variant counts).
//
// Each benchmark cycles through the same 64 seeded random configurations (inside the joint limits, with
// random joint rates, accelerations and the torques that produce them), so a result is not one point.
// Every call's output goes through benchmark::DoNotOptimize.
//
// Allocations: this binary replaces the global operator new/delete (every form) and interposes glibc's
// malloc family (Eigen's dynamic matrices, and so KDL's JntArray and JntSpaceInertiaMatrix, allocate with
// malloc, not operator new). Both are counted; the counter "allocs_per_call" is the number of allocations
// made during the timed loop divided by its iterations. It must be 0 for ours; the binary fails if not.
//
// Before anything is timed, ours and KDL are cross-checked at a few configurations (tool pose, Jacobian,
// gravity torques, inverse dynamics, mass matrix, forward dynamics) to 1e-9 relative, on the RX170 and on
// a synthetic chain with general axes, rotated inertial frames and massive links behind fixed joints; the
// binary stops (exit 2) with a message naming the chain, the call, the configuration and both results when
// they disagree.
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <memory>
#include <new>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <kdl/chain.hpp>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainfdsolver_recursive_newton_euler.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <kdl/frames.hpp>
#include <kdl/jacobian.hpp>
#include <kdl/jntarray.hpp>
#include <kdl/jntspaceinertiamatrix.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>

#include "bench/support/allocation_counting.hpp"
#include "model/common/sin_cos.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"
#include "model/robot/load_urdf.hpp"
#include "model/robot/robot.hpp"
#include "model/robot/workspace.hpp"

namespace {

using jointcomp::Jacobian;
using jointcomp::JointMatrix;
using jointcomp::JointVector;
using jointcomp::Robot;
using jointcomp::RobotWorkspace;

constexpr int kConfigurations = 64;  // a power of two: the loops cycle with a mask
constexpr std::uint64_t kSeed = 20240611;
const char* const kUrdfPath = JOINTCOMP_DATA_DIR "/robots/rx170.urdf";
const char* const kBaseLink = "base_link";
const char* const kTipLink = "flange";

// A chain the RX170 does not resemble, for the cross-check only.
const char* const kSyntheticUrdf = R"(<?xml version="1.0"?>
<robot name="synthetic">
  <link name="base_link"/>
  <joint name="j1" type="revolute">
    <parent link="base_link"/><child link="l1"/>
    <origin xyz="0.1 -0.05 0.4" rpy="0.1 -0.2 0.3"/>
    <axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" velocity="2" effort="1000"/>
  </joint>
  <link name="l1">
    <inertial>
      <origin xyz="0.02 0.03 0.15" rpy="0.4 0.1 -0.7"/>
      <mass value="20"/>
      <inertia ixx="0.9" ixy="0.05" ixz="-0.03" iyy="0.7" iyz="0.02" izz="0.5"/>
    </inertial>
  </link>
  <joint name="j2" type="revolute">
    <parent link="l1"/><child link="l2"/>
    <origin xyz="0.12 0.0 0.3" rpy="1.2 0.3 -0.4"/>
    <axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" velocity="2" effort="1000"/>
  </joint>
  <link name="l2">
    <inertial>
      <origin xyz="0.3 0.01 -0.02" rpy="-0.3 0.5 0.2"/>
      <mass value="15"/>
      <inertia ixx="0.2" ixy="-0.01" ixz="0.02" iyy="1.1" iyz="0.04" izz="1.0"/>
    </inertial>
  </link>
  <joint name="j2_fixed" type="fixed">
    <parent link="l2"/><child link="l2_motor"/>
    <origin xyz="0.5 0.05 0.02" rpy="0.2 0.7 -1.1"/>
  </joint>
  <link name="l2_motor">
    <inertial>
      <origin xyz="0.01 -0.02 0.05" rpy="0.9 -0.4 0.6"/>
      <mass value="6"/>
      <inertia ixx="0.03" ixy="0.004" ixz="-0.002" iyy="0.05" iyz="0.003" izz="0.04"/>
    </inertial>
  </link>
  <joint name="j3" type="revolute">
    <parent link="l2_motor"/><child link="l3"/>
    <origin xyz="0.2 0.0 0.1" rpy="-0.5 0.0 0.9"/>
    <axis xyz="0.6 0 0.8"/>
    <limit lower="-2.5" upper="2.5" velocity="3" effort="500"/>
  </joint>
  <link name="l3">
    <inertial>
      <origin xyz="0.0 0.2 0.05" rpy="0.3 0.3 0.3"/>
      <mass value="8"/>
      <inertia ixx="0.3" ixy="0.02" ixz="0.01" iyy="0.1" iyz="-0.02" izz="0.3"/>
    </inertial>
  </link>
  <joint name="j4" type="revolute">
    <parent link="l3"/><child link="l4"/>
    <origin xyz="0.0 0.4 0.0" rpy="1.5707963267948966 0 0"/>
    <axis xyz="1 0 0"/>
    <limit lower="-3" upper="3" velocity="4" effort="200"/>
  </joint>
  <link name="l4">
    <inertial>
      <origin xyz="0.05 0.0 0.1" rpy="0 -0.6 0.2"/>
      <mass value="4"/>
      <inertia ixx="0.05" ixy="0.001" ixz="0.002" iyy="0.06" iyz="0.001" izz="0.02"/>
    </inertial>
  </link>
  <joint name="j5" type="revolute">
    <parent link="l4"/><child link="l5"/>
    <origin xyz="0.1 0.0 0.2" rpy="-0.3 0.2 0.1"/>
    <axis xyz="0 -1 0"/>
    <limit lower="-2" upper="2" velocity="5" effort="100"/>
  </joint>
  <link name="l5">
    <inertial>
      <origin xyz="0.0 0.0 0.03" rpy="0.1 0.2 0.3"/>
      <mass value="2"/>
      <inertia ixx="0.01" ixy="0.0005" ixz="0.0" iyy="0.012" iyz="0.0003" izz="0.008"/>
    </inertial>
  </link>
  <joint name="j6" type="continuous">
    <parent link="l5"/><child link="l6"/>
    <origin xyz="0.0 0.05 0.08" rpy="0.0 0.4 0.0"/>
    <axis xyz="0.267261241912424 0.534522483824849 0.801783725737273"/>
  </joint>
  <link name="l6">
    <inertial>
      <origin xyz="0.0 0.01 0.04" rpy="0.5 0 0"/>
      <mass value="0.8"/>
      <inertia ixx="0.002" ixy="0.0001" ixz="0.0" iyy="0.003" iyz="0.0" izz="0.002"/>
    </inertial>
  </link>
  <joint name="tool_joint" type="fixed">
    <parent link="l6"/><child link="flange"/>
    <origin xyz="0.02 0.0 0.15" rpy="0.3 -0.2 0.5"/>
  </joint>
  <link name="flange">
    <inertial>
      <origin xyz="0.0 0.0 0.05" rpy="0.2 0.1 0"/>
      <mass value="3"/>
      <inertia ixx="0.01" ixy="0.001" ixz="0.0" iyy="0.012" iyz="0.0" izz="0.006"/>
    </inertial>
  </link>
</robot>
)";

// ---------------------------------------------------------------------------------------------------
// The two models and the configurations, built once before anything is timed.

struct Sample {
  JointVector q, qd, qdd, tau;  // tau = inverse dynamics of (q, qd, qdd), so forward dynamics gives qdd back
  KDL::JntArray kq, kqd, kqdd, ktau;
};

// KDL's solvers keep a reference to the chain: the chain lives here, before them, and never moves.
struct KdlModel {
  KDL::Tree tree;
  KDL::Chain chain;
  std::unique_ptr<KDL::ChainFkSolverPos_recursive> fk;
  std::unique_ptr<KDL::ChainJntToJacSolver> jacobian;
  std::unique_ptr<KDL::ChainIdSolver_RNE> rne;
  std::unique_ptr<KDL::ChainDynParam> dyn_param;
  std::unique_ptr<KDL::ChainFdSolver_RNE> fd;
  KDL::Wrenches no_wrenches;  // external wrenches per segment: none
  KDL::JntArray zeros;        // zero joint rates and accelerations, for gravity by RNE
};

struct Fixture {
  Robot robot;
  KdlModel kdl;
  std::vector<Sample> samples;
};

Fixture* g_fixture = nullptr;

[[noreturn]] void fail(const std::string& message) {
  std::cerr << "robot_bench: " << message << std::endl;
  std::exit(2);
}

KDL::JntArray toKdl(const JointVector& v) {
  KDL::JntArray a(static_cast<unsigned int>(v.size()));
  for (int i = 0; i < v.size(); ++i) a(i) = v[i];
  return a;
}

// A chain to load: from a file, or from URDF text (then `name` stands for the file in messages).
struct UrdfSource {
  std::string name;
  std::string path;  // empty: use xml
  std::string xml;
};

std::unique_ptr<Fixture> buildFixture(const UrdfSource& source) {
  auto fixture = std::make_unique<Fixture>();
  jointcomp::UrdfChainOptions options;
  options.root_link = kBaseLink;
  options.tip_link = kTipLink;
  try {
    fixture->robot = source.path.empty() ? jointcomp::loadRobotFromUrdfString(source.xml, source.name, options)
                                         : jointcomp::loadRobotFromUrdfFile(source.path, options);
  } catch (const std::exception& error) {
    fail("cannot load our robot from " + source.name + ": " + error.what());
  }
  const Robot& robot = fixture->robot;
  const int n = robot.dof();

  KdlModel& kdl = fixture->kdl;
  const bool parsed = source.path.empty() ? kdl_parser::treeFromString(source.xml, kdl.tree)
                                          : kdl_parser::treeFromFile(source.path, kdl.tree);
  if (!parsed) fail("kdl_parser cannot read " + source.name);
  if (!kdl.tree.getChain(kBaseLink, kTipLink, kdl.chain)) {
    fail(std::string("KDL has no chain ") + kBaseLink + " -> " + kTipLink + " in " + source.name);
  }
  if (static_cast<int>(kdl.chain.getNrOfJoints()) != n) {
    fail("KDL's chain has " + std::to_string(kdl.chain.getNrOfJoints()) + " joints, ours " + std::to_string(n));
  }
  const KDL::Vector gravity(robot.gravity.x(), robot.gravity.y(), robot.gravity.z());
  kdl.fk = std::make_unique<KDL::ChainFkSolverPos_recursive>(kdl.chain);
  kdl.jacobian = std::make_unique<KDL::ChainJntToJacSolver>(kdl.chain);
  kdl.rne = std::make_unique<KDL::ChainIdSolver_RNE>(kdl.chain, gravity);
  kdl.dyn_param = std::make_unique<KDL::ChainDynParam>(kdl.chain, gravity);
  kdl.fd = std::make_unique<KDL::ChainFdSolver_RNE>(kdl.chain, gravity);
  kdl.no_wrenches.assign(kdl.chain.getNrOfSegments(), KDL::Wrench::Zero());
  kdl.zeros = KDL::JntArray(static_cast<unsigned int>(n));

  // Seeded configurations inside the joint limits (continuous joints: -pi..pi), rates up to the
  // velocity limit (1 rad/s when none), accelerations up to 5 rad/s^2.
  std::mt19937_64 random(kSeed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  RobotWorkspace ws(robot);
  for (int k = 0; k < kConfigurations; ++k) {
    Sample s;
    s.q.resize(n);
    s.qd.resize(n);
    s.qdd.resize(n);
    for (int i = 0; i < n; ++i) {
      const jointcomp::Joint& joint = robot.joints[i];
      const double lower = std::isfinite(joint.lower) ? joint.lower : -M_PI;
      const double upper = std::isfinite(joint.upper) ? joint.upper : M_PI;
      s.q[i] = 0.5 * (lower + upper) + 0.5 * (upper - lower) * unit(random);
      s.qd[i] = (joint.velocity_limit > 0.0 ? joint.velocity_limit : 1.0) * unit(random);
      s.qdd[i] = 5.0 * unit(random);
    }
    jointcomp::inverseDynamics(robot, ws, s.q, s.qd, s.qdd, s.tau);
    s.kq = toKdl(s.q);
    s.kqd = toKdl(s.qd);
    s.kqdd = toKdl(s.qdd);
    s.ktau = toKdl(s.tau);
    fixture->samples.push_back(std::move(s));
  }
  return fixture;
}

// ---------------------------------------------------------------------------------------------------
// Cross-check against KDL (outside timing).

constexpr double kTolerance = 1e-9;
const char* g_checking = "";  // the chain under cross-check, for messages

std::string format(const Eigen::MatrixXd& m) {
  std::ostringstream out;
  out.precision(12);
  out << m;
  return out.str();
}

std::string scientific(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.2e", value);
  return text;
}

// Relative difference in the max norm; below 1 the reference's scale is taken as 1 (absolute error).
double relativeDifference(const Eigen::MatrixXd& ours, const Eigen::MatrixXd& kdl) {
  return (ours - kdl).cwiseAbs().maxCoeff() / std::max(1.0, kdl.cwiseAbs().maxCoeff());
}

void expectClose(const char* what, int sample, const Eigen::MatrixXd& ours, const Eigen::MatrixXd& kdl, double& worst) {
  if (ours.rows() != kdl.rows() || ours.cols() != kdl.cols()) {
    fail(std::string("cross-check: ") + what + " has different sizes in ours and KDL");
  }
  const double difference = relativeDifference(ours, kdl);
  worst = std::max(worst, difference);
  if (!(difference <= kTolerance)) {
    fail(std::string("cross-check FAILED (") + g_checking + "): " + what + " at configuration " +
         std::to_string(sample) + " differs from KDL by " + scientific(difference) +
         " (relative, max norm; tolerance 1e-9)\nours:\n" + format(ours) + "\nKDL:\n" + format(kdl) +
         "\nours - KDL:\n" + format(ours - kdl) + "\nThe benchmark is not run on models that disagree.");
  }
}

Eigen::MatrixXd fromKdl(const KDL::JntArray& a) { return a.data; }

void requireKdl(int status, const char* what) {
  if (status < 0) fail(std::string("KDL's ") + what + " failed with error " + std::to_string(status));
}

void crossCheck(const std::string& label, Fixture& f) {
  g_checking = label.c_str();
  const Robot& robot = f.robot;
  KdlModel& kdl = f.kdl;
  const int n = robot.dof();
  RobotWorkspace ws(robot);
  double worst_pose = 0, worst_position = 0, worst_jacobian = 0, worst_gravity = 0, worst_gravity_dp = 0,
         worst_gravity_frames = 0, worst_rnea = 0, worst_mass = 0, worst_fd = 0;
  const int checks[] = {0, 1, 2, 3, 17, 42, 63};
  for (int k : checks) {
    const Sample& s = f.samples[k];

    jointcomp::forwardKinematics(robot, ws, s.q);
    KDL::Frame frame;
    requireKdl(kdl.fk->JntToCart(s.kq, frame), "ChainFkSolverPos_recursive::JntToCart");
    Eigen::Matrix<double, 3, 4> ours_pose, kdl_pose;
    ours_pose << ws.tool_pose.linear(), ws.tool_pose.translation();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) kdl_pose(r, c) = frame.M(r, c);
      kdl_pose(r, 3) = frame.p(r);
    }
    expectClose("tool pose (forward kinematics)", k, ours_pose, kdl_pose, worst_pose);
    const Eigen::Vector3d tool_position = jointcomp::toolPosition(robot, s.q);
    expectClose("tool position (toolPosition)", k, tool_position, Eigen::Vector3d(kdl_pose.col(3)), worst_position);

    Jacobian jacobian;
    jointcomp::toolJacobian(robot, ws, jacobian);
    KDL::Jacobian kdl_jacobian(static_cast<unsigned int>(n));
    requireKdl(kdl.jacobian->JntToJac(s.kq, kdl_jacobian), "ChainJntToJacSolver::JntToJac");
    expectClose("tool Jacobian", k, jacobian, kdl_jacobian.data, worst_jacobian);

    JointVector tau;
    jointcomp::gravityTorques(robot, ws, s.q, tau);
    KDL::JntArray kdl_tau(static_cast<unsigned int>(n));
    requireKdl(kdl.rne->CartToJnt(s.kq, kdl.zeros, kdl.zeros, kdl.no_wrenches, kdl_tau),
               "ChainIdSolver_RNE::CartToJnt (gravity)");
    expectClose("gravity torques vs KDL ChainIdSolver_RNE", k, tau, fromKdl(kdl_tau), worst_gravity);
    requireKdl(kdl.dyn_param->JntToGravity(s.kq, kdl_tau), "ChainDynParam::JntToGravity");
    expectClose("gravity torques vs KDL ChainDynParam::JntToGravity", k, tau, fromKdl(kdl_tau), worst_gravity_dp);
    double sines[jointcomp::kMaxJoints], cosines[jointcomp::kMaxJoints];
    jointcomp::sinCosBatch(s.q.data(), n, sines, cosines);
    jointcomp::gravityTorquesInJointFrames(robot, cosines, sines, tau);
    expectClose("gravity torques in joint frames vs KDL ChainDynParam::JntToGravity", k, tau, fromKdl(kdl_tau),
                worst_gravity_frames);

    jointcomp::inverseDynamics(robot, ws, s.q, s.qd, s.qdd, tau);
    requireKdl(kdl.rne->CartToJnt(s.kq, s.kqd, s.kqdd, kdl.no_wrenches, kdl_tau), "ChainIdSolver_RNE::CartToJnt");
    expectClose("inverse dynamics (RNEA) torques", k, tau, fromKdl(kdl_tau), worst_rnea);

    JointMatrix mass;
    jointcomp::massMatrix(robot, ws, s.q, mass);
    KDL::JntSpaceInertiaMatrix kdl_mass(static_cast<unsigned int>(n));
    requireKdl(kdl.dyn_param->JntToMass(s.kq, kdl_mass), "ChainDynParam::JntToMass");
    expectClose("mass matrix", k, mass, kdl_mass.data, worst_mass);

    JointVector qdd;
    jointcomp::forwardDynamics(robot, ws, s.q, s.qd, s.tau, qdd);
    KDL::JntArray kdl_qdd(static_cast<unsigned int>(n));
    requireKdl(kdl.fd->CartToJnt(s.kq, s.kqd, s.ktau, kdl.no_wrenches, kdl_qdd), "ChainFdSolver_RNE::CartToJnt");
    expectClose("forward dynamics accelerations", k, qdd, fromKdl(kdl_qdd), worst_fd);
    // Both must give back the accelerations the torques were made from.
    double round_trip = 0;
    expectClose("forward dynamics of inverse dynamics (ours) vs the sampled qdd", k, qdd, s.qdd, round_trip);
  }
  std::fprintf(
      stderr,
      "robot_bench: cross-check against KDL passed for %s at %zu configurations (largest relative differences: "
      "pose %.1e, tool position alone %.1e, Jacobian %.1e, gravity %.1e (RNE) %.1e (DynParam) %.1e (ours in joint "
      "frames), RNEA %.1e, mass "
      "matrix %.1e, forward dynamics %.1e; tolerance 1e-9)\n",
      label.c_str(), sizeof(checks) / sizeof(checks[0]), worst_pose, worst_position, worst_jacobian, worst_gravity,
      worst_gravity_dp, worst_gravity_frames, worst_rnea, worst_mass, worst_fd);
}

// ---------------------------------------------------------------------------------------------------
// Benchmarks. Allocations are counted over the whole timed loop.

using jointcomp::bench::AllocationCounter;

#define BENCH_PROLOGUE                            \
  Fixture& f = *g_fixture;                        \
  const Robot& robot = f.robot;                   \
  KdlModel& kdl = f.kdl;                          \
  const int n = robot.dof();                      \
  const std::vector<Sample>& samples = f.samples; \
  unsigned index = 0;                             \
  (void)robot;                                    \
  (void)kdl;                                      \
  (void)n;                                        \
  (void)samples

#define NEXT_SAMPLE samples[index++ & (kConfigurations - 1)]

// Forward kinematics: the tool pose.
void BM_Ours_ForwardKinematics(benchmark::State& state) {
  BENCH_PROLOGUE;
  RobotWorkspace ws(robot);
  const AllocationCounter allocations;
  for (auto _ : state) {
    jointcomp::forwardKinematics(robot, ws, NEXT_SAMPLE.q);
    benchmark::DoNotOptimize(ws.tool_pose);
  }
  allocations.report(state);
}
// The tool's position alone (the FMU's tool output); KDL's way to it is its forward kinematics.
void BM_Ours_ToolPosition(benchmark::State& state) {
  BENCH_PROLOGUE;
  const AllocationCounter allocations;
  for (auto _ : state) benchmark::DoNotOptimize(jointcomp::toolPosition(robot, NEXT_SAMPLE.q));
  allocations.report(state);
}
void BM_Kdl_ForwardKinematics(benchmark::State& state) {
  BENCH_PROLOGUE;
  KDL::Frame frame;
  const AllocationCounter allocations;
  for (auto _ : state) {
    benchmark::DoNotOptimize(kdl.fk->JntToCart(NEXT_SAMPLE.kq, frame));
    benchmark::DoNotOptimize(frame);
  }
  allocations.report(state);
}

// The sines and cosines a forward kinematics needs (no KDL pair: KDL calls libm): the joints' six at once by
// sinCosBatch against six libm sin-and-cos pairs (GCC merges each pair into one sincos call), and one angle
// by sinCos against libm.
void BM_Ours_JointSinCos(benchmark::State& state) {
  BENCH_PROLOGUE;
  double sines[jointcomp::kMaxJoints], cosines[jointcomp::kMaxJoints];
  const AllocationCounter allocations;
  for (auto _ : state) {
    jointcomp::sinCosBatch(NEXT_SAMPLE.q.data(), n, sines, cosines);
    benchmark::DoNotOptimize(sines);
    benchmark::DoNotOptimize(cosines);
  }
  allocations.report(state);
}
void BM_Libm_JointSinCos(benchmark::State& state) {
  BENCH_PROLOGUE;
  double sines[jointcomp::kMaxJoints], cosines[jointcomp::kMaxJoints];
  for (auto _ : state) {
    const JointVector& q = NEXT_SAMPLE.q;
    for (int i = 0; i < n; ++i) {
      sines[i] = std::sin(q[i]);
      cosines[i] = std::cos(q[i]);
    }
    benchmark::DoNotOptimize(sines);
    benchmark::DoNotOptimize(cosines);
  }
}
void BM_Ours_SinCos(benchmark::State& state) {
  BENCH_PROLOGUE;
  for (auto _ : state) {
    double sine, cosine;
    jointcomp::sinCos(NEXT_SAMPLE.q[0], sine, cosine);
    benchmark::DoNotOptimize(sine);
    benchmark::DoNotOptimize(cosine);
  }
}
void BM_Libm_SinCos(benchmark::State& state) {
  BENCH_PROLOGUE;
  for (auto _ : state) {
    const double angle = NEXT_SAMPLE.q[0];
    double sine = std::sin(angle), cosine = std::cos(angle);
    benchmark::DoNotOptimize(sine);
    benchmark::DoNotOptimize(cosine);
  }
}

// Jacobian from q (KDL's JntToJac runs its own forward kinematics, so ours includes it too).
void BM_Ours_Jacobian(benchmark::State& state) {
  BENCH_PROLOGUE;
  RobotWorkspace ws(robot);
  Jacobian jacobian(6, n);
  const AllocationCounter allocations;
  for (auto _ : state) {
    jointcomp::forwardKinematics(robot, ws, NEXT_SAMPLE.q);
    jointcomp::toolJacobian(robot, ws, jacobian);
    benchmark::DoNotOptimize(jacobian);
  }
  allocations.report(state);
}
void BM_Kdl_Jacobian(benchmark::State& state) {
  BENCH_PROLOGUE;
  KDL::Jacobian jacobian(static_cast<unsigned int>(n));
  const AllocationCounter allocations;
  for (auto _ : state) {
    benchmark::DoNotOptimize(kdl.jacobian->JntToJac(NEXT_SAMPLE.kq, jacobian));
    benchmark::DoNotOptimize(jacobian.data);
  }
  allocations.report(state);
}

// Gravity torques from q. KDL has two ways: RNE with zero rates and accelerations, and ChainDynParam.
void BM_Ours_Gravity(benchmark::State& state) {
  BENCH_PROLOGUE;
  RobotWorkspace ws(robot);
  JointVector tau(n);
  const AllocationCounter allocations;
  for (auto _ : state) {
    jointcomp::gravityTorques(robot, ws, NEXT_SAMPLE.q, tau);
    benchmark::DoNotOptimize(tau);
  }
  allocations.report(state);
}
// Gravity alone, without the chain's poses (what offline compensation uses): the sines, then the recursion in
// joint frames.
void BM_Ours_GravityInJointFrames(benchmark::State& state) {
  BENCH_PROLOGUE;
  JointVector tau(n);
  double sines[jointcomp::kMaxJoints], cosines[jointcomp::kMaxJoints];
  const AllocationCounter allocations;
  for (auto _ : state) {
    const JointVector& q = NEXT_SAMPLE.q;
    jointcomp::sinCosBatch(q.data(), n, sines, cosines);
    jointcomp::gravityTorquesInJointFrames(robot, cosines, sines, tau);
    benchmark::DoNotOptimize(tau);
  }
  allocations.report(state);
}
void BM_Kdl_Gravity_RNE(benchmark::State& state) {
  BENCH_PROLOGUE;
  KDL::JntArray tau(static_cast<unsigned int>(n));
  const AllocationCounter allocations;
  for (auto _ : state) {
    benchmark::DoNotOptimize(kdl.rne->CartToJnt(NEXT_SAMPLE.kq, kdl.zeros, kdl.zeros, kdl.no_wrenches, tau));
    benchmark::DoNotOptimize(tau.data);
  }
  allocations.report(state);
}
void BM_Kdl_Gravity_DynParam(benchmark::State& state) {
  BENCH_PROLOGUE;
  KDL::JntArray tau(static_cast<unsigned int>(n));
  const AllocationCounter allocations;
  for (auto _ : state) {
    benchmark::DoNotOptimize(kdl.dyn_param->JntToGravity(NEXT_SAMPLE.kq, tau));
    benchmark::DoNotOptimize(tau.data);
  }
  allocations.report(state);
}

// What compensation asks per path point: tool pose, Jacobian and gravity torques at one q.
void BM_Ours_FkJacobianGravity(benchmark::State& state) {
  BENCH_PROLOGUE;
  RobotWorkspace ws(robot);
  Jacobian jacobian(6, n);
  JointVector tau(n);
  const AllocationCounter allocations;
  for (auto _ : state) {
    jointcomp::forwardKinematics(robot, ws, NEXT_SAMPLE.q);
    jointcomp::toolJacobian(robot, ws, jacobian);
    jointcomp::gravityTorquesAtCurrentPose(robot, ws, tau);
    benchmark::DoNotOptimize(ws.tool_pose);
    benchmark::DoNotOptimize(jacobian);
    benchmark::DoNotOptimize(tau);
  }
  allocations.report(state);
}
void BM_Kdl_FkJacobianGravity_RNE(benchmark::State& state) {
  BENCH_PROLOGUE;
  KDL::Frame frame;
  KDL::Jacobian jacobian(static_cast<unsigned int>(n));
  KDL::JntArray tau(static_cast<unsigned int>(n));
  const AllocationCounter allocations;
  for (auto _ : state) {
    const KDL::JntArray& q = NEXT_SAMPLE.kq;
    benchmark::DoNotOptimize(kdl.fk->JntToCart(q, frame));
    benchmark::DoNotOptimize(kdl.jacobian->JntToJac(q, jacobian));
    benchmark::DoNotOptimize(kdl.rne->CartToJnt(q, kdl.zeros, kdl.zeros, kdl.no_wrenches, tau));
    benchmark::DoNotOptimize(frame);
    benchmark::DoNotOptimize(jacobian.data);
    benchmark::DoNotOptimize(tau.data);
  }
  allocations.report(state);
}
void BM_Kdl_FkJacobianGravity_DynParam(benchmark::State& state) {
  BENCH_PROLOGUE;
  KDL::Frame frame;
  KDL::Jacobian jacobian(static_cast<unsigned int>(n));
  KDL::JntArray tau(static_cast<unsigned int>(n));
  const AllocationCounter allocations;
  for (auto _ : state) {
    const KDL::JntArray& q = NEXT_SAMPLE.kq;
    benchmark::DoNotOptimize(kdl.fk->JntToCart(q, frame));
    benchmark::DoNotOptimize(kdl.jacobian->JntToJac(q, jacobian));
    benchmark::DoNotOptimize(kdl.dyn_param->JntToGravity(q, tau));
    benchmark::DoNotOptimize(frame);
    benchmark::DoNotOptimize(jacobian.data);
    benchmark::DoNotOptimize(tau.data);
  }
  allocations.report(state);
}

// Inverse dynamics (recursive Newton-Euler) with gravity.
void BM_Ours_InverseDynamics(benchmark::State& state) {
  BENCH_PROLOGUE;
  RobotWorkspace ws(robot);
  JointVector tau(n);
  const AllocationCounter allocations;
  for (auto _ : state) {
    const Sample& s = NEXT_SAMPLE;
    jointcomp::inverseDynamics(robot, ws, s.q, s.qd, s.qdd, tau);
    benchmark::DoNotOptimize(tau);
  }
  allocations.report(state);
}
void BM_Kdl_InverseDynamics(benchmark::State& state) {
  BENCH_PROLOGUE;
  KDL::JntArray tau(static_cast<unsigned int>(n));
  const AllocationCounter allocations;
  for (auto _ : state) {
    const Sample& s = NEXT_SAMPLE;
    benchmark::DoNotOptimize(kdl.rne->CartToJnt(s.kq, s.kqd, s.kqdd, kdl.no_wrenches, tau));
    benchmark::DoNotOptimize(tau.data);
  }
  allocations.report(state);
}

// Joint-space mass matrix.
void BM_Ours_MassMatrix(benchmark::State& state) {
  BENCH_PROLOGUE;
  RobotWorkspace ws(robot);
  JointMatrix mass(n, n);
  const AllocationCounter allocations;
  for (auto _ : state) {
    jointcomp::massMatrix(robot, ws, NEXT_SAMPLE.q, mass);
    benchmark::DoNotOptimize(mass);
  }
  allocations.report(state);
}
void BM_Kdl_MassMatrix(benchmark::State& state) {
  BENCH_PROLOGUE;
  KDL::JntSpaceInertiaMatrix mass(static_cast<unsigned int>(n));
  const AllocationCounter allocations;
  for (auto _ : state) {
    benchmark::DoNotOptimize(kdl.dyn_param->JntToMass(NEXT_SAMPLE.kq, mass));
    benchmark::DoNotOptimize(mass.data);
  }
  allocations.report(state);
}

// Forward dynamics: joint accelerations from torques.
void BM_Ours_ForwardDynamics(benchmark::State& state) {
  BENCH_PROLOGUE;
  RobotWorkspace ws(robot);
  JointVector qdd(n);
  const AllocationCounter allocations;
  for (auto _ : state) {
    const Sample& s = NEXT_SAMPLE;
    jointcomp::forwardDynamics(robot, ws, s.q, s.qd, s.tau, qdd);
    benchmark::DoNotOptimize(qdd);
  }
  allocations.report(state);
}
void BM_Kdl_ForwardDynamics(benchmark::State& state) {
  BENCH_PROLOGUE;
  KDL::JntArray qdd(static_cast<unsigned int>(n));
  const AllocationCounter allocations;
  for (auto _ : state) {
    const Sample& s = NEXT_SAMPLE;
    benchmark::DoNotOptimize(kdl.fd->CartToJnt(s.kq, s.kqd, s.ktau, kdl.no_wrenches, qdd));
    benchmark::DoNotOptimize(qdd.data);
  }
  allocations.report(state);
}

BENCHMARK(BM_Ours_ForwardKinematics);
BENCHMARK(BM_Ours_ToolPosition);
BENCHMARK(BM_Kdl_ForwardKinematics);
BENCHMARK(BM_Ours_JointSinCos);
BENCHMARK(BM_Libm_JointSinCos);
BENCHMARK(BM_Ours_SinCos);
BENCHMARK(BM_Libm_SinCos);
BENCHMARK(BM_Ours_Jacobian);
BENCHMARK(BM_Kdl_Jacobian);
BENCHMARK(BM_Ours_Gravity);
BENCHMARK(BM_Ours_GravityInJointFrames);
BENCHMARK(BM_Kdl_Gravity_RNE);
BENCHMARK(BM_Kdl_Gravity_DynParam);
BENCHMARK(BM_Ours_FkJacobianGravity);
BENCHMARK(BM_Kdl_FkJacobianGravity_RNE);
BENCHMARK(BM_Kdl_FkJacobianGravity_DynParam);
BENCHMARK(BM_Ours_InverseDynamics);
BENCHMARK(BM_Kdl_InverseDynamics);
BENCHMARK(BM_Ours_MassMatrix);
BENCHMARK(BM_Kdl_MassMatrix);
BENCHMARK(BM_Ours_ForwardDynamics);
BENCHMARK(BM_Kdl_ForwardDynamics);

// Ours must allocate nothing in the timed loop: this wrapper of the display reporter notes every BM_Ours_
// run whose allocs_per_call is not 0, and main fails after the run if there is one.
class OursAllocationCheck : public benchmark::BenchmarkReporter {
public:
  explicit OursAllocationCheck(benchmark::BenchmarkReporter* inner) : inner_(inner) {}
  bool ReportContext(const Context& context) override { return inner_->ReportContext(context); }
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) {
      const std::string name = run.benchmark_name();
      const auto counter = run.counters.find("allocs_per_call");
      // Single runs and means (allocation counts are not negative, so a zero mean means none); the
      // spread aggregates (stddev, cv) say nothing about it.
      const bool counts = run.run_type == Run::RT_Iteration || run.aggregate_name == "mean";
      if (counts && name.rfind("BM_Ours_", 0) == 0 && counter != run.counters.end() && counter->second.value != 0.0) {
        offenders_ += " " + name;
      }
    }
    inner_->ReportRuns(runs);
  }
  void Finalize() override { inner_->Finalize(); }
  const std::string& offenders() const { return offenders_; }

private:
  benchmark::BenchmarkReporter* inner_;
  std::string offenders_;
};

// The counting must see both kinds of allocation, or a 0 would mean nothing.
void checkAllocationCounting() {
  const std::uint64_t before_new = jointcomp::bench::allocationCount();
  auto* boxed = new std::vector<double>(16, 1.0);  // operator new, twice
  benchmark::DoNotOptimize(boxed->data());
  delete boxed;
  const std::uint64_t before_malloc = jointcomp::bench::allocationCount();
  Eigen::VectorXd heap = Eigen::VectorXd::Ones(64);  // Eigen's malloc
  benchmark::DoNotOptimize(heap.data());
  const std::uint64_t after = jointcomp::bench::allocationCount();
  if (before_malloc - before_new < 2 || after - before_malloc < 1) {
    fail("the allocation counter does not see operator new or malloc; allocs_per_call would be meaningless");
  }
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  checkAllocationCounting();
  // The RX170 has every axis along z, inertial frames unrotated and diagonal inertia tensors; a second,
  // synthetic chain checks what the RX170 cannot: general axes, rotated inertial frames, products of
  // inertia, and massive links behind fixed joints (mid-chain and after the last joint).
  crossCheck("synthetic chain", *buildFixture({"synthetic chain (robot_bench.cpp)", "", kSyntheticUrdf}));
  std::unique_ptr<Fixture> fixture = buildFixture({kUrdfPath, kUrdfPath, ""});
  crossCheck("RX170", *fixture);
  g_fixture = fixture.get();

  // The default display reporter (console or --benchmark_format) belongs to Google Benchmark.
  OursAllocationCheck check(benchmark::CreateDefaultDisplayReporter());
  benchmark::RunSpecifiedBenchmarks(&check);
  benchmark::Shutdown();
  if (!check.offenders().empty()) {
    std::cerr << "robot_bench: our calls allocated in the timed loop (allocs_per_call != 0):" << check.offenders()
              << std::endl;
    return 3;
  }
  return 0;
}
