#include "model/common/input_file.hpp"

#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "model/common/errors.hpp"

namespace jointcomp {
namespace {

std::string sizeText(std::uintmax_t bytes) {
  return bytes >= (1u << 20) ? std::to_string(bytes >> 20) + " MiB" : std::to_string(bytes) + " bytes";
}

// Why a file of this kind is no input, or nullptr when it may be read.
const char* kindProblem(mode_t mode) {
  if (S_ISDIR(mode)) return "is a folder, not a file";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "is a device, not a file";
  if (S_ISSOCK(mode)) return "is a socket, not a file";
  if (S_ISREG(mode) || S_ISFIFO(mode)) return nullptr;
  return "is not a regular file";
}

}  // namespace

std::string readInputFile(const std::string& path, const char* what, std::uintmax_t max_bytes) {
  const std::string named = path + ": the " + what;
  auto tooLarge = [&]() { return Error(named + " is larger than " + sizeText(max_bytes) + "; is it the right file?"); };
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error(path + ": cannot open the " + what + " (" + std::strerror(errno) + ")");
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat info {};
  if (::fstat(fd, &info) != 0) throw Error(path + ": cannot read the " + what + " (" + std::strerror(errno) + ")");
  if (const char* problem = kindProblem(info.st_mode)) throw Error(path + " " + problem + " (the " + what + ")");
  std::string text;
  if (S_ISREG(info.st_mode)) {
    if (static_cast<std::uintmax_t>(info.st_size) > max_bytes) throw tooLarge();
    text.reserve(static_cast<std::size_t>(info.st_size));
  }
  char buffer[1 << 16];
  for (;;) {
    const ssize_t got = ::read(fd, buffer, sizeof buffer);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw Error(path + ": cannot read the " + what + " (" + std::strerror(errno) + ")");
    if (got == 0) break;
    if (text.size() + static_cast<std::size_t>(got) > max_bytes) throw tooLarge();
    text.append(buffer, static_cast<std::size_t>(got));
  }
  return text;
}

}  // namespace jointcomp
