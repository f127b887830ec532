// URDFs the fuzzer found (tests/fuzz/regressions/urdf): each is refused with a UrdfError, never a crash.
#include <string>

#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/io/atomic_file.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp {
namespace {

const std::string kRegressions = std::string(JOINTCOMP_TEST_DATA_DIR) + "/../fuzz/regressions/urdf/";

// urdfdom rejects a joint whose child is its own parent link (and leaks what it built: tests/fuzz/lsan.supp).
TEST(UrdfFuzzRegressions, AJointWhoseChildIsItsParentLinkIsRefused) {
  const std::string text = readTextFile(kRegressions + "joint_child_is_its_parent_link.urdf", "URDF");
  ASSERT_FALSE(text.empty());
  EXPECT_THROW(loadRobotFromUrdfString(text, "fuzzed.urdf"), UrdfError);
}

}  // namespace
}  // namespace jointcomp
