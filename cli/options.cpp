#include "cli/options.hpp"

#include <cstdio>
#include <map>

#include <CLI/CLI.hpp>

namespace jointcomp::cli {

const char* optionHelp(const std::string& name) {
  static const std::map<std::string, const char*> help = {
      {"urdf", "the robot's URDF"},
      {"base-link", "first link of the chain (default: the URDF's root)"},
      {"tip-link", "last link of the chain (default: the end of the longest moving chain, e.g. tool0)"},
      {"params", "parameter file (joint-error effects, gears, drives)"},
      {"truth", "parameter file of the simulated robot as it really is"},
      {"out", "output folder (a file for simulate and the importers); checked before any work"},
      {"campaign", "measurement campaign(s) to fit (docs/measurement-campaign.md), comma-separated or repeated"},
      {"holdout", "held-out campaign(s), evaluated with only their instrument frame refitted; repeatable"},
      {"seed", "random seed"},
      {"compensate-joints", "joints whose references are compensated, e.g. 2,3 (default: all)"},
      {"no-plot", "write no plot"},
      {"quiet", "print no progress lines"},
      {"quasi-static", "simulate the quasi-static robot instead of the flexible-joint plant"},
      {"feed-rate",
       "tool speed along the path in m/s (default: the paper's 0.03); acceleration and jerk limits scale with it"},
      {"no-dynamic-correction",
       "only the paper's three runs (by default the plant's run has a fourth: stiffness, kinematic and dynamic "
       "correction)"},
      {"loss", "robust loss of the fit: huber, cauchy or none"},
      {"loss-scale-mm", "scale of the robust loss in mm (default: from the least-squares residuals)"},
      {"pivot-threshold", "relative pivot below which a parameter counts as not identifiable"},
      {"fix", "calibration parameters held at nominal, comma-separated names"},
      {"base", "discovery's base model: frame or textbook"},
      {"max-steps", "most effects discovery adds"},
      {"orders", "highest harmonic order offered by default"},
      {"folds", "time blocks of the cross-validation"},
      {"types", "candidate effect types to try, comma-separated (default: all)"},
      {"noise-floor-mm", "instrument noise floor in mm (3-D RMS), where discovery may stop"},
      {"min-cv-gain", "smallest relative cross-validation gain a candidate needs"},
      {"joint", "joint number (1-based)"},
      {"stage", "gear stage"},
      {"use", "stiffness identification: local or global"},
      {"protocol", "stiffness, joint2-sweep, spiral, random or back-and-forth"},
      {"perturb", "perturb the truth with this seed and write it beside the campaign"},
      {"plant", "measure on the flexible-joint plant"},
      {"target", "target on the flange x,y,z in mm"},
      {"from", "sweep start in deg"},
      {"to", "sweep end in deg"},
      {"step", "sweep step in deg"},
      {"settle", "settling time per pose in s"},
      {"cycles", "number of back-and-forth cycles"},
      {"count", "number of random poses"},
      {"pose", "joint angles in deg, comma-separated"},
      {"no-noise", "simulate perfect instruments"},
      {"global-poses", "poses of the global stiffness protocol"},
      {"warm-up", "thermal warm-up RISE_DEGC[,TAU_S[,START_DEGC]]"},
      {"in", "the file to import"},
      {"trafo", "the IPA tracker-to-base transform file"},
      {"columns", "campaign column = export column, comma-separated (t=Time,q1=A1,...)"},
      {"angles", "the export's angle unit: deg or rad"},
      {"lengths", "the export's length unit: mm or m"},
      {"separator", "the export's cell separator: , ; | or tab (default: detected)"},
      {"decimal", "the export's decimal mark: . or , (default: detected)"},
      {"robot", "the robot's name in the campaign's metadata"},
      {"frame", "the export's frame: base or instrument"},
  };
  const auto found = help.find(name);
  return found == help.end() ? "" : found->second;
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
