// Where the command-line tool finds the files it ships with (robots, parameter files, plot scripts, FMUs):
// installed, they sit in <prefix>/share/jointcomp beside <prefix>/bin/jointcomp, and the tool finds them
// from its own place, so the prefix may be anything (cmake --install --prefix, an unpacked .deb); run
// from its build folder, it uses the source and build trees it was built from.
#pragma once

#include <string>

namespace jointcomp::cli {

struct FileLocations {
  std::string data;   // robots/ and params/
  std::string plots;  // the plot scripts
  std::string fmus;   // jointcomp_fmi2.fmu and jointcomp_fmi3.fmu
  bool installed = false;
};

const FileLocations& fileLocations();

// <data>/robots/<name>.urdf and <data>/params/<name>.json
std::string robotFile(const std::string& name);
std::string parameterFile(const std::string& name);

// What `export-fmu` packs besides the robot, for FMI 2 or 3: the FMU binary that serves every robot and
// the documentation. Installed: <prefix>/share/jointcomp/fmu/binaries/<platform>/jointcomp.so and
// .../fmu/documentation/; in the build tree, the binary CMake builds (<build>/fmu/binaries/<platform>/) and
// the source tree's documentation and LICENSE. The paths are where they should be; the caller checks.
struct FmuParts {
  std::string platform;       // the binaries/ folder: linux64 (FMI 2), x86_64-linux (FMI 3)
  std::string binary;         // jointcomp.so
  std::string documentation;  // index.html
  std::string license;        // the project's LICENSE
};
FmuParts fmuParts(int fmi_version);

}  // namespace jointcomp::cli
