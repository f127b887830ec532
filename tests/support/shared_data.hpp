// Data the repository cannot carry (the IPA UR10 laser-tracker files, the FMI schemas) is found through one
// setting: the environment variable JOINTCOMP_SHARED, a folder holding data/ipa-ur10/ and fmi-schema/
// (.ci/run sets it to ../shared). Without it, or without the file there, a test that needs one skips and
// says what is missing and where.
#pragma once

#include <cstdlib>
#include <fstream>
#include <string>

namespace jointcomp::test {

// JOINTCOMP_SHARED/<relative>, or "" when the setting is absent.
inline std::string sharedFile(const std::string& relative) {
  const char* root = std::getenv("JOINTCOMP_SHARED");
  return root && *root ? std::string(root) + "/" + relative : std::string();
}

// "" when the file is there; otherwise the skip message, "skipped: <what> not found at <where>".
inline std::string missingSharedFile(const std::string& what, const std::string& relative) {
  const std::string path = sharedFile(relative);
  if (path.empty())
    return "skipped: " + what + " not found: JOINTCOMP_SHARED is not set (a folder with " + relative + ")";
  if (!std::ifstream(path).good()) return "skipped: " + what + " not found at " + path;
  return "";
}

}  // namespace jointcomp::test

// Skips the test unless JOINTCOMP_SHARED/<relative> is there.
#define JOINTCOMP_REQUIRE_SHARED_FILE(what, relative)                                           \
  do {                                                                                          \
    const std::string jointcomp_missing = ::jointcomp::test::missingSharedFile(what, relative); \
    if (!jointcomp_missing.empty()) GTEST_SKIP() << jointcomp_missing;                          \
  } while (false)
