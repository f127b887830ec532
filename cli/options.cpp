#include "cli/options.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <system_error>

#include <CLI/CLI.hpp>

namespace jointcomp::cli {

namespace {

// Each option's line of --help, by its name without the dashes (a table, not code: kept out of optionHelp).
struct OptionHelp {
  const char* name;
  const char* text;
};
constexpr OptionHelp kOptionHelp[] = {
    {"urdf", "the robot's URDF"},
    {"base-link", "first link of the chain (default: the URDF's root)"},
    {"tip-link", "last link of the chain (default: the end of the longest moving chain, e.g. tool0)"},
    {"params", "parameter file (joint-error effects, gears, drives)"},
    {"truth", "parameter file of the simulated robot as it really is"},
    {"out", "output folder (a file for simulate, the importers and export-fmu); checked before any work"},
    {"campaign",
     "measurement campaign(s) to fit (docs/measurement-campaign.md), comma-separated or repeated; calibrate takes "
     "at most 1,000,000 rows in all (about 3.4 KB of memory a row), discover at most 100,000 (about 50 KB a row)"},
    {"holdout", "held-out campaign(s), evaluated with only their instrument frame refitted; repeatable"},
    {"seed", "random seed, 0 to 2^62"},
    {"compensate-joints", "joints whose references are compensated, e.g. 2,3 (default: all)"},
    {"no-plot", "write no plot"},
    {"quiet", "print no progress lines"},
    {"quasi-static", "simulate the quasi-static robot instead of the flexible-joint plant"},
    {"feed-rate",
     "tool speed along the path in m/s, 0.003 to 2 (default: the paper's 0.03); acceleration and jerk limits "
     "scale with it"},
    {"no-dynamic-correction",
     "only the paper's three runs (by default the plant's run has a fourth: stiffness, kinematic and dynamic "
     "correction)"},
    {"loss", "robust loss of the fit: huber, cauchy or none"},
    {"loss-scale-mm", "scale of the robust loss in mm, above 0 (default: from the least-squares residuals)"},
    {"pivot-threshold", "relative pivot below which a parameter counts as not identifiable, above 0 and at most 1"},
    {"fix", "calibration parameters held at nominal, comma-separated names"},
    {"geometry-limits",
     "OFFSET_DEG,SHIFT_MM,TURN_DEG: the largest correction of a joint's zero, of where its axis sits in its link, "
     "and of the axis's direction that a calibration may fit (default 5.73,20,2.86); a fit beyond is refused"},
    {"base",
     "discovery's base model: textbook (default: frame, target, joint offsets, the identifiable geometry and "
     "compliance, as calibrate fits them, so discover is never worse than calibrate) or frame (frame and target "
     "only; offsets, compliance and geometry are then candidates)"},
    {"table-knots",
     "knots per revolution of the periodic tables offered, comma-separated, 4 to 720 "
     "(default 16,32,64,128)"},
    {"max-prior-weight",
     "largest weight of a table's roughness prior, 0 to 1e6 (default 10; 0: none); "
     "cross-validation chooses among 0 and five decades up to it"},
    {"max-ridge-weight", "largest weight of a table's ridge toward zero, 0 to 1e6 (default 1; 0: none)"},
    {"transfer-significance",
     "standard errors by which a candidate may make a left-out group of rows worse (beyond 1 %), 0 to 100 "
     "(default 3)"},
    {"min-group-share",
     "smallest share of the rows a joint-space part of the transfer check holds, 0 to 0.49 "
     "(default 0.05; smaller parts join the nearest)"},
    {"angle-ranges", "ranges of a candidate's joint angle left out one at a time, 2 to 50 (default 5)"},
    {"no-pairs", "offer no pairs of one family's candidates on two joints"},
    {"holdout-same-instrument",
     "the held-out campaigns were measured with the fitted ones' instrument, not moved: an instrument scale "
     "discovery finds applies to them (default: each is another set-up)"},
    {"max-steps", "most effects discovery adds, 0 to 64"},
    {"orders", "highest harmonic order offered by default, 1 to 64 (identify: a list of orders)"},
    {"folds", "time blocks of the cross-validation, 2 to 20, and at most one per 5 rows of the fitted campaigns"},
    {"types", "candidate effect types to try, comma-separated (default: all)"},
    {"noise-floor-mm", "instrument noise floor in mm (3-D RMS), where discovery may stop, 0 to 1000"},
    {"min-cv-gain", "smallest relative cross-validation gain a candidate needs, 0 to 1"},
    {"joint", "joint number (1-based)"},
    {"stage", "gear stage"},
    {"use", "stiffness identification: local or global"},
    {"protocol", "stiffness, joint2-sweep, spiral, random or back-and-forth"},
    {"perturb", "perturb the truth with this seed and write it beside the campaign"},
    {"plant", "measure on the flexible-joint plant"},
    {"target",
     "target on the flange x,y,z in mm (the tool offset; calibrate: replaces the campaigns' # target:, fitted "
     "unless --fix target)"},
    {"from", "sweep start in deg"},
    {"to", "sweep end in deg"},
    {"step", "sweep step in deg (at most 1e6 steps)"},
    {"settle", "settling time per pose in s, at most 3600"},
    {"cycles", "number of back-and-forth cycles, 1 to 10000 (at most 1e6 rows in all)"},
    {"count", "number of random poses, 1 to 100000"},
    {"pose", "joint angles in deg, comma-separated"},
    {"no-noise", "simulate perfect instruments"},
    {"global-poses", "poses of the global stiffness protocol, 0 to 1000"},
    {"warm-up", "thermal warm-up RISE_DEGC[,TAU_S[,START_DEGC]]"},
    {"in", "the file to import"},
    {"trafo", "the IPA tracker-to-base transform file"},
    {"columns",
     "campaign column = export column, comma-separated (t=Time,q1=A1,...); joint_K columns are found as qK; "
     "x=X_target+dX takes the sum of two columns"},
    {"joints",
     "the number of joints, 1 to 12 (default: as many as mapped; refused when the header seems to hold one more)"},
    {"angles", "the export's angle unit: deg or rad"},
    {"lengths", "the export's length unit: mm or m"},
    {"separator", "the export's cell separator: , ; | or tab (default: detected)"},
    {"decimal", "the export's decimal mark: . or , (default: detected)"},
    {"robot", "the robot's name in the campaign's metadata"},
    {"frame", "the export's frame: base or instrument"},
    {"fmi", "FMI version of the FMU: 2 (default) or 3"},
    {"drives",
     "parameter file whose \"plant\" object (drives and controller gains) the FMU takes when --params has none "
     "(default: the shipped parameter file of the robot's name, if any)"},
};

}  // namespace

const char* optionHelp(const std::string& name) {
  for (const OptionHelp& option : kOptionHelp) {
    if (name == option.name) return option.text;
  }
  return "";
}

std::string excerpt(const std::string& text, std::size_t keep) {
  if (text.size() <= keep) return "'" + text + "'";
  return "'" + text.substr(0, keep) + "...' (" + std::to_string(text.size()) + " characters)";
}

namespace {

std::string formatBound(double value) {
  char text[40];
  std::snprintf(text, sizeof text, "%.10g", value);
  return text;
}

// from_chars takes no leading '+'; a sign is fine as long as the rest is the number.
const char* afterPlus(const std::string& text) {
  const char* first = text.data();
  return text.size() > 1 && text[0] == '+' && text[1] != '-' ? first + 1 : first;
}

}  // namespace

std::string numberProblem(const std::string& text, const Bounds& bounds) {
  double value = 0.0;
  const char* end = text.data() + text.size();
  const auto [stop, error] = std::from_chars(afterPlus(text), end, value);
  const std::string quoted = excerpt(text);
  const std::string range = (bounds.min_open ? "greater than " : "from ") + formatBound(bounds.min) +
                            (bounds.min_open ? " and at most " : " to ") + formatBound(bounds.max);
  if (text.empty() || stop != end || (error != std::errc() && error != std::errc::result_out_of_range))
    return quoted + " is not a number";
  if (error == std::errc::result_out_of_range) return quoted + " is out of range: it must be " + range;
  if (!std::isfinite(value)) return quoted + " is not a finite number";
  if (value < bounds.min || (bounds.min_open && value == bounds.min) || value > bounds.max)
    return quoted + " is out of range: it must be " + range;
  return "";
}

std::string integerProblem(const std::string& text, long long min, long long max) {
  long long value = 0;
  const char* end = text.data() + text.size();
  const auto [stop, error] = std::from_chars(afterPlus(text), end, value);
  const std::string quoted = excerpt(text);
  const std::string range = "an integer from " + std::to_string(min) + " to " + std::to_string(max);
  if (text.empty() || stop != end || (error != std::errc() && error != std::errc::result_out_of_range))
    return quoted + " is not " + (text.find_first_of(".eE") != std::string::npos ? "an integer" : "a number") + " (" +
           range + ")";
  if (error == std::errc::result_out_of_range || value < min || value > max)
    return quoted + " is out of range: it must be " + range;
  return "";
}

double parseNumber(const std::string& text, const std::string& option, const Bounds& bounds) {
  const std::string problem = numberProblem(text, bounds);
  if (!problem.empty()) throw UsageError("--" + option + ": " + problem);
  double value = 0.0;
  std::from_chars(afterPlus(text), text.data() + text.size(), value);
  return value;
}

long long parseInteger(const std::string& text, const std::string& option, long long min, long long max) {
  const std::string problem = integerProblem(text, min, max);
  if (!problem.empty()) throw UsageError("--" + option + ": " + problem);
  long long value = 0;
  std::from_chars(afterPlus(text), text.data() + text.size(), value);
  return value;
}

std::vector<double> numberList(const std::string& text, const std::string& option, const Bounds& bounds) {
  std::vector<double> values;
  for (const std::string& item : splitCommaList(text)) values.push_back(parseNumber(item, option, bounds));
  return values;
}

std::function<std::string(const std::string&)> integerCheck(long long min, long long max) {
  return [min, max](const std::string& text) { return integerProblem(text, min, max); };
}

std::function<std::string(const std::string&)> numberCheck(const Bounds& bounds) {
  return [bounds](const std::string& text) { return numberProblem(text, bounds); };
}

double Options::number(const std::string& name, double fallback, const Bounds& bounds) const {
  return has(name) ? parseNumber(get(name, ""), name, bounds) : fallback;
}

long long Options::integer(const std::string& name, long long fallback, long long min, long long max) const {
  return has(name) ? parseInteger(get(name, ""), name, min, max) : fallback;
}

Options::Options(int argc, char** argv, const std::set<std::string>& known, const std::set<std::string>& flags,
                 const std::string& command) {
  const std::string name = "jointcomp " + (command.empty() ? std::string(argc > 0 ? argv[0] : "") : command);
  CLI::App app("", name);
  app.set_help_flag("-h,--help", "this help");
  for (const std::string& option : known) {
    if (flags.count(option)) {
      app.add_flag_callback(
          "--" + option, [this, option] { values_[option] = "1"; }, optionHelp(option));
    } else {
      app.add_option_function<std::string>(
             "--" + option, [this, option](const std::string& value) { values_[option] = value; }, optionHelp(option))
          ->type_name("VALUE");
    }
  }
  if (argc <= 0) return;  // `jointcomp` alone: the defaults
  parseCommandLine(app, argc, argv);
}

void parseCommandLine(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::printf("%s", app.help().c_str());
    throw HelpShown();
  } catch (const CLI::ParseError& error) {
    throw UsageError(std::string(error.what()) + "\n" + app.help());
  }
}

}  // namespace jointcomp::cli
