// What a long computation is doing, told to whoever shows it (the CLI's console lines, a C API or Python
// callback): "calibrating: iteration 4, RMS 0.4213 mm". Empty: silent. Called on the working thread.
#pragma once

#include <functional>
#include <string>

namespace jointcomp {

using Progress = std::function<void(const std::string&)>;

inline void report(const Progress& progress, const std::string& what) {
  if (progress) progress(what);
}

}  // namespace jointcomp
