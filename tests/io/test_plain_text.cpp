// Text inputs with a UTF-8 byte-order mark are read as without it; UTF-16, UTF-32 and NUL bytes are refused
// naming the source and the byte offset, by every reader of user text (issue 41: a BOM made the IPA importer
// say "'Timestamp' is missing", a NUL cut a message mid-sentence).
#include <functional>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/common/plain_text.hpp"
#include "model/common/strict_json.hpp"
#include "model/io/csv_import.hpp"
#include "model/io/ipa_ur10_import.hpp"
#include "model/io/measurement_campaign.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

const std::string kBom = "\xEF\xBB\xBF";

const std::string kIpa =
    "Timestamp;Goal x;Goal y;Goal z;Goal roll;Goal pitch;Goal yaw;shoulder_pan_joint;shoulder_lift_joint;"
    "elbow_joint;wrist_1_joint;wrist_2_joint;wrist_3_joint;measurement_temperature;measurement_x;measurement_y;"
    "measurement_z;measurement_rx;measurement_ry;measurement_rz\n"
    "20200714163904;0,365141;-0,000212669;1,4273;1,57002;1,57007;1,57073;-1,5708;-1,5708;0,0;-1,5708;0,0;0,0;"
    "23,68;2361,9831;-1368,5474;119,39713;-90,409151;-59,885105;-90,887438\n"
    "20200714163924;0,8;0,6;0,9;1,74533;1,5708;1,5708;-2,14055;-2,08493;-0,837441;-0,218756;0,393594;-0,00187856;"
    "23,68;1685,2797;-1665,3456;-415,81103;-90,282663;-49,675357;-90,926009\n";

std::string urdf() {
  return "<?xml version=\"1.0\"?><robot name=\"r\"><link name=\"base\"/><link name=\"l1\"><inertial><mass "
         "value=\"1\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/></inertial>"
         "</link><joint name=\"j1\" type=\"revolute\"><parent link=\"base\"/><child link=\"l1\"/><axis "
         "xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint></robot>";
}

// UTF-16 little-endian with its mark, as Windows' Notepad saves "Unicode".
std::string utf16(const std::string& ascii) {
  std::string out = "\xFF\xFE";
  for (char c : ascii) {
    out.push_back(c);
    out.push_back('\0');
  }
  return out;
}

struct Reader {
  const char* name;
  std::string good;
  std::function<void(const std::string& text, const std::string& source)> read;
};

std::vector<Reader> readers() {
  return {
      {"urdf", urdf(), [](const std::string& t, const std::string& s) { loadRobotFromUrdfString(t, s); }},
      {"json", "{\"a\": 1}", [](const std::string& t, const std::string& s) { parseStrictJson(t, s); }},
      {"ipa", kIpa, [](const std::string& t, const std::string& s) { parseIpaUr10(t, s); }},
      {"csv", "q1,q2,x,y,z\n0.1,0.2,1,2,3\n0.2,0.3,1,2,3\n",
       [](const std::string& t, const std::string& s) { importCsv(t, s, CsvImportOptions{}); }},
  };
}

TEST(PlainText, AByteOrderMarkIsSkippedByEveryReader) {
  for (const Reader& r : readers()) {
    EXPECT_NO_THROW(r.read(r.good, "plain.txt")) << r.name;  // the text itself is fine
    EXPECT_NO_THROW(r.read(kBom + r.good, "with_bom.txt")) << r.name;
  }
}

TEST(PlainText, NulBytesAndUtf16AreRefusedNamingTheSourceAndTheOffset) {
  for (const Reader& r : readers()) {
    std::string with_nul = r.good;
    with_nul.insert(7, 1, '\0');
    const std::vector<std::pair<std::string, std::string>> cases = {
        {with_nul, "bad.txt: byte 7 is a NUL byte"},
        {utf16(r.good), "bad.txt: bytes 0-1 are a UTF-16 byte-order mark"},
        {std::string("\xFF\xFE\0\0", 4) + "x", "bad.txt: bytes 0-3 are a UTF-32 byte-order mark"},
        {r.good.substr(0, 3) + std::string(1, '\0'), "bad.txt: byte 3 is a NUL byte"},
    };
    for (const auto& [text, says] : cases) {
      try {
        r.read(text, "bad.txt");
        ADD_FAILURE() << r.name << " accepted " << says;
      } catch (const Error& error) {
        EXPECT_THAT(error.what(), HasSubstr(says)) << r.name;
        EXPECT_THAT(error.what(), HasSubstr("save it as UTF-8 text")) << r.name;
      }
    }
  }
}

TEST(PlainText, TheIpaImporterReadsAFileWithAByteOrderMarkAsWithout) {
  const MeasurementCampaign plain = parseIpaUr10(kIpa, "a.csv");
  const MeasurementCampaign marked = parseIpaUr10(kBom + kIpa, "b.csv");
  ASSERT_EQ(plain.size(), 2u);
  ASSERT_EQ(marked.size(), plain.size());
  EXPECT_EQ(marked.command[1], plain.command[1]);
  EXPECT_EQ(marked.time, plain.time);
}

TEST(PlainText, TheCheckItself) {
  EXPECT_EQ(plainTextProblem("plain text\n"), "");
  EXPECT_EQ(plainTextProblem(""), "");
  EXPECT_EQ(byteOrderMarkLength(kBom + "x"), 3u);
  EXPECT_EQ(byteOrderMarkLength("\xEF\xBB"), 0u);  // a mark cut short is not one
  EXPECT_THAT(plainTextProblem(std::string("ab\0", 3)), HasSubstr("byte 2 is a NUL byte"));
  EXPECT_THAT(plainTextProblem("\xFE\xFF"), HasSubstr("UTF-16"));
  EXPECT_THAT(plainTextProblem(std::string("\0\0\xFE\xFF", 4)), HasSubstr("UTF-32"));
}

}  // namespace
}  // namespace jointcomp
