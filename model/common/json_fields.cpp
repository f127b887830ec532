#include "model/common/json_fields.hpp"

#include <climits>
#include <cmath>
#include <cstdint>

#include "model/common/errors.hpp"

namespace jointcomp {

JsonFields::JsonFields(const nlohmann::json& object, std::string path) : object_(object), path_(std::move(path)) {
  if (!object_.is_object()) throw ParameterError(path_ + ": expected a JSON object");
}

std::string JsonFields::pathOf(const std::string& key) const {
  // A path that ends in ": " is a file name: its top-level keys follow without a dot.
  if (path_.size() >= 2 && path_.compare(path_.size() - 2, 2, ": ") == 0) return path_ + key;
  return path_ + "." + key;
}

void JsonFields::fail(const std::string& key, const std::string& what) const {
  throw ParameterError(pathOf(key) + ": " + what);
}

bool JsonFields::has(const std::string& key) const { return object_.contains(key); }

const nlohmann::json& JsonFields::require(const std::string& key) {
  seen_.insert(key);
  if (!object_.contains(key)) fail(key, "missing");
  return object_.at(key);
}

double JsonFields::number(const std::string& key) {
  const nlohmann::json& value = require(key);
  if (!value.is_number()) fail(key, "expected a number");
  const double x = value.get<double>();
  if (!std::isfinite(x)) fail(key, "not finite");
  return x;
}

double JsonFields::positiveNumber(const std::string& key) {
  const double x = number(key);
  if (!(x > 0.0)) fail(key, "must be positive, is " + std::to_string(x));
  return x;
}

double JsonFields::nonNegativeNumber(const std::string& key) {
  const double x = number(key);
  if (x < 0.0) fail(key, "must not be negative, is " + std::to_string(x));
  return x;
}

double JsonFields::numberOr(const std::string& key, double fallback) {
  if (!has(key)) {
    seen_.insert(key);
    return fallback;
  }
  return number(key);
}

int JsonFields::integer(const std::string& key) {
  const nlohmann::json& value = require(key);
  if (!value.is_number_integer()) fail(key, "expected an integer");
  // Beyond int's range the conversion would wrap to another number, silently: refused instead.
  if (value.is_number_unsigned() ? value.get<std::uint64_t>() > static_cast<std::uint64_t>(INT_MAX)
                                 : value.get<std::int64_t>() < INT_MIN || value.get<std::int64_t>() > INT_MAX) {
    fail(key, "out of range: " + value.dump());
  }
  return value.get<int>();
}

std::string JsonFields::text(const std::string& key) {
  const nlohmann::json& value = require(key);
  if (!value.is_string()) fail(key, "expected a string");
  return value.get<std::string>();
}

std::string JsonFields::textOr(const std::string& key, const std::string& fallback) {
  if (!has(key)) {
    seen_.insert(key);
    return fallback;
  }
  return text(key);
}

bool JsonFields::flagOr(const std::string& key, bool fallback) {
  seen_.insert(key);
  if (!has(key)) return fallback;
  if (!object_.at(key).is_boolean()) fail(key, "expected true or false");
  return object_.at(key).get<bool>();
}

std::vector<double> JsonFields::numbers(const std::string& key, int size) {
  const nlohmann::json& value = require(key);
  if (!value.is_array()) fail(key, "expected an array of numbers");
  if (size >= 0 && static_cast<int>(value.size()) != size) {
    fail(key, "expected " + std::to_string(size) + " values, found " + std::to_string(value.size()));
  }
  std::vector<double> result;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string element = key + "[" + std::to_string(i) + "]";
    if (!value[i].is_number()) fail(element, "expected a number");
    const double x = value[i].get<double>();
    if (!std::isfinite(x)) fail(element, "not finite");
    result.push_back(x);
  }
  return result;
}

const nlohmann::json& JsonFields::array(const std::string& key) {
  const nlohmann::json& value = require(key);
  if (!value.is_array()) fail(key, "expected an array");
  return value;
}

const nlohmann::json& JsonFields::object(const std::string& key) {
  const nlohmann::json& value = require(key);
  if (!value.is_object()) fail(key, "expected an object");
  return value;
}

void JsonFields::rejectUnknownKeys() const {
  for (const auto& item : object_.items()) {
    if (seen_.count(item.key()) == 0) fail(item.key(), "unknown key");
  }
}

}  // namespace jointcomp
