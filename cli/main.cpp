// jointcomp: the command-line tool. With no arguments it runs the main job on the built-in RX170.
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "cli/commands.hpp"

namespace {

void printUsage() {
  std::printf(
      "usage: jointcomp [command] [options]\n"
      "commands:\n"
      "  paper [--urdf FILE] [--params FILE] [--out DIR] [--seed N] [--compensate-joints 2,3] [--quasi-static]\n"
      "        [--no-plot]\n"
      "                             the paper's spiral test on a simulated robot: Table II analogue\n"
      "  kinematics [--urdf FILE]   forward kinematics and gravity torques at a few poses\n"
      "  import-ipa --in FILE --out FILE [--trafo FILE]\n"
      "                             convert IPA UR10 laser-tracker files into a measurement campaign\n"
      "  help                       this text\n"
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
    if (command == "paper") return jointcomp::cli::runPaper(argc > 1 ? argc - 1 : 0, argv + 1);
    if (command == "import-ipa") return jointcomp::cli::runImportIpa(argc - 1, argv + 1);
    if (command == "kinematics") return jointcomp::cli::runKinematics(argc - 1, argv + 1);
    std::fprintf(stderr, "jointcomp: unknown command '%s'\n", command.c_str());
    printUsage();
    return 2;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "jointcomp %s: %s\n", command.c_str(), error.what());
    return 1;
  }
}
