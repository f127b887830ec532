#include "cli/plot.hpp"

#include "cli/file_locations.hpp"

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <vector>

#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace jointcomp::cli {
namespace {

constexpr const char* kPython = "/usr/bin/python3";  // Debian's, with python3-matplotlib

// Exit status of the child, or a text saying why there is none.
bool runChild(const std::vector<std::string>& arguments, std::string& why) {
  std::vector<char*> argv;
  for (const std::string& a : arguments) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t parent = getpid();
  const pid_t child = fork();
  if (child < 0) {
    why = std::string("cannot start ") + kPython + ": " + std::strerror(errno);
    return false;
  }
  if (child == 0) {
    // Dies with the parent; if the parent is already gone, do not start.
    if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != parent) _exit(127);
    execv(kPython, argv.data());
    _exit(127);
  }
  int status = 0;
  while (waitpid(child, &status, 0) < 0) {
    if (errno != EINTR) {
      why = std::string("lost the plot process: ") + std::strerror(errno);
      return false;
    }
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return true;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127) {
    why = std::string(kPython) + " could not be run (needs Debian's python3 and python3-matplotlib)";
  } else if (WIFEXITED(status)) {
    why = arguments[1] + " exited with status " + std::to_string(WEXITSTATUS(status)) + " (its message is above)";
  } else {
    why = arguments[1] + " was killed by signal " + std::to_string(WTERMSIG(status));
  }
  return false;
}

}  // namespace

bool drawPlot(const std::string& script, const std::string& input, const std::string& output, const std::string& note) {
  std::fflush(stdout);  // the child's output follows ours
  const std::string path = fileLocations().plots + "/" + script;
  std::string why;
  struct stat written {};
  if (!runChild({kPython, path, input, output}, why)) {
    std::printf("no plot: %s\n", why.c_str());
    return false;
  }
  if (::stat(output.c_str(), &written) != 0 || !S_ISREG(written.st_mode)) {
    std::printf("no plot: %s exited 0 but %s is not there\n", script.c_str(), output.c_str());
    return false;
  }
  std::printf("wrote %s%s\n", output.c_str(), note.c_str());
  return true;
}

}  // namespace jointcomp::cli
