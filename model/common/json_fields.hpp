// Strict reading of one JSON object of a parameter file: every key must be known, every value of the
// right type and finite, and every error names the path of the offending field.
#pragma once

#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace jointcomp {

class JsonFields {
public:
  // `path` is how the object is named in messages, e.g. "rx170.json: effects[1]".
  JsonFields(const nlohmann::json& object, std::string path);

  bool has(const std::string& key) const;
  double number(const std::string& key);
  double positiveNumber(const std::string& key);
  double nonNegativeNumber(const std::string& key);
  double numberOr(const std::string& key, double fallback);
  int integer(const std::string& key);
  std::string text(const std::string& key);
  std::string textOr(const std::string& key, const std::string& fallback);
  bool flagOr(const std::string& key, bool fallback);
  // An array of numbers; `size` < 0 accepts any length.
  std::vector<double> numbers(const std::string& key, int size = -1);
  const nlohmann::json& array(const std::string& key);
  const nlohmann::json& object(const std::string& key);
  // Throws ParameterError for any key that was never asked for.
  void rejectUnknownKeys() const;

  std::string pathOf(const std::string& key) const;
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;

private:
  const nlohmann::json& require(const std::string& key);

  const nlohmann::json& object_;
  std::string path_;
  std::set<std::string> seen_;
};

}  // namespace jointcomp
