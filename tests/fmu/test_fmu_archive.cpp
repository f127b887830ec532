// The FMU's ZIP writer, read by independent readers: /usr/bin/python3's zipfile (testzip checks every
// CRC; the contents, names, folders and modes compared with what was written) and `unzip -t`.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <nlohmann/json.hpp>

#include "fmu/description/fmu_archive.hpp"
#include "model/common/errors.hpp"
#include "tests/support/child_process.hpp"

namespace jointcomp::fmu {
namespace {

constexpr const char* kPython = "/usr/bin/python3";

std::string scratch(const std::string& name) {
  std::filesystem::create_directories(JOINTCOMP_FMU_SCRATCH_DIR);
  return std::string(JOINTCOMP_FMU_SCRATCH_DIR) + "/" + name;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<ArchiveEntry> sampleEntries() {
  std::string every_byte;
  for (int i = 0; i < 256; ++i) every_byte += static_cast<char>(i);
  std::string large;
  for (std::uint32_t i = 0; i < 300000; ++i) large += static_cast<char>((i * 7919u) % 251u);
  return {{"modelDescription.xml", "<?xml version=\"1.0\"?>\n<a/>\n", false},
          {"binaries/linux64/jointcomp.so", large, true},
          {"resources/robot.json", "{}\n", false},
          {"resources/empty", "", false},
          {"resources/bytes.bin", every_byte, false},
          {"documentation/licenses/LICENSE.txt", "BSD\n", false},
          {"documentation/caf\xc3\xa9.txt", "utf-8 name\n", false}};
}

// zipfile's view: testzip's verdict, and per entry its name, mode and (files) contents in hex.
constexpr const char* kReader = R"(
import json, sys, zipfile
with zipfile.ZipFile(sys.argv[1]) as z:
    out = {'bad': z.testzip(), 'entries': [[i.filename, i.external_attr >> 16, i.compress_type,
                                            None if i.is_dir() else z.read(i).hex()] for i in z.infolist()]}
print(json.dumps(out))
)";

std::string hex(const std::string& bytes) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  for (const char c : bytes) {
    out += digits[(static_cast<unsigned char>(c) >> 4) & 0xF];
    out += digits[static_cast<unsigned char>(c) & 0xF];
  }
  return out;
}

TEST(Crc32, MatchesTheStandardCheckValueAndContinues) {
  const std::string text = "123456789";
  EXPECT_EQ(crc32(text.data(), text.size()), 0xCBF43926u);  // the CRC-32 check value (ISO-HDLC)
  EXPECT_EQ(crc32(nullptr, 0), 0u);
  const std::uint32_t first = crc32(text.data(), 4);
  EXPECT_EQ(crc32(text.data() + 4, text.size() - 4, first), 0xCBF43926u);
}

TEST(FmuArchive, ZipfileReadsBackEveryEntryWithItsFoldersAndModes) {
  const std::vector<ArchiveEntry> entries = sampleEntries();
  const std::string path = scratch("sample.zip");
  writeZipArchive(path, entries);
  const test::ChildResult read = test::runChild({kPython, "-c", kReader, path});
  ASSERT_EQ(read.exit_code, 0) << read.why << read.output;
  const nlohmann::json zip = nlohmann::json::parse(read.output);
  EXPECT_TRUE(zip["bad"].is_null()) << zip["bad"];
  // Each file after the folders it is in, each folder once.
  std::vector<std::string> expected_names = {"modelDescription.xml",
                                             "binaries/",
                                             "binaries/linux64/",
                                             "binaries/linux64/jointcomp.so",
                                             "resources/",
                                             "resources/robot.json",
                                             "resources/empty",
                                             "resources/bytes.bin",
                                             "documentation/",
                                             "documentation/licenses/",
                                             "documentation/licenses/LICENSE.txt",
                                             "documentation/caf\xc3\xa9.txt"};
  std::vector<std::string> names;
  for (const nlohmann::json& entry : zip["entries"]) names.push_back(entry[0]);
  EXPECT_EQ(names, expected_names);
  for (const nlohmann::json& entry : zip["entries"]) {
    const std::string name = entry[0];
    EXPECT_EQ(entry[2], 0) << name;  // stored
    if (name.back() == '/') {
      EXPECT_EQ(entry[1], 040755) << name;
      continue;
    }
    for (const ArchiveEntry& written : entries) {
      if (written.path != name) continue;
      EXPECT_EQ(entry[3], hex(written.contents)) << name;
      EXPECT_EQ(entry[1], written.executable ? 0100755 : 0100644) << name;
    }
  }
}

TEST(FmuArchive, UnzipTestsItClean) {
  if (::access("/usr/bin/unzip", X_OK) != 0) GTEST_SKIP() << "skipped: /usr/bin/unzip is not installed";
  const std::string path = scratch("unzip_test.zip");
  writeZipArchive(path, sampleEntries());
  const test::ChildResult unzip = test::runChild({"/usr/bin/unzip", "-t", path});
  EXPECT_EQ(unzip.exit_code, 0) << unzip.why << unzip.output;
  EXPECT_NE(unzip.output.find("No errors detected"), std::string::npos) << unzip.output;
}

TEST(FmuArchive, TheSameEntriesGiveTheSameBytes) {
  const std::string a = zipArchive(sampleEntries());
  EXPECT_EQ(a, zipArchive(sampleEntries()));
  std::vector<ArchiveEntry> changed = sampleEntries();
  changed[4].contents[17] ^= 1;  // one bit of one file
  EXPECT_NE(a, zipArchive(changed));
  EXPECT_EQ(a.size(), zipArchive(changed).size());
}

TEST(FmuArchive, ReplacesAnOldArchiveWhole) {
  const std::string path = scratch("replaced.zip");
  writeZipArchive(path, sampleEntries());
  const std::vector<ArchiveEntry> smaller = {{"modelDescription.xml", "x", false}};
  writeZipArchive(path, smaller);
  EXPECT_EQ(readFile(path), zipArchive(smaller));
}

TEST(FmuArchive, RefusesPathsThatAreNotPlainRelativeOnes) {
  const std::vector<std::pair<std::string, std::string>> refused = {
      {"", "empty path"}, {"/etc/passwd", "absolute"}, {"a/../b", "'..'"},   {"a//b", "empty"},
      {"a/./b", "'.'"},   {"a\\b", "backslash"},       {"folder/", "empty"}, {"tab\there", "control"},
  };
  for (const auto& [path, reason] : refused) {
    try {
      zipArchive({ArchiveEntry{path, "x", false}});
      ADD_FAILURE() << "'" << path << "' was accepted";
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(reason), std::string::npos) << error.what();
    }
  }
  EXPECT_THROW(zipArchive({{"a", "1", false}, {"a", "2", false}}), Error);    // twice
  EXPECT_THROW(zipArchive({{"a", "1", false}, {"a/b", "2", false}}), Error);  // a file and a folder
  EXPECT_THROW(writeZipArchive(scratch("no such folder/x.zip"), sampleEntries()), Error);
}

}  // namespace
}  // namespace jointcomp::fmu
