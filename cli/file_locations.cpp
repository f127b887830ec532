#include "cli/file_locations.hpp"

#include <climits>
#include <cstdlib>

#include <sys/stat.h>
#include <unistd.h>

namespace jointcomp::cli {
namespace {

bool isRegularFile(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode);
}

// The folder of the running executable ("" when the kernel does not say).
std::string executableFolder() {
  char buffer[PATH_MAX];
  const ssize_t length = ::readlink("/proc/self/exe", buffer, sizeof buffer - 1);
  if (length <= 0) return "";
  const std::string path(buffer, static_cast<size_t>(length));
  const size_t slash = path.rfind('/');
  return slash == std::string::npos ? "" : path.substr(0, slash);
}

FileLocations locate() {
  // JOINTCOMP_DATA_FROM_BINDIR is the installed data folder relative to the installed binary's folder
  // (GNUInstallDirs: ../share/jointcomp); a file every installation carries tells the two layouts apart.
  const std::string folder = executableFolder();
  if (!folder.empty()) {
    const std::string candidate = folder + "/" + JOINTCOMP_DATA_FROM_BINDIR;
    if (isRegularFile(candidate + "/robots/rx170.urdf") && isRegularFile(candidate + "/plots/atomic_png.py")) {
      char resolved[PATH_MAX];
      const std::string installed = ::realpath(candidate.c_str(), resolved) ? std::string(resolved) : candidate;
      return FileLocations{installed, installed + "/plots", installed + "/fmu", true};
    }
  }
  return FileLocations{JOINTCOMP_DATA_DIR, std::string(JOINTCOMP_SOURCE_DIR) + "/cli/plots", JOINTCOMP_FMU_DIR, false};
}

}  // namespace

const FileLocations& fileLocations() {
  static const FileLocations locations = locate();
  return locations;
}

std::string robotFile(const std::string& name) { return fileLocations().data + "/robots/" + name + ".urdf"; }
std::string parameterFile(const std::string& name) { return fileLocations().data + "/params/" + name + ".json"; }

FmuParts fmuParts(int fmi_version) {
  const FileLocations& files = fileLocations();
  FmuParts parts;
  parts.platform = fmi_version == 2 ? "linux64" : "x86_64-linux";
  parts.binary = files.fmus + "/binaries/" + parts.platform + "/jointcomp.so";
  if (files.installed) {
    parts.documentation = files.fmus + "/documentation/index.html";
    parts.license = files.fmus + "/documentation/licenses/LICENSE.txt";
  } else {
    parts.documentation = std::string(JOINTCOMP_SOURCE_DIR) + "/fmu/documentation/index.html";
    parts.license = std::string(JOINTCOMP_SOURCE_DIR) + "/LICENSE";
  }
  return parts;
}

}  // namespace jointcomp::cli
