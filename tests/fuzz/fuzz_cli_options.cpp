// libFuzzer target: any command line given to the options every command shares (cli/options.cpp) and any
// text given to the numeric readers yields values within their bounds or a UsageError naming the option,
// never a crash, a value outside its range or a message that grows with the input (issue 41).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "cli/output_paths.hpp"

namespace {

using namespace jointcomp::cli;

void expectBounded(const std::exception& error) {
  if (std::string(error.what()).size() > 4096) std::abort();  // an excerpt, never the whole input
}

void readers(const std::string& text) {
  try {
    const long long value = parseInteger(text, "seed", 0, kMaxSeed);
    if (value < 0 || value > kMaxSeed) std::abort();
  } catch (const UsageError& error) {
    expectBounded(error);
  }
  try {
    const double value = parseNumber(text, "loss-scale-mm", {0.0, 1e6, true});
    if (!(value > 0.0 && value <= 1e6)) std::abort();
  } catch (const UsageError& error) {
    expectBounded(error);
  }
  const std::string name = plainFileName(text);
  if (name.empty() || name.size() > kMaxPlainNameLength || name[0] == '.' ||
      name.find_first_of("/\\\n") != std::string::npos)
    std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  readers(text);
  // The same bytes as a command line: words separated by NUL or newline.
  std::vector<std::string> words = {"fuzz"};
  std::string word;
  for (const char c : text) {
    if (c == '\0' || c == '\n') {
      words.push_back(word);
      word.clear();
    } else {
      word += c;
    }
  }
  words.push_back(word);
  if (words.size() > 64) return 0;
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  try {
    const Options options(static_cast<int>(argv.size()), argv.data(), {"seed", "folds", "feed-rate", "quiet"},
                          {"quiet"});
    const long long folds = options.integer("folds", 5, 2, kMaxFolds);
    const double speed = options.number("feed-rate", 0.03, {0.003, 2.0});
    if (folds < 2 || folds > kMaxFolds || !(speed >= 0.003 && speed <= 2.0)) std::abort();
    (void)options.integer("seed", 1, 0, kMaxSeed);
  } catch (const HelpShown&) {
  } catch (const std::invalid_argument& error) {  // UsageError among them
    (void)error;
  }
  return 0;
}
