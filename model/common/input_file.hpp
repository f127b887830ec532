// The whole of an input file the user named, within a size the caller states, checked before it is read:
// `--urdf /dev/zero` or `--campaign /dev/zero` must be refused at once, not after gigabytes.
#pragma once

#include <cstdint>
#include <string>

namespace jointcomp {

// The file's bytes. A folder, a device (/dev/zero, /dev/random, a disk) or a socket is refused before a
// byte is read; a regular file larger than `max_bytes` is refused from its size; a pipe is read up to
// `max_bytes` and no further. Throws Error naming the path, `what` ("URDF", "measurement file") and the
// reason.
std::string readInputFile(const std::string& path, const char* what, std::uintmax_t max_bytes);

}  // namespace jointcomp
