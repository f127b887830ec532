// The options_json argument of the C API's calls: a JSON object read key by key, shared by identification and
// the plant, so that every call refuses unknown keys and bad values the same way.
#pragma once

#include <nlohmann/json.hpp>

#include "api_support.hpp"
#include "model/common/json_fields.hpp"
#include "model/common/strict_json.hpp"

namespace jointcomp::capi {

// Reads options_json (NULL: no options) with `read`, which asks JsonFields for each key it knows; unknown
// keys and bad values become JC_ERROR_INVALID_ARGUMENT naming the key (e.g. "options_json.seed: ...").
template <class Read>
void readOptions(const char* options_json, Read&& read) {
  nlohmann::json options = nlohmann::json::object();
  try {
    if (options_json) options = parseStrictJson(options_json, "options_json");
  } catch (const ParameterError& error) {
    invalid(error.what());
  }
  if (!options.is_object()) invalid("options_json must be a JSON object, like {\"seed\": 3}");
  try {
    JsonFields fields(options, "options_json");
    read(fields);
    fields.rejectUnknownKeys();
  } catch (const ParameterError& error) {
    invalid(error.what());
  } catch (const InvalidArgument& error) {
    invalid(error.what());
  }
}

}  // namespace jointcomp::capi
