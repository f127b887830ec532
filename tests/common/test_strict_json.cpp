// Strict JSON: a key repeated in one object is an error naming the key and the object it is in (nlohmann
// alone keeps the last silently); the same key in different objects is fine; valid text reads exactly as
// nlohmann reads it; an error quotes at most a short excerpt of a huge bad value.
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/strict_json.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

std::string errorOf(const std::string& text) {
  try {
    parseStrictJson(text, "doc.json");
  } catch (const ParameterError& error) {
    return error.what();
  }
  return "";
}

TEST(StrictJson, ARepeatedKeyIsAnErrorNamingItAndWhereItIs) {
  EXPECT_THAT(errorOf(R"({"seed": 1, "seed": 2})"), HasSubstr("'seed' appears twice in the top-level object"));
  EXPECT_THAT(errorOf(R"({"plant": {"drives": {"kp": 1, "kd": 2, "kp": 3}}})"),
              HasSubstr("'kp' appears twice in 'plant.drives'"));
  EXPECT_THAT(errorOf(R"({"effects": [{"type": "a"}, {"type": "b", "type": "c"}]})"),
              HasSubstr("'type' appears twice in 'effects.[]'"));
  EXPECT_THAT(errorOf(R"({"a": 1, "a": 1})"), HasSubstr("doc.json"));
}

TEST(StrictJson, TheSameKeyInDifferentObjectsIsFineAndValidTextReadsAsNlohmannReadsIt) {
  const std::string text =
      R"({"a": {"x": 1, "y": [1, 2, {"x": 3}]}, "b": {"x": 2}, "list": [{"x": 1}, {"x": 1}], "x": null})";
  EXPECT_EQ(parseStrictJson(text, "doc.json"), nlohmann::json::parse(text));
  EXPECT_EQ(parseStrictJson("[1, 2.5, \"s\"]", "doc.json"), nlohmann::json::parse("[1, 2.5, \"s\"]"));
}

TEST(StrictJson, AnErrorQuotesAShortExcerptOfAHugeBadValue) {
  const std::string huge = "{\"mass\": " + std::string(100000, '7') + "x}";
  const std::string message = errorOf(huge);
  EXPECT_THAT(message, HasSubstr("not valid JSON"));
  EXPECT_LT(message.size(), 600u) << message.substr(0, 600);
  const std::string key(5000, 'k');
  EXPECT_LT(errorOf("{\"" + key + "\": 1, \"" + key + "\": 2}").size(), 600u);
  EXPECT_EQ(shortExcerpt("short"), "short");
}

}  // namespace
}  // namespace jointcomp
