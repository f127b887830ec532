#include "model/io/atomic_file.hpp"

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fcntl.h>
#include <unistd.h>

#include "model/common/errors.hpp"
#include "model/common/input_file.hpp"

namespace jointcomp {
namespace {

// Closes the descriptor it owns.
class FileDescriptor {
public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }
  // Closes now, reporting the error a deferred write may only report here.
  bool close() {
    const int fd = fd_;
    fd_ = -1;
    return ::close(fd) == 0;
  }

private:
  int fd_;
};

std::string reason() { return std::strerror(errno); }

std::string folderOf(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

// A name beside the target, unique per process and call (two threads may write the same path).
std::string temporaryNameFor(const std::string& path) {
  static std::atomic<unsigned long> counter{0};
  return path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
}

void writeAll(int fd, const std::string& contents, const std::string& path) {
  const char* next = contents.data();
  std::size_t left = contents.size();
  while (left > 0) {
    const ssize_t written = ::write(fd, next, left);
    if (written < 0) {
      if (errno == EINTR) continue;
      throw Error(path + ": cannot write the file (" + reason() + ")");
    }
    next += written;
    left -= static_cast<std::size_t>(written);
  }
  // On the disk before the rename publishes it, so that a crash of the machine cannot leave the new name
  // on an empty file.
  if (::fsync(fd) != 0) throw Error(path + ": cannot write the file (" + reason() + ")");
}

// What the preferred way achieved.
enum class Unnamed { Published, AtTemporary, NotSupported };

// The preferred way: an unnamed file in the target's folder (O_TMPFILE), given a name only once it is
// complete, so that a process killed while writing leaves nothing behind. A new file is linked under its
// own name at once; an existing one is replaced by a rename from the temporary name. NotSupported when
// the file system cannot do it (then nothing was created).
Unnamed writeUnnamedThenLink(const std::string& path, const std::string& temporary, const std::string& contents) {
  FileDescriptor file(::open(folderOf(path).c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666));
  if (file.get() < 0) return Unnamed::NotSupported;
  writeAll(file.get(), contents, path);
  const std::string by_descriptor = "/proc/self/fd/" + std::to_string(file.get());
  if (::linkat(AT_FDCWD, by_descriptor.c_str(), AT_FDCWD, path.c_str(), AT_SYMLINK_FOLLOW) == 0) {
    return Unnamed::Published;
  }
  if (errno != EEXIST) return Unnamed::NotSupported;
  return ::linkat(AT_FDCWD, by_descriptor.c_str(), AT_FDCWD, temporary.c_str(), AT_SYMLINK_FOLLOW) == 0
             ? Unnamed::AtTemporary
             : Unnamed::NotSupported;
}

// Elsewhere: a named temporary, removed when the write fails.
void writeNamed(const std::string& path, const std::string& temporary, const std::string& contents) {
  FileDescriptor file(::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666));
  if (file.get() < 0) throw Error(path + ": cannot create the file (" + reason() + ")");
  try {
    writeAll(file.get(), contents, path);
    if (!file.close()) throw Error(path + ": cannot write the file (" + reason() + ")");
  } catch (const Error&) {
    ::unlink(temporary.c_str());
    throw;
  }
}

// The new name reaches the disk with its folder (best effort: some file systems refuse it).
void syncFolderOf(const std::string& path) {
  FileDescriptor folder(::open(folderOf(path).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (folder.get() >= 0) (void)::fsync(folder.get());
}

}  // namespace

void writeFileAtomically(const std::string& path, const std::string& contents) {
  const std::string temporary = temporaryNameFor(path);
  switch (writeUnnamedThenLink(path, temporary, contents)) {
    case Unnamed::Published: syncFolderOf(path); return;
    case Unnamed::AtTemporary: break;
    case Unnamed::NotSupported: writeNamed(path, temporary, contents); break;
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0) {
    const std::string why = reason();
    ::unlink(temporary.c_str());
    throw Error(path + ": cannot replace the file (" + why + ")");
  }
  syncFolderOf(path);
}

std::string readTextFile(const std::string& path, const char* what, std::uintmax_t max_bytes) {
  return readInputFile(path, what, max_bytes);
}

}  // namespace jointcomp
