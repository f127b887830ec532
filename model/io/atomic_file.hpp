// Files written whole or not at all: the text goes to a temporary file beside the target, is synced to
// the disk, then renamed over the target. The temporary is unnamed while it is written (O_TMPFILE) where
// the file system allows, so that a process killed part-way leaves neither a partial file nor a temporary.
#pragma once

#include <cstdint>
#include <string>

namespace jointcomp {

// Inputs have sane sizes, checked before they are read: a parameter or robot file is a few kilobytes, a
// measurement campaign of a million rows about 150 MB.
constexpr std::uintmax_t kMaxJsonFileBytes = 16u << 20;           // 16 MiB
constexpr std::uintmax_t kMaxMeasurementFileBytes = 2048u << 20;  // 2 GiB

// Throws Error naming the path when the file cannot be written.
void writeFileAtomically(const std::string& path, const std::string& contents);
// The whole file; throws Error naming the path when it cannot be read or holds more than max_bytes (a
// folder or a device is refused before it is read, a pipe is read up to the limit, never past it:
// model/common/input_file.hpp).
std::string readTextFile(const std::string& path, const char* what,
                         std::uintmax_t max_bytes = kMaxMeasurementFileBytes);

}  // namespace jointcomp
