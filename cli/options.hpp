// A small command-line option reader: --name value pairs, with clear errors for unknown or missing ones.
#pragma once

#include <cstddef>
#include <functional>
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

// What a message quotes of a value the user gave: the whole of a short one, the start of a long one with
// its length ("abc..." (10000067 characters)), so that a 10 MB argument does not become a 10 MB message.
std::string excerpt(const std::string& text, std::size_t keep = 48);

// The range a number option must lie in: [min, max], or (min, max] with min_open (a scale, a speed).
struct Bounds {
  double min;
  double max;
  bool min_open = false;
};

// One shared reader for every numeric option of every command: the whole text must be the number
// ("5x", "1e3" for an integer, "nan", "inf" refused) and within the bounds. The problem as a sentence
// ("'5x' is not an integer", "-1 is out of range: ..."), or "" when the text is fine.
std::string numberProblem(const std::string& text, const Bounds& bounds);
std::string integerProblem(const std::string& text, long long min, long long max);
// The same, thrown as a UsageError naming --option (exit 2).
double parseNumber(const std::string& text, const std::string& option, const Bounds& bounds);
long long parseInteger(const std::string& text, const std::string& option, long long min, long long max);

// The same readers as CLI11 checks (option->check(integerCheck(1, 100))), for the commands that declare
// their options to CLI11 directly: the problem, or "" when the text is fine.
std::function<std::string(const std::string&)> integerCheck(long long min, long long max);
std::function<std::string(const std::string&)> numberCheck(const Bounds& bounds);

// Seeds: non-negative integers up to 2^62, in every command.
constexpr long long kMaxSeed = 1LL << 62;

// Limits of discover's options: its work and memory grow with the candidates (harmonic orders), the steps
// and the folds (a normal matrix per fold). Beyond them the option is refused with the number.
constexpr long long kMaxDiscoverySteps = 64;
constexpr long long kMaxHarmonicOrder = 64;
constexpr long long kMaxFolds = 20;
constexpr std::size_t kMinRowsPerFold = 5;

// "1,2.5,-3" -> {1, 2.5, -3}; throws naming --option and the item that is not a finite number in `bounds`.
std::vector<double> numberList(const std::string& text, const std::string& option,
                               const Bounds& bounds = {-1e300, 1e300});

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
  // --name read whole and range-checked (parseNumber, parseInteger); `fallback` when it is not given.
  double number(const std::string& name, double fallback, const Bounds& bounds) const;
  long long integer(const std::string& name, long long fallback, long long min, long long max) const;
  std::string get(const std::string& name, const std::string& fallback) const {
    auto it = values_.find(name);
    return it == values_.end() ? fallback : it->second;
  }

private:
  std::map<std::string, std::string> values_;
};

}  // namespace jointcomp::cli
