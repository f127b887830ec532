// The subcommands of the jointcomp tool; each takes argv after the command name.
#pragma once

#include <string>

namespace jointcomp::cli {

int runKinematics(int argc, char** argv);
int runPaper(int argc, char** argv);
int runImportIpa(int argc, char** argv);
int runImportCsv(int argc, char** argv);
int runCalibrate(int argc, char** argv);
int runSimulate(int argc, char** argv);
int runIdentify(int argc, char** argv);
int runDiscover(int argc, char** argv);
// cli/export_fmu_command.cpp: an FMU of any robot
int runExportFmu(int argc, char** argv);
// The export-fmu command line that packs the robot of `urdf` with `parameters` into `fmu`, for calibrate and
// discover to print; with a note when the parameters have no drives and jointcomp ships none for the robot.
std::string exportFmuCommand(const std::string& urdf, const std::string& parameters, bool has_drives,
                             const std::string& robot_name, const std::string& fmu);
// cli/distributed_commands.cpp: run jointcomp.distributed (Python, Dask)
int runMonteCarlo(int argc, char** argv);
int runFleet(int argc, char** argv);

}  // namespace jointcomp::cli
