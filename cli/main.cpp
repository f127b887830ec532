// jointcomp: the command-line tool. With no arguments it runs the main job on the built-in RX170.
#include <cstdio>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "cli/file_locations.hpp"
#include "cli/options.hpp"
#include "cli/output_paths.hpp"
#include "model/effects/registry.hpp"

namespace {

// The discovery types, as the effect registry names them, wrapped under the command's description.
void printDiscoveryTypes() {
  const char* indent = "                             ";
  std::string line = std::string(indent) + "types:";
  const std::vector<std::string> types = jointcomp::EffectRegistry::builtin().discoveryVocabulary();
  for (std::size_t i = 0; i < types.size(); ++i) {
    const std::string word = " " + types[i] + (i + 1 < types.size() ? "," : "");
    if (line.size() + word.size() > 110) {
      std::printf("%s\n", line.c_str());
      line = std::string(indent) + "      ";  // under the first type
    }
    line += word;
  }
  std::printf("%s\n", line.c_str());
}

void printUsage() {
  std::printf(
      "usage: jointcomp [command] [options]\n"
      "commands:\n"
      "  paper [--urdf FILE] [--params FILE] [--out DIR] [--seed N] [--compensate-joints 2,3] [--quasi-static]\n"
      "        [--feed-rate M_PER_S] [--no-dynamic-correction] [--no-plot]\n"
      "                             the paper's spiral test on a simulated robot: Table II analogue, and a\n"
      "                             fourth run with the dynamic correction\n"
      "  kinematics [--urdf FILE]   forward kinematics and gravity torques at a few poses\n"
      "  import-ipa --in FILE --out FILE [--trafo FILE]\n"
      "                             convert IPA UR10 laser-tracker files into a measurement campaign\n"
      "  import-csv --in EXPORT.csv --out CAMPAIGN.csv [--columns t=NAME,q1=NAME,..,x=NAME,y=NAME,z=NAME]\n"
      "        [--angles deg|rad] [--lengths mm|m] [--separator ,|;|tab] [--decimal .|,] [--robot NAME]\n"
      "        [--frame base|instrument]\n"
      "                             your own tracker export as a campaign (docs/measurement-campaign.md):\n"
      "                             separator and decimal mark detected, metadata lines before the header skipped\n"
      "  simulate --protocol stiffness|joint2-sweep|spiral|random|back-and-forth --truth PARAMS.json\n"
      "        [--urdf FILE] [--seed N] [--out FILE] [--perturb SEED] [--plant] [--no-noise] [--target x,y,z]\n"
      "        [--pose q1,..] [--joint N] [--from DEG] [--to DEG] [--step DEG] [--settle S] [--cycles N] [--count N]\n"
      "        [--warm-up RISE_DEGC[,TAU_S[,START_DEGC]]]\n"
      "                             a measurement campaign of a simulated robot with simulated instruments\n"
      "                             (--warm-up: temperatures rising to START + RISE with time constant TAU)\n"
      "  identify stiffness|transmission --campaign FILE --out DIR [--urdf FILE] [--params NOMINAL.json]\n"
      "        [--joint 2] [--stage 2] [--orders 1,2,..] [--use local|global] [--truth PARAMS.json] [--no-plot]\n"
      "                             joint stiffness or transmission-error harmonics from a campaign\n"
      "  calibrate --campaign FILE[,FILE] --out DIR [--urdf FILE] [--params FILE] [--holdout FILE ...]\n"
      "        [--loss huber|cauchy|none] [--loss-scale-mm X] [--pivot-threshold X] [--fix NAME,..] [--no-plot]\n"
      "        [--target x,y,z (mm)] [--base-frame x,y,z,rx,ry,rz (mm, deg: the base in the instrument's frame)]\n"
      "                             --fix target, --fix base (or frame): keep them as given\n"
      "                             kinematic calibration (instrument frame, target, joint offsets, placements,\n"
      "                             compliance) from measured positions; campaigns from several instrument\n"
      "                             set-ups are fitted together, one frame each; held-out campaigns re-fit theirs\n"
      "  discover --campaign FILE[,FILE] --out DIR [--urdf FILE] [--params FILE] [--holdout FILE ...]\n"
      "        [--base textbook|frame] [--max-steps N] [--orders N] [--folds K] [--types offset,harmonic,..]\n"
      "        [--noise-floor-mm X] [--min-cv-gain X] [--loss huber|cauchy|none] [--table-knots N,..]\n"
      "        [--max-prior-weight X] [--max-ridge-weight X] [--transfer-significance X] [--no-pairs] [--no-plot]\n"
      "        [--target x,y,z] [--base-frame x,y,z,rx,ry,rz] [--fix target|base]: as calibrate\n"
      "                             residual discovery: from the textbook calibration, adds the candidate\n"
      "                             effects the data ask for, one (or a pair) at a time (time-blocked CV + BIC,\n"
      "                             a transfer check), and writes the extended parameter file;\n");
  printDiscoveryTypes();
  std::printf(
      "  export-fmu --urdf FILE --params FILE --out ROBOT.fmu [--fmi 2|3] [--drives PARAMS.json]\n"
      "        [--base-link L] [--tip-link L] [--rigid-stiffness N_M_PER_RAD]\n"
      "                             an FMI 2.0 (default) or 3.0 co-simulation FMU of the robot: its flexible-joint\n"
      "                             plant with the compensation in front, every effect of the parameter file;\n"
      "                             --drives: a file whose \"plant\" object gives the drives if --params has none;\n"
      "                             a joint the file calls rigid gets --rigid-stiffness (default 10x the stiffest)\n"
      "  montecarlo [--urdf FILE] [--params FILE] [--report REPORT.json | --distribution FILE] [--samples N]\n"
      "        [--seed N] [--plant] [--out DIR] [--scheduler tcp://HOST:8786] [--workers N] [--timeout S]\n"
      "                             the spiral's accuracy under parameter uncertainty (percentiles, 95 %% bounds,\n"
      "                             error band along the path), on a Dask cluster (Python: jointcomp.distributed)\n"
      "  fleet --campaign FILE [FILE ..] [--urdf FILE] [--params FILE] [--method calibrate|discover] [--out DIR]\n"
      "        [--scheduler tcp://HOST:8786] [--workers N] [--timeout S]\n"
      "                             calibrate many robots, one campaign each, on a Dask cluster: a report per\n"
      "                             robot and a fleet summary with outliers flagged\n"
      "  help                       this text; jointcomp <command> --help lists a command's options\n"
      "  --version                  the version, and where the robots, parameter files and plot scripts are\n"
      "Every command that reads --urdf also takes --base-link LINK and --tip-link LINK (default: the URDF's\n"
      "root, and the end of its longest moving chain, as ROS-Industrial's tool0 beside fixed side frames).\n"
      "With no command, jointcomp runs `paper` on the built-in Staubli RX170.\n");
}

}  // namespace

int main(int argc, char** argv) {
  const std::string command = argc > 1 ? argv[1] : "paper";
  try {
    if (command == "help" || command == "--help" || command == "-h") {
      printUsage();
      return 0;
    }
    if (command == "--version" || command == "version") {
      const jointcomp::cli::FileLocations& files = jointcomp::cli::fileLocations();
      std::printf("jointcomp %s\nfiles: %s (%s)\n", JOINTCOMP_VERSION, files.data.c_str(),
                  files.installed ? "installed" : "the source tree it was built from");
      return 0;
    }
    if (command == "paper") return jointcomp::cli::runPaper(argc > 1 ? argc - 1 : 0, argv + 1);
    if (command == "import-ipa") return jointcomp::cli::runImportIpa(argc - 1, argv + 1);
    if (command == "import-csv") return jointcomp::cli::runImportCsv(argc - 1, argv + 1);
    if (command == "calibrate") return jointcomp::cli::runCalibrate(argc - 1, argv + 1);
    if (command == "kinematics") return jointcomp::cli::runKinematics(argc - 1, argv + 1);
    if (command == "simulate") return jointcomp::cli::runSimulate(argc - 1, argv + 1);
    if (command == "identify") return jointcomp::cli::runIdentify(argc - 1, argv + 1);
    if (command == "discover") return jointcomp::cli::runDiscover(argc - 1, argv + 1);
    if (command == "export-fmu") return jointcomp::cli::runExportFmu(argc - 1, argv + 1);
    if (command == "montecarlo") return jointcomp::cli::runMonteCarlo(argc - 1, argv + 1);
    if (command == "fleet") return jointcomp::cli::runFleet(argc - 1, argv + 1);
    std::fprintf(stderr, "jointcomp: unknown command '%s'\n", command.c_str());
    printUsage();
    return 2;
  } catch (const jointcomp::cli::HelpShown&) {
    return 0;
  } catch (const jointcomp::cli::UsageError& error) {
    jointcomp::cli::removeCreatedEmptyFolders();
    std::fprintf(stderr, "jointcomp %s: %s\n", command.c_str(), error.what());
    return 2;
  } catch (const std::bad_alloc&) {
    jointcomp::cli::removeCreatedEmptyFolders();
    // Not "std::bad_alloc": say what it means and where to look.
    std::fprintf(stderr,
                 "jointcomp %s: out of memory: the inputs ask for more than this machine has (the limits of the "
                 "options are in jointcomp %s --help)\n",
                 command.c_str(), command.c_str());
    return 1;
  } catch (const std::exception& error) {
    jointcomp::cli::removeCreatedEmptyFolders();
    std::fprintf(stderr, "jointcomp %s: %s\n", command.c_str(), error.what());
    return 1;
  }
}
