// The readers every command shares (issue 41): numbers parsed whole and range-checked, refused naming the
// option ("--seed 1e3" ran seed 1, "--seed -1" seed 2^64 - 1, "--folds 5x" 5 folds, "nan" slipped through
// every comparison); long values quoted as excerpts; names from user data made plain file names.
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/options.hpp"
#include "cli/output_paths.hpp"

namespace jointcomp::cli {
namespace {

using ::testing::HasSubstr;

// `call` must throw UsageError (exit 2) whose message has each of `phrases`.
template <typename Call>
void expectRefused(Call call, const std::vector<std::string>& phrases) {
  try {
    call();
    ADD_FAILURE() << "accepted";
  } catch (const UsageError& error) {
    for (const std::string& phrase : phrases) EXPECT_THAT(error.what(), HasSubstr(phrase));
  }
}

TEST(CliOptions, IntegersAreReadWholeAndInRange) {
  EXPECT_EQ(parseInteger("2012", "seed", 0, kMaxSeed), 2012);
  EXPECT_EQ(parseInteger("+7", "seed", 0, kMaxSeed), 7);
  EXPECT_EQ(parseInteger("4611686018427387904", "seed", 0, kMaxSeed), kMaxSeed);
  expectRefused([] { parseInteger("1e3", "seed", 0, kMaxSeed); }, {"--seed: '1e3' is not an integer"});
  expectRefused([] { parseInteger("-1", "seed", 0, kMaxSeed); },
                {"--seed: '-1' is out of range: it must be an integer from 0 to 4611686018427387904"});
  expectRefused([] { parseInteger("5x", "folds", 2, 20); }, {"--folds: '5x' is not a number"});
  expectRefused([] { parseInteger("2.5", "folds", 2, 20); }, {"--folds: '2.5' is not an integer"});
  expectRefused([] { parseInteger("", "folds", 2, 20); }, {"--folds: '' is not a number"});
  expectRefused([] { parseInteger(" 5", "folds", 2, 20); }, {"is not a number"});
  expectRefused([] { parseInteger("99999999999999999999999", "count", 1, 100); }, {"is out of range"});
  expectRefused([] { parseInteger("21", "folds", 2, 20); }, {"an integer from 2 to 20"});
}

TEST(CliOptions, NumbersAreReadWholeFiniteAndInRange) {
  EXPECT_DOUBLE_EQ(parseNumber("0.03", "feed-rate", {0.003, 2.0}), 0.03);
  EXPECT_DOUBLE_EQ(parseNumber("1e-2", "feed-rate", {0.003, 2.0}), 0.01);
  EXPECT_DOUBLE_EQ(parseNumber("+2", "feed-rate", {0.003, 2.0}), 2.0);
  EXPECT_DOUBLE_EQ(parseNumber("0", "min-cv-gain", {0.0, 1.0}), 0.0);
  for (const char* text : {"nan", "NaN", "inf", "-inf"}) {
    expectRefused(
        [&] {
          parseNumber(text, "min-cv-gain", {0.0, 1.0});
        },
        {"--min-cv-gain: '" + std::string(text) + "' is not a finite number"});
  }
  expectRefused(
      [] {
        parseNumber("0", "loss-scale-mm", {0.0, 1e6, true});
      },
      {"--loss-scale-mm: '0' is out of range: it must be greater than 0 and at most 1000000"});
  expectRefused([] { parseNumber("-1", "loss-scale-mm", {0.0, 1e6, true}); }, {"'-1' is out of range"});
  expectRefused(
      [] {
        parseNumber("1e-5", "feed-rate", {0.003, 2.0});
      },
      {"--feed-rate: '1e-5' is out of range: it must be from 0.003 to 2"});
  expectRefused([] { parseNumber("1e400", "feed-rate", {0.003, 2.0}); }, {"'1e400' is out of range"});
  expectRefused([] { parseNumber("0.5mm", "step", {0.0, 360.0, true}); }, {"--step: '0.5mm' is not a number"});
  expectRefused([] { parseNumber("0x10", "step", {0.0, 360.0, true}); }, {"is not a number"});
}

TEST(CliOptions, ListsAreCheckedItemByItem) {
  EXPECT_EQ(numberList("1,2.5,-3", "target"), (std::vector<double>{1, 2.5, -3}));
  expectRefused([] { numberList("1,nan,3", "target"); }, {"--target: 'nan' is not a finite number"});
  expectRefused([] { numberList("1,2,30000", "target", {-1e4, 1e4}); }, {"--target: '30000' is out of range"});
}

TEST(CliOptions, TheSameReadersCheckCli11Options) {
  EXPECT_EQ(integerCheck(1, 10000)("100"), "");
  EXPECT_EQ(integerCheck(1, 10000)("1073741824"),
            "'1073741824' is out of range: it must be an integer from 1 to 10000");
  EXPECT_EQ(numberCheck({0.0, 1e7, true})("nan"), "'nan' is not a finite number");
}

TEST(CliOptions, LongValuesAreQuotedAsExcerpts) {
  const std::string key(10000067, 'k');
  try {
    parseInteger(key, "seed", 0, kMaxSeed);
    ADD_FAILURE() << "accepted";
  } catch (const UsageError& error) {
    EXPECT_LT(std::string(error.what()).size(), 200u);
    EXPECT_THAT(error.what(), HasSubstr("...' (10000067 characters)"));
  }
  EXPECT_EQ(excerpt("short"), "'short'");
}

TEST(CliOptions, OptionsReadTheirNumbersThroughTheSharedReader) {
  std::vector<std::string> words = {"simulate", "--count", "2e9", "--seed", "1"};
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  const Options options(static_cast<int>(argv.size()), argv.data(), {"count", "seed", "cycles"});
  EXPECT_EQ(options.integer("seed", 5, 0, kMaxSeed), 1);
  EXPECT_EQ(options.integer("cycles", 5, 1, 10), 5);
  expectRefused([&] { options.integer("count", 200, 1, 100000); }, {"--count: '2e9' is not an integer"});
}

TEST(CliOutputNames, NamesFromUserDataArePlainFileNamesInsideOut) {
  // A URDF robot named "../../victim" made calibrate write <out>/../../victim_calibrated.urdf.
  EXPECT_EQ(plainFileName("../../victim"), "_.._victim");
  EXPECT_EQ(plainFileName(".."), "robot");
  EXPECT_EQ(plainFileName(""), "robot");
  EXPECT_EQ(plainFileName("/etc/passwd"), "_etc_passwd");
  EXPECT_EQ(plainFileName(".hidden"), "hidden");
  EXPECT_EQ(plainFileName("rx170"), "rx170");
  EXPECT_EQ(plainFileName("ur10-e_v2.1"), "ur10-e_v2.1");
  EXPECT_EQ(plainFileName("a b\nc\\d"), "a_b_c_d");
  EXPECT_EQ(plainFileName(std::string(1000, 'x')).size(), kMaxPlainNameLength);
}

TEST(CliOutputPaths, AnEmptyOrUnusableOutIsRefused) {
  EXPECT_THROW(prepareOutputFolder(""), std::invalid_argument);
  EXPECT_THROW(prepareOutputFolder("/proc/jointcomp-out"), std::invalid_argument);
}

}  // namespace
}  // namespace jointcomp::cli
