// Plots are drawn by Python scripts (cli/plots) run with Debian's interpreter from an argument vector: no
// shell, so any path (quotes, semicolons, spaces, newlines) is just a path. The child dies with its parent
// (a killed jointcomp leaves no process behind that writes later), and a plot counts as written only when
// the script exited 0 and the file is there.
#pragma once

#include <string>

namespace jointcomp::cli {

// Runs /usr/bin/python3 <cli/plots/SCRIPT> INPUT OUTPUT and prints what happened: "wrote OUTPUT<note>" or
// "no plot: <why>". Returns true when the plot was written.
bool drawPlot(const std::string& script, const std::string& input, const std::string& output,
              const std::string& note = "");

}  // namespace jointcomp::cli
