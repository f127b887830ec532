// libFuzzer target: any text given to the IPA UR10 importer yields a campaign or a jointcomp::Error.
#include <cstddef>
#include <cstdint>
#include <string>

#include "model/common/errors.hpp"
#include "model/io/ipa_ur10_import.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    (void)jointcomp::parseIpaUr10(text, "fuzz.csv").size();
  } catch (const jointcomp::Error&) {}
  return 0;
}
