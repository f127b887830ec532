// libFuzzer target: any text given as a parameter file (effects and plant drives) for the RX170 yields a
// model or a jointcomp::Error, never a crash; a model that loads is written and read back.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "model/common/errors.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/load_urdf.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const auto robot = std::make_shared<const jointcomp::Robot>(
      jointcomp::loadRobotFromUrdfFile(JOINTCOMP_DATA_DIR "/robots/rx170.urdf"));
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const jointcomp::JointErrorModel model = jointcomp::parseParameters(text, "fuzz.json", robot);
    const jointcomp::JointErrorModel again =
        jointcomp::parseParameters(jointcomp::parametersToJson(model), "again", robot);
    (void)again.effectCount();
  } catch (const jointcomp::Error&) {}
  try {
    (void)jointcomp::parseDriveParameters(text, "fuzz.json", *robot);
  } catch (const jointcomp::Error&) {}
  return 0;
}
