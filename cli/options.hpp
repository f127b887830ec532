// A small command-line option reader: --name value pairs, with clear errors for unknown or missing ones.
#pragma once

#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace jointcomp::cli {

// "a,b,,c" -> {"a", "b", "c"}: the items of a comma-separated option value, empty ones dropped.
inline std::vector<std::string> splitCommaList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

// "1,2.5,-3" -> {1, 2.5, -3}; throws naming --option and the item that is not a number.
inline std::vector<double> numberList(const std::string& text, const std::string& option) {
  std::vector<double> values;
  for (const std::string& item : splitCommaList(text)) {
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size())
      throw std::invalid_argument("--" + option + ": '" + item + "' is not a number");
    values.push_back(value);
  }
  return values;
}

class Options {
public:
  // Reads argv[1..argc) as --name value pairs (or bare --flag when `flags` holds the name).
  Options(int argc, char** argv, const std::set<std::string>& known, const std::set<std::string>& flags = {}) {
    for (int i = 1; i < argc; ++i) {
      std::string name = argv[i];
      if (name.rfind("--", 0) != 0 || known.count(name.substr(2)) == 0) {
        throw std::invalid_argument("unknown option '" + name + "' (see jointcomp help)");
      }
      name = name.substr(2);
      if (flags.count(name)) {
        values_[name] = "1";
        continue;
      }
      if (i + 1 >= argc) throw std::invalid_argument("option --" + name + " needs a value");
      values_[name] = argv[++i];
    }
  }
  bool has(const std::string& name) const { return values_.count(name) != 0; }
  std::string get(const std::string& name, const std::string& fallback) const {
    auto it = values_.find(name);
    return it == values_.end() ? fallback : it->second;
  }

private:
  std::map<std::string, std::string> values_;
};

}  // namespace jointcomp::cli
