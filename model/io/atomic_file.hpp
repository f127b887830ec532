// Files written whole or not at all: the text goes to a temporary file beside the target, then a rename.
#pragma once

#include <string>

namespace jointcomp {

// Throws Error naming the path when the file cannot be written.
void writeFileAtomically(const std::string& path, const std::string& contents);
std::string readTextFile(const std::string& path, const char* what);

}  // namespace jointcomp
