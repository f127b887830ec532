// libFuzzer target: any text given to the URDF loader yields a Robot or a jointcomp::Error, never a crash.
#include <cstddef>
#include <cstdint>
#include <string>

#include "model/common/errors.hpp"
#include "model/robot/load_urdf.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const jointcomp::Robot robot = jointcomp::loadRobotFromUrdfString(text, "fuzz.urdf");
    (void)robot.dof();
  } catch (const jointcomp::Error&) {}
  return 0;
}
