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

}  // namespace jointcomp::cli
