// libFuzzer target: any text given as a user's tracker export (separator and decimal mark detected) yields
// a campaign or a jointcomp::Error, never a crash; a campaign that imports is written in the format and
// read back with every row.
#include <cstddef>
#include <cstdint>
#include <string>

#include "model/common/errors.hpp"
#include "model/io/csv_import.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const jointcomp::MeasurementCampaign campaign = jointcomp::importCsv(text, "fuzz.csv", {});
    const jointcomp::MeasurementCampaign again = jointcomp::parseCampaign(jointcomp::campaignToText(campaign), "again");
    if (again.size() != campaign.size()) __builtin_trap();  // a round trip never loses a row
  } catch (const jointcomp::Error&) {}
  return 0;
}
