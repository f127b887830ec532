// Misuse of the Monte Carlo job (jc_spiral_job_*): NULL, foreign, never-a-handle and freed jobs; NULL and
// wrongly sized arrays; NaN and infinite parameter values; values out of their parameter's range; bad seeds
// and flags. Each call returns the documented status with a message naming the entry point and what is wrong,
// writes none of its outputs, and leaves the job working: afterwards a draw gives the bits it gave before.
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <jointcomp/jointcomp.h>
#include <nlohmann/json.hpp>

namespace {

const std::string kUrdf = std::string(JOINTCOMP_DATA_DIR) + "/robots/rx170.urdf";
const std::string kParameters = std::string(JOINTCOMP_DATA_DIR) + "/params/rx170.json";
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::int32_t kHuge = std::numeric_limits<std::int32_t>::max();
constexpr std::int32_t kMostNegative = std::numeric_limits<std::int32_t>::min();
constexpr double kUntouched = 12345.678;

std::vector<std::int32_t> wrongLengths(std::int32_t good) {
  return {0, good - 1, good + 1, -1, -good, kMostNegative, kHuge};
}

::testing::AssertionResult failsWith(jc_status got, jc_status expected, const char* function, const std::string& part) {
  const std::string message = jc_last_error();
  if (got != expected) {
    return ::testing::AssertionFailure() << function << " returned " << jc_status_name(got) << ", expected "
                                         << jc_status_name(expected) << " (message: " << message << ")";
  }
  if (message.find(function) == std::string::npos || message.find(part) == std::string::npos) {
    return ::testing::AssertionFailure() << function << ": the message '" << message << "' does not name " << function
                                         << " or does not contain '" << part << "'";
  }
  return ::testing::AssertionSuccess();
}
#define EXPECT_FAILS(expected, function, part, call) EXPECT_TRUE(failsWith((call), (expected), function, part))
#define EXPECT_INVALID(function, part, call) EXPECT_FAILS(JC_ERROR_INVALID_ARGUMENT, function, part, call)

class CapiMisuseSpiralJob : public ::testing::Test {
protected:
  // One robot and one job for the suite: planning and compensating the spiral takes a fraction of a second
  // (seconds under sanitizers).
  static void SetUpTestSuite() {
    ASSERT_EQ(jc_robot_load(kUrdf.c_str(), kParameters.c_str(), &robot_), JC_OK) << jc_last_error();
    ASSERT_EQ(jc_spiral_job_create(robot_, 0, &job_), JC_OK) << jc_last_error();
    ASSERT_EQ(jc_spiral_job_sizes(job_, &m_, &p_), JC_OK);
    std::int32_t length = 0;
    ASSERT_EQ(jc_spiral_job_parameters(job_, nullptr, 0, &length), JC_OK);
    std::string text(static_cast<std::size_t>(length) + 1, '\0');
    ASSERT_EQ(jc_spiral_job_parameters(job_, &text[0], length + 1, &length), JC_OK);
    parameters_ = nlohmann::json::parse(text.c_str());
    for (const auto& entry : parameters_) nominal_.push_back(entry.at("value").get<double>());
    reference_metrics_.assign(15, 0.0);
    ASSERT_EQ(jc_spiral_job_run(job_, nominal_.data(), p_, 7, reference_metrics_.data(), 15, nullptr, 0), JC_OK);
  }
  static void TearDownTestSuite() {
    jc_spiral_job_free(job_);
    jc_robot_free(robot_);
  }
  // The job still draws the bits it drew before the misuse.
  void TearDown() override {
    std::vector<double> metrics(15, 0.0);
    ASSERT_EQ(jc_spiral_job_run(job_, nominal_.data(), p_, 7, metrics.data(), 15, nullptr, 0), JC_OK)
        << jc_last_error();
    EXPECT_EQ(metrics, reference_metrics_);
  }
  static std::int32_t index(const std::string& name) {
    for (std::size_t k = 0; k < parameters_.size(); ++k) {
      if (parameters_[k].at("name") == name) return static_cast<std::int32_t>(k);
    }
    ADD_FAILURE() << "no parameter " << name;
    return 0;
  }

  static jc_robot* robot_;
  static jc_spiral_job* job_;
  static std::int32_t m_, p_;
  static nlohmann::json parameters_;
  static std::vector<double> nominal_, reference_metrics_;
};
jc_robot* CapiMisuseSpiralJob::robot_ = nullptr;
jc_spiral_job* CapiMisuseSpiralJob::job_ = nullptr;
std::int32_t CapiMisuseSpiralJob::m_ = 0;
std::int32_t CapiMisuseSpiralJob::p_ = 0;
nlohmann::json CapiMisuseSpiralJob::parameters_;
std::vector<double> CapiMisuseSpiralJob::nominal_, CapiMisuseSpiralJob::reference_metrics_;

// Every job call with good arguments but the job; outputs in `out` (kUntouched) and `count`.
struct JobCall {
  const char* name;
  jc_status (*call)(jc_spiral_job* job, const std::vector<double>& values, std::vector<double>& out,
                    std::int32_t& count);
};
const JobCall kJobCalls[] = {
    {"jc_spiral_job_sizes", [](jc_spiral_job* job, const std::vector<double>&, std::vector<double>&,
                               std::int32_t& count) { return jc_spiral_job_sizes(job, &count, &count); }},
    {"jc_spiral_job_time",
     [](jc_spiral_job* job, const std::vector<double>&, std::vector<double>& out, std::int32_t&) {
       return jc_spiral_job_time(job, out.data(), static_cast<std::int32_t>(out.size()));
     }},
    {"jc_spiral_job_parameters", [](jc_spiral_job* job, const std::vector<double>&, std::vector<double>&,
                                    std::int32_t& count) { return jc_spiral_job_parameters(job, nullptr, 0, &count); }},
    {"jc_spiral_job_run",
     [](jc_spiral_job* job, const std::vector<double>& values, std::vector<double>& out, std::int32_t&) {
       return jc_spiral_job_run(job, values.data(), static_cast<std::int32_t>(values.size()), 7, out.data(), 15,
                                nullptr, 0);
     }},
};

bool untouched(const std::vector<double>& out) {
  for (double x : out) {
    if (x != kUntouched) return false;
  }
  return true;
}

TEST_F(CapiMisuseSpiralJob, NullForeignNeverAndFreedJobsAreRefusedByName) {
  std::vector<double> out(static_cast<std::size_t>(m_), kUntouched);
  std::int32_t count = 777;
  jc_spiral_job* freed = nullptr;
  ASSERT_EQ(jc_spiral_job_create(robot_, 0, &freed), JC_OK);
  ASSERT_EQ(jc_spiral_job_free(freed), JC_OK);
  std::vector<unsigned char> garbage(256, 0xab);
  for (const JobCall& c : kJobCalls) {
    EXPECT_INVALID(c.name, "job is NULL", c.call(nullptr, nominal_, out, count));
    EXPECT_FAILS(JC_ERROR_WRONG_HANDLE, c.name, "got a jc_robot",
                 c.call(reinterpret_cast<jc_spiral_job*>(robot_), nominal_, out, count));
    EXPECT_FAILS(JC_ERROR_WRONG_HANDLE, c.name, "not a live jointcomp handle",
                 c.call(reinterpret_cast<jc_spiral_job*>(garbage.data()), nominal_, out, count));
    EXPECT_FAILS(JC_ERROR_WRONG_HANDLE, c.name, "already freed", c.call(freed, nominal_, out, count));
  }
  EXPECT_TRUE(untouched(out));
  EXPECT_EQ(count, 777);
  EXPECT_EQ(jc_spiral_job_free(nullptr), JC_OK) << "freeing NULL is a no-op";
  EXPECT_FAILS(JC_ERROR_WRONG_HANDLE, "jc_spiral_job_free", "already freed", jc_spiral_job_free(freed));
  EXPECT_FAILS(JC_ERROR_WRONG_HANDLE, "jc_spiral_job_free", "got a jc_robot",
               jc_spiral_job_free(reinterpret_cast<jc_spiral_job*>(robot_)));
  std::int32_t dof = 777;
  EXPECT_FAILS(JC_ERROR_WRONG_HANDLE, "jc_robot_dof", "got a jc_spiral_job",
               jc_robot_dof(reinterpret_cast<jc_robot*>(job_), &dof));
  EXPECT_EQ(dof, 777);
}

TEST_F(CapiMisuseSpiralJob, CreateRefusesNullRobotsBadFlagsAndAPlantWithoutDrives) {
  jc_spiral_job* const sentinel = reinterpret_cast<jc_spiral_job*>(&p_);  // never written by a failing create
  jc_spiral_job* job = sentinel;
  EXPECT_INVALID("jc_spiral_job_create", "nominal is NULL", jc_spiral_job_create(nullptr, 0, &job));
  EXPECT_INVALID("jc_spiral_job_create", "job is NULL", jc_spiral_job_create(robot_, 0, nullptr));
  for (std::int32_t flag : {-1, 2, kHuge, kMostNegative}) {
    EXPECT_INVALID("jc_spiral_job_create", "use_plant is " + std::to_string(flag),
                   jc_spiral_job_create(robot_, flag, &job));
  }
  jc_robot* bare = nullptr;  // kinematics and dynamics only: no drives
  ASSERT_EQ(jc_robot_load(kUrdf.c_str(), nullptr, &bare), JC_OK);
  EXPECT_INVALID("jc_spiral_job_create", "no \"plant\" object", jc_spiral_job_create(bare, 1, &job));
  jc_robot_free(bare);
  EXPECT_EQ(job, sentinel);
}

TEST_F(CapiMisuseSpiralJob, SizesTimeAndParametersRefuseBadOutputs) {
  std::int32_t count = 777;
  EXPECT_INVALID("jc_spiral_job_sizes", "samples is NULL", jc_spiral_job_sizes(job_, nullptr, &count));
  EXPECT_INVALID("jc_spiral_job_sizes", "parameters is NULL", jc_spiral_job_sizes(job_, &count, nullptr));
  EXPECT_EQ(count, 777);
  std::vector<double> time(static_cast<std::size_t>(m_) + 1, kUntouched);
  EXPECT_INVALID("jc_spiral_job_time", "time is NULL", jc_spiral_job_time(job_, nullptr, m_));
  for (std::int32_t length : wrongLengths(m_)) {
    EXPECT_INVALID("jc_spiral_job_time", "time_len is " + std::to_string(length),
                   jc_spiral_job_time(job_, time.data(), length));
  }
  EXPECT_TRUE(untouched(time));
  std::string buffer(8, 'x');
  std::int32_t length = 777;
  EXPECT_INVALID("jc_spiral_job_parameters", "length is NULL", jc_spiral_job_parameters(job_, &buffer[0], 8, nullptr));
  EXPECT_INVALID("jc_spiral_job_parameters", "capacity is negative",
                 jc_spiral_job_parameters(job_, &buffer[0], -1, &length));
  EXPECT_INVALID("jc_spiral_job_parameters", "buffer is NULL", jc_spiral_job_parameters(job_, nullptr, 8, &length));
  EXPECT_INVALID("jc_spiral_job_parameters", "buffer holds 8 bytes",
                 jc_spiral_job_parameters(job_, &buffer[0], 8, &length));
  EXPECT_EQ(buffer, std::string(8, 'x'));
  EXPECT_EQ(length, 777);
}

TEST_F(CapiMisuseSpiralJob, RunRefusesBadValuesSeedsAndOutputs) {
  std::vector<double> metrics(16, kUntouched), errors(9 * static_cast<std::size_t>(m_) + 1, kUntouched);
  const auto run = [&](const double* values, std::int32_t values_len, std::int64_t seed, double* m, std::int32_t m_len,
                       double* e, std::int32_t e_len) {
    return jc_spiral_job_run(job_, values, values_len, seed, m, m_len, e, e_len);
  };
  const char* name = "jc_spiral_job_run";
  EXPECT_INVALID(name, "values is NULL", run(nullptr, p_, 7, metrics.data(), 15, nullptr, 0));
  for (std::int32_t length : wrongLengths(p_)) {
    EXPECT_INVALID(name, "values_len is " + std::to_string(length),
                   run(nominal_.data(), length, 7, metrics.data(), 15, nullptr, 0));
  }
  for (double bad : {kNaN, kInf, -kInf}) {
    for (std::int32_t k : {0, p_ / 2, p_ - 1}) {  // an effect's value, and a geometry deviation last
      std::vector<double> values = nominal_;
      values[static_cast<std::size_t>(k)] = bad;
      EXPECT_INVALID(name, "values[" + std::to_string(k) + "]",
                     run(values.data(), p_, 7, metrics.data(), 15, errors.data(), 9 * m_));
    }
  }
  // A value out of its parameter's range is refused naming the parameter.
  for (double stiffness : {0.0, -1e5}) {
    std::vector<double> values = nominal_;
    values[static_cast<std::size_t>(index("joint_2.stiffness_nm_per_rad"))] = stiffness;
    EXPECT_INVALID(name, "joint_2.stiffness_nm_per_rad", run(values.data(), p_, 7, metrics.data(), 15, nullptr, 0));
  }
  for (std::int64_t seed : {std::int64_t{-1}, std::numeric_limits<std::int64_t>::min()}) {
    EXPECT_INVALID(name, "noise_seed is " + std::to_string(seed),
                   run(nominal_.data(), p_, seed, metrics.data(), 15, nullptr, 0));
  }
  EXPECT_INVALID(name, "metrics is NULL", run(nominal_.data(), p_, 7, nullptr, 15, nullptr, 0));
  for (std::int32_t length : wrongLengths(15)) {
    EXPECT_INVALID(name, "metrics_len is " + std::to_string(length),
                   run(nominal_.data(), p_, 7, metrics.data(), length, nullptr, 0));
  }
  for (std::int32_t length : wrongLengths(9 * m_)) {
    EXPECT_INVALID(name, "errors_len is " + std::to_string(length),
                   run(nominal_.data(), p_, 7, metrics.data(), 15, errors.data(), length));
  }
  EXPECT_INVALID(name, "errors_len is 5", run(nominal_.data(), p_, 7, metrics.data(), 15, nullptr, 5));
  EXPECT_TRUE(untouched(metrics));
  EXPECT_TRUE(untouched(errors));
}

}  // namespace
