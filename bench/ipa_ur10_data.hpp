// The IPA UR10 laser-tracker data and the nominal UR10, as the calibration and discovery benchmarks read
// them. The data is not in the repository: it is found under $JOINTCOMP_SHARED/data/ipa-ur10 (the one
// setting for such data; README, Tests).
#pragma once

#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>

#include "model/effects/joint_error_model.hpp"
#include "model/io/ipa_ur10_import.hpp"
#include "model/robot/load_urdf.hpp"

namespace bench_ipa {

inline std::string ipa(const std::string& file) {
  const char* root = std::getenv("JOINTCOMP_SHARED");
  return std::string(root && *root ? root : "(JOINTCOMP_SHARED not set)") + "/data/ipa-ur10/" + file;
}

inline bool haveData() { return std::ifstream(ipa("Series_A/measurements_grid.csv")).good(); }

inline const jointcomp::JointErrorModel& prior() {
  static const jointcomp::JointErrorModel model(
      std::make_shared<const jointcomp::Robot>(
          jointcomp::loadRobotFromUrdfFile(std::string(JOINTCOMP_DATA_DIR) + "/robots/ur10.urdf")),
      jointcomp::GearTrain::direct(6), {});
  return model;
}

inline const jointcomp::MeasurementCampaign& seriesA() {
  static const jointcomp::MeasurementCampaign campaign =
      jointcomp::importIpaUr10(ipa("Series_A/measurements_grid.csv"), ipa("Series_A/Trafo_TM_F_init.txt"));
  return campaign;
}

inline const jointcomp::MeasurementCampaign& seriesB() {
  static const jointcomp::MeasurementCampaign campaign = jointcomp::importIpaUr10(
      ipa("Series_B/measurements_joint_configurations.csv"), ipa("Series_B/Trafo_TM_F_init.txt"));
  return campaign;
}

}  // namespace bench_ipa
