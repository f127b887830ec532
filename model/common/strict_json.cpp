#include "model/common/strict_json.hpp"
#include "model/common/plain_text.hpp"

#include <set>
#include <vector>

#include "model/common/errors.hpp"

namespace jointcomp {

std::string shortExcerpt(const std::string& message) {
  if (message.size() <= kMaxQuotedCharacters) return message;
  return message.substr(0, kMaxQuotedCharacters) + "... (" + std::to_string(message.size() - kMaxQuotedCharacters) +
         " more characters)";
}

nlohmann::json parseStrictJson(const std::string& text, const std::string& source_name) {
  // One set of keys per open object, and the path of keys that leads to it, for the message.
  std::vector<std::set<std::string>> keys;
  std::vector<std::string> path;
  auto where = [&path]() {
    std::string p;
    for (const std::string& k : path) p += (p.empty() ? "" : ".") + k;
    return p.empty() ? std::string("the top-level object") : "'" + p + "'";
  };
  using Event = nlohmann::json::parse_event_t;
  const nlohmann::json::parser_callback_t check = [&](int depth, Event event, nlohmann::json& parsed) {
    if (event == Event::object_start) {
      keys.emplace_back();
      path.resize(static_cast<std::size_t>(depth), "[]");  // an object inside an array
    } else if (event == Event::object_end) {
      if (!keys.empty()) keys.pop_back();
    } else if (event == Event::key) {
      const std::string key = parsed.get<std::string>();
      path.resize(static_cast<std::size_t>(depth > 0 ? depth - 1 : 0));
      if (!keys.empty() && !keys.back().insert(key).second) {
        throw ParameterError(source_name + ": the key '" + shortExcerpt(key) + "' appears twice in " + where() +
                             " (JSON keys must be unique: which one was meant?)");
      }
      path.push_back(key);
    }
    return true;
  };
  std::string storage;
  const std::string& body = plainText<ParameterError>(text, source_name, storage);
  try {
    return nlohmann::json::parse(body, check);
  } catch (const nlohmann::json::parse_error& error) {
    throw ParameterError(source_name + ": not valid JSON (byte " + std::to_string(error.byte) +
                         "): " + shortExcerpt(error.what()));
  } catch (const nlohmann::json::exception& error) {  // e.g. a number too large for a double
    throw ParameterError(source_name + ": not valid JSON: " + shortExcerpt(error.what()));
  }
}

}  // namespace jointcomp
