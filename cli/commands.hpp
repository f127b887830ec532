// The subcommands of the jointcomp tool; each takes argv after the command name.
#pragma once

namespace jointcomp::cli {

int runKinematics(int argc, char** argv);
int runPaper(int argc, char** argv);
int runImportIpa(int argc, char** argv);
int runImportCsv(int argc, char** argv);
int runCalibrate(int argc, char** argv);
int runSimulate(int argc, char** argv);
int runIdentify(int argc, char** argv);
int runDiscover(int argc, char** argv);
// cli/distributed_commands.cpp: run jointcomp.distributed (Python, Dask)
int runMonteCarlo(int argc, char** argv);
int runFleet(int argc, char** argv);

}  // namespace jointcomp::cli
