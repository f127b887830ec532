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

// `jointcomp <command> --help` was shown: the command ends there, successfully.
struct HelpShown {};

// A command line that does not parse (an unknown option, a missing value): main prints it with the
// command's usage and exits 2.
class UsageError : public std::invalid_argument {
public:
  using std::invalid_argument::invalid_argument;
};

}  // namespace jointcomp::cli
namespace CLI {
class App;
}
namespace jointcomp::cli {

// Parses `app` the way every command does: --help prints the usage and throws HelpShown, a command line
// that does not parse throws UsageError carrying the message and the usage.
void parseCommandLine(CLI::App& app, int argc, char** argv);

// What each option means, for --help (one table: the options mean the same in every command).
const char* optionHelp(const std::string& name);

// The options of one command, parsed by CLI11: --name value pairs (or bare --flag when `flags` holds the
// name), --help for the command's usage. `command` names it in the usage ("identify stiffness"; default:
// argv[0], the command name main passes).
class Options {
public:
  Options(int argc, char** argv, const std::set<std::string>& known, const std::set<std::string>& flags = {},
          const std::string& command = "");
  bool has(const std::string& name) const { return values_.count(name) != 0; }
  std::string get(const std::string& name, const std::string& fallback) const {
    auto it = values_.find(name);
    return it == values_.end() ? fallback : it->second;
  }

private:
  std::map<std::string, std::string> values_;
};

}  // namespace jointcomp::cli
