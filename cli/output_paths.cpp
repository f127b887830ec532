#include "cli/output_paths.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <system_error>
#include <vector>

#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

namespace jointcomp::cli {
namespace {

namespace fs = std::filesystem;

// The folders this run made for its outputs, deepest first: a refused run removes those it left empty.
// (The command-line tool is one run per process; the library keeps no such state.)
std::vector<fs::path>& createdFolders() {
  static std::vector<fs::path> folders;
  return folders;
}

// Why `folder` cannot take our files, or "" when it can (made if it did not exist).
std::string folderProblem(const std::string& folder) {
  std::error_code error;
  const fs::file_status status = fs::status(folder, error);
  if (fs::exists(status) && !fs::is_directory(status)) return "'" + folder + "' exists and is not a folder";
  if (!fs::exists(status)) {
    std::vector<fs::path> missing;  // deepest first
    for (fs::path p = fs::absolute(folder, error); !p.empty() && !fs::exists(p, error); p = p.parent_path()) {
      missing.push_back(p);
      if (p == p.parent_path()) break;
    }
    fs::create_directories(folder, error);
    if (!error) createdFolders().insert(createdFolders().end(), missing.begin(), missing.end());
    if (error) return "'" + folder + "' cannot be created (" + error.message() + ")";
  }
  // access(W_OK) is not enough: a read-only file system only shows when a file is made. An unnamed file
  // (O_TMPFILE) is never visible, even if we are killed here; file systems without it get a named one.
  int fd = ::open(folder.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0600);
  if (fd < 0 && (errno == EOPNOTSUPP || errno == EISDIR || errno == EINVAL)) {
    std::string probe = (fs::path(folder) / ".jointcomp-write-check-XXXXXX").string();
    fd = ::mkstemp(probe.data());
    if (fd >= 0) ::unlink(probe.c_str());
  }
  if (fd < 0) return "'" + folder + "' is not writable (" + std::strerror(errno) + ")";
  ::close(fd);
  return "";
}

}  // namespace

void prepareOutputFolder(const std::string& folder, const std::string& option) {
  if (folder.empty()) throw std::invalid_argument(option + ": the path is empty");
  const std::string problem = folderProblem(folder);
  if (!problem.empty()) throw std::invalid_argument(option + ": " + problem);
}

void removeCreatedEmptyFolders() {
  for (const fs::path& folder : createdFolders()) {
    std::error_code error;
    if (fs::is_directory(folder, error) && fs::is_empty(folder, error)) fs::remove(folder, error);
  }
  createdFolders().clear();
}

std::string plainFileName(const std::string& text, const std::string& fallback) {
  std::string name;
  for (const char c : text) {
    const bool plain =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
    if (name.empty() && c == '.') continue;  // no leading dot
    name += plain ? c : '_';
    if (name.size() == kMaxPlainNameLength) break;
  }
  return name.empty() ? fallback : name;
}

void prepareOutputFile(const std::string& file, const std::string& option) {
  if (file.empty()) throw std::invalid_argument(option + ": the path is empty");
  std::error_code error;
  if (fs::is_directory(file, error)) throw std::invalid_argument(option + ": '" + file + "' is a folder, not a file");
  const fs::path parent = fs::path(file).parent_path();
  const std::string problem = folderProblem(parent.empty() ? std::string(".") : parent.string());
  if (!problem.empty()) throw std::invalid_argument(option + ": cannot write '" + file + "': " + problem);
}

}  // namespace jointcomp::cli
