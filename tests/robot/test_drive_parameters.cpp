// The drives' named parameters: names joint by joint, get and set are inverse, a refused update names the
// parameter and changes nothing, and the names, the file's keys and the values agree with the JSON the
// parameter file holds (an independent path through the same numbers).
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/drive_parameters.hpp"
#include "tests/plant/plant_test_support.hpp"

namespace jointcomp {
namespace {

using namespace plant_testing;

std::vector<DriveParameters> rx170Drives() { return loadParameterSet(kParameters, rx170()).drives; }

TEST(DriveParameters, NamesFollowTheFileKeysJointByJoint) {
  const auto robot = rx170();
  const std::vector<DriveParameters> drives = rx170Drives();
  const std::vector<std::string> names = driveParameterNames(*robot);
  const std::vector<double> values = driveParameters(drives);
  ASSERT_EQ(names.size(), values.size());
  ASSERT_EQ(names.size(), static_cast<std::size_t>(robot->dof()) * driveFields().size());
  // Every name is "<joint>.<key>" and its value is what the file's JSON says for that joint and key.
  const nlohmann::json json = drivesToJson(drives, *robot);
  for (std::size_t k = 0; k < names.size(); ++k) {
    const std::size_t dot = names[k].find('.');
    ASSERT_NE(dot, std::string::npos) << names[k];
    const std::string joint = names[k].substr(0, dot), key = names[k].substr(dot + 1);
    bool found = false;
    for (const auto& entry : json.at("joints")) {
      if (entry.at("joint") != joint) continue;
      found = true;
      EXPECT_EQ(entry.at(key).get<double>(), values[k]) << names[k];
    }
    EXPECT_TRUE(found) << names[k];
  }
}

TEST(DriveParameters, SetIsTheInverseOfGet) {
  const auto robot = rx170();
  std::vector<DriveParameters> drives = rx170Drives();
  std::vector<double> values = driveParameters(drives);
  for (std::size_t k = 0; k < values.size(); ++k) values[k] *= 1.0 + 0.01 * static_cast<double>(k % 7);
  setDriveParameters(drives, *robot, values);
  EXPECT_EQ(driveParameters(drives), values);
  // And through the file: written and read back, the same numbers.
  const std::vector<DriveParameters> reread = drivesFromJson(drivesToJson(drives, *robot), *robot, "round trip");
  EXPECT_EQ(driveParameters(reread), values);
}

TEST(DriveParameters, ARefusedUpdateNamesTheParameterAndChangesNothing) {
  const auto robot = rx170();
  std::vector<DriveParameters> drives = rx170Drives();
  const std::vector<double> before = driveParameters(drives);
  const std::vector<std::string> names = driveParameterNames(*robot);
  struct Case {
    std::string name;
    double value;
  };
  const Case cases[] = {{robot->joints[1].name + ".kp_nm_per_rad", -1.0},
                        {robot->joints[2].name + ".motor_inertia_kgm2", 0.0},
                        {robot->joints[0].name + ".kd_nms_per_rad", std::numeric_limits<double>::quiet_NaN()},
                        {robot->joints[5].name + ".coulomb_friction_nm", std::numeric_limits<double>::infinity()}};
  for (const Case& c : cases) {
    std::vector<double> values = before;
    const auto at = std::find(names.begin(), names.end(), c.name);
    ASSERT_NE(at, names.end()) << c.name;
    values[static_cast<std::size_t>(at - names.begin())] = c.value;
    try {
      setDriveParameters(drives, *robot, values);
      ADD_FAILURE() << c.name << " = " << c.value << " was accepted";
    } catch (const ParameterError& e) {
      EXPECT_NE(std::string(e.what()).find(c.name), std::string::npos) << e.what();
    }
    EXPECT_EQ(driveParameters(drives), before) << c.name;
  }
  EXPECT_THROW(setDriveParameters(drives, *robot, std::vector<double>(before.size() - 1, 1.0)), ParameterError);
  EXPECT_EQ(driveParameters(drives), before);
}

}  // namespace
}  // namespace jointcomp
