// Files written whole or not at all: the text goes to a temporary file beside the target, is synced to
// the disk, then renamed over the target. The temporary is unnamed while it is written (O_TMPFILE) where
// the file system allows, so that a process killed part-way leaves neither a partial file nor a temporary.
#pragma once

#include <string>

namespace jointcomp {

// Throws Error naming the path when the file cannot be written.
void writeFileAtomically(const std::string& path, const std::string& contents);
std::string readTextFile(const std::string& path, const char* what);

}  // namespace jointcomp
