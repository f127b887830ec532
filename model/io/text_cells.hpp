// The cells of a line of delimited text, as every reader of tabular files here splits them: each cell
// trimmed of `blanks`, a trailing separator giving a last empty cell. One place, so that the campaign
// reader and the importers agree on what a cell is.
#pragma once

#include <sstream>
#include <string>
#include <vector>

namespace jointcomp {

inline std::string trimmed(const std::string& text, const char* blanks = " \t\r\n") {
  const auto first = text.find_first_not_of(blanks);
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(blanks) - first + 1);
}

inline std::vector<std::string> splitCells(const std::string& line, char separator, const char* blanks = " \t\r\n") {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream stream(line);
  while (std::getline(stream, cell, separator)) cells.push_back(trimmed(cell, blanks));
  if (!line.empty() && line.back() == separator) cells.emplace_back();
  return cells;
}

}  // namespace jointcomp
