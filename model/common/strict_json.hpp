// JSON read strictly: nlohmann keeps the last of a repeated key silently, and its parse errors quote the
// offending text whole (a gigabyte-long number came back in the message). Here a key repeated in one
// object is an error naming the key and where it is, and every message quotes at most a short excerpt.
#pragma once

#include <cstddef>
#include <string>

#include <nlohmann/json.hpp>

namespace jointcomp {

constexpr std::size_t kMaxQuotedCharacters = 200;

// Throws ParameterError "<source_name>: ..." for text that is not JSON or repeats a key in one object.
nlohmann::json parseStrictJson(const std::string& text, const std::string& source_name);

// `message` cut to kMaxQuotedCharacters, with what was cut said.
std::string shortExcerpt(const std::string& message);

}  // namespace jointcomp
