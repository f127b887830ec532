// Shared helpers of the identification tests: the shipped RX170 and its parameter file, a seeded "true"
// robot, the true stiffness of a model, the check of a measurement error's message, and a temporary
// directory.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/effects/compliance.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/effects/perturbation.hpp"
#include "model/effects/transmission_error.hpp"
#include "model/experiment/campaign_simulation.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp {
namespace identify_test {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;

inline std::shared_ptr<const Robot> rx170() {
  static const std::shared_ptr<const Robot> robot =
      std::make_shared<const Robot>(loadRobotFromUrdfFile(std::string(JOINTCOMP_DATA_DIR) + "/robots/rx170.urdf"));
  return robot;
}

inline JointErrorModel rx170Model() {
  return loadParameterFile(std::string(JOINTCOMP_DATA_DIR) + "/params/rx170.json", rx170());
}

// The RX170 as it "really" is: the nominal parameters moved by a seeded perturbation.
inline JointErrorModel truthModel(std::uint64_t seed) {
  PerturbationSpec perturbation;
  perturbation.seed = seed;
  return perturbedModel(rx170Model(), perturbation);
}

// A campaign of `count` random well-conditioned poses measured on `truth` (seeded tracker noise).
inline MeasurementCampaign randomCampaign(const JointErrorModel& truth, int count, std::uint64_t seed) {
  CampaignSimulationSpec spec;
  spec.protocol = CampaignProtocol::RandomPoses;
  spec.seed = seed;
  spec.random.count = count;
  return simulateCampaign(truth, spec);
}

// `model` with one more transmission-error harmonic.
inline JointErrorModel withHarmonic(JointErrorModel model, int joint, int stage, double cycles, double amplitude,
                                    double phase = 0.6) {
  Harmonic h;
  h.joint = joint;
  h.stage = stage;
  h.cycles_per_revolution = cycles;
  h.amplitude_rad = amplitude;
  h.phase_rad = phase;
  model.addEffect(std::make_unique<TransmissionErrorEffect>(model.robot(), model.gears(), std::vector<Harmonic>{h}));
  return model;
}

// `call` must throw a MeasurementError whose message contains `fragment`.
template <typename Call>
void expectMeasurementError(Call call, const std::string& fragment) {
  try {
    call();
    ADD_FAILURE() << "no error; expected one with '" << fragment << "'";
  } catch (const MeasurementError& error) {
    EXPECT_THAT(error.what(), ::testing::HasSubstr(fragment));
  }
}

inline double stiffnessOf(const JointErrorModel& model, int joint) {
  const int index = model.findEffect(ComplianceEffect::kType);
  return static_cast<const ComplianceEffect&>(model.effect(index)).stiffness(joint);
}

// A fresh directory under the system's temporary directory, removed by the destructor.
class TemporaryDirectory {
public:
  explicit TemporaryDirectory(const std::string& name)
      : path_(std::filesystem::temp_directory_path() / ("jointcomp_identify_" + name)) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TemporaryDirectory() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

private:
  std::filesystem::path path_;
};

}  // namespace identify_test
}  // namespace jointcomp
