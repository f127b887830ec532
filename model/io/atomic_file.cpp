#include "model/io/atomic_file.hpp"

#include <cstdio>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include "model/common/errors.hpp"

namespace jointcomp {

void writeFileAtomically(const std::string& path, const std::string& contents) {
  const std::string temporary = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream file(temporary, std::ios::binary | std::ios::trunc);
    if (!file) throw Error(path + ": cannot create the file");
    file << contents;
    file.flush();
    if (!file) {
      std::remove(temporary.c_str());
      throw Error(path + ": cannot write the file");
    }
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    std::remove(temporary.c_str());
    throw Error(path + ": cannot replace the file");
  }
}

std::string readTextFile(const std::string& path, const char* what) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw Error(path + ": cannot open the " + what);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

}  // namespace jointcomp
