// Runs a program from an argument vector (no shell), its standard output and error captured together,
// killed when it outlives its time: for the tests that check a file with an independent reader
// (/usr/bin/python3's zipfile, xmllint, unzip) or run the command-line tool as a user would.
#pragma once

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <string>
#include <vector>

#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

namespace jointcomp::test {

struct ChildResult {
  int exit_code = -1;  // -1: it did not exit (killed, not started); `why` says which
  std::string output;  // standard output and error, interleaved
  std::string why;
};

// argv[0] is the program's path. Nothing is read from standard input (it is /dev/null).
inline ChildResult runChild(const std::vector<std::string>& argv, double timeout_s = 300.0) {
  ChildResult result;
  std::vector<char*> pointers;
  for (const std::string& a : argv) pointers.push_back(const_cast<char*>(a.c_str()));
  pointers.push_back(nullptr);
  int pipe_fds[2];
  if (argv.empty() || ::pipe(pipe_fds) != 0) {
    result.why = "cannot start: no program or no pipe";
    return result;
  }
  const pid_t child = ::fork();
  if (child < 0) {
    result.why = std::string("cannot fork: ") + std::strerror(errno);
    ::close(pipe_fds[0]);
    ::close(pipe_fds[1]);
    return result;
  }
  if (child == 0) {
    ::dup2(pipe_fds[1], STDOUT_FILENO);
    ::dup2(pipe_fds[1], STDERR_FILENO);
    ::close(pipe_fds[0]);
    ::close(pipe_fds[1]);
    ::close(STDIN_FILENO);
    ::execv(pointers[0], pointers.data());
    _exit(127);
  }
  ::close(pipe_fds[1]);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  bool timed_out = false;
  char buffer[4096];
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      timed_out = true;
      break;
    }
    pollfd poll_fd{pipe_fds[0], POLLIN, 0};
    const int ready = ::poll(&poll_fd, 1, static_cast<int>(left.count()));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;  // the deadline is checked above
    const ssize_t got = ::read(pipe_fds[0], buffer, sizeof buffer);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) break;  // end of output: the child closed it (it exits)
    result.output.append(buffer, static_cast<std::size_t>(got));
  }
  ::close(pipe_fds[0]);
  if (timed_out) ::kill(child, SIGKILL);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {}
  if (timed_out) {
    result.why = argv[0] + " did not finish within " + std::to_string(timeout_s) + " s and was killed";
  } else if (WIFEXITED(status)) {
    result.exit_code = WEXITSTATUS(status);
    if (result.exit_code == 127) result.why = argv[0] + " could not be run (exit 127)";
  } else if (WIFSIGNALED(status)) {
    result.why = argv[0] + " was killed by signal " + std::to_string(WTERMSIG(status));
  }
  return result;
}

}  // namespace jointcomp::test
