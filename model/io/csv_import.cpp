#include "model/io/csv_import.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>
#include <vector>

#include "model/common/errors.hpp"
#include "model/common/plain_text.hpp"
#include "model/common/strict_json.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/text_cells.hpp"

namespace jointcomp {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Cells of an export: blanks and the quotes spreadsheets put around text are not part of a cell.
constexpr const char* kBlanksAndQuotes = " \t\r\n\"";

std::vector<std::string> split(const std::string& line, char separator) {
  return splitCells(line, separator, kBlanksAndQuotes);
}

std::string trim(const std::string& text) { return trimmed(text, kBlanksAndQuotes); }

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

// t, x, y, z, temp, payload, qK or qmK (K of one or two digits): the columns an export may be mapped to.
bool isCampaignColumn(const std::string& name) {
  for (const char* fixed : {"t", "x", "y", "z", "temp", "payload"}) {
    if (name == fixed) return true;
  }
  const std::size_t digits = name.rfind("qm", 0) == 0 ? 2 : name.rfind('q', 0) == 0 ? 1 : 0;
  return digits > 0 && name.size() > digits && name.size() <= digits + 2 &&
         name.find_first_not_of("0123456789", digits) == std::string::npos;
}

std::string separatorName(char separator) { return separator == '\t' ? "tab" : std::string("'") + separator + "'"; }

class CsvImporter {
public:
  CsvImporter(const std::string& source, const CsvImportOptions& options) : source_(source), options_(options) {}

  MeasurementCampaign run(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream stream(text);
    for (std::string line; std::getline(stream, line);) {
      if (lines.empty() && line.rfind("\xEF\xBB\xBF", 0) == 0) line = line.substr(3);  // UTF-8 byte-order mark
      if (!line.empty() && line.back() == '\r') line.pop_back();
      lines.push_back(line);
    }
    const std::size_t header = findHeader(lines);
    const std::vector<std::string> names = split(lines[header], separator_);
    detectDecimalMark(lines, header);
    mapColumns(names, static_cast<int>(header) + 1);

    MeasurementCampaign campaign;
    campaign.source = source_;
    campaign.robot = options_.robot;
    campaign.frame = options_.frame;
    campaign.has_target = options_.has_target;
    campaign.target_in_flange = options_.target_in_flange;
    campaign.metadata["imported_from"] = source_;
    campaign.metadata["imported_preamble_lines"] = std::to_string(header);
    campaign.metadata["separator"] = separatorName(separator_);
    campaign.metadata["decimal_mark"] = std::string(1, decimal_);
    if (time_ < 0) campaign.metadata["time_from"] = "row index (1 s per row)";
    campaign.dof = static_cast<int>(q_.size());
    campaign.has_position = x_ >= 0;
    campaign.has_measured_angles = !qm_.empty();
    const double angle = options_.angles_in_radians ? 1.0 : kPi / 180.0;
    const double length = options_.lengths_in_metres ? 1.0 : 1e-3;
    int row = 0;
    for (std::size_t l = header + 1; l < lines.size(); ++l) {
      const int line_number = static_cast<int>(l) + 1;
      if (trim(lines[l]).empty()) continue;
      const std::vector<std::string> cells = split(lines[l], separator_);
      if (cells.size() != names.size()) {
        fail(line_number, "row has " + std::to_string(cells.size()) + " cells, the header has " +
                              std::to_string(names.size()) + " (separator " + separatorName(separator_) +
                              ", decimal mark '" + std::string(1, decimal_) + "')");
      }
      const auto value = [&](int column, bool required) {
        return number(cells[static_cast<std::size_t>(column)], line_number, names[static_cast<std::size_t>(column)],
                      required);
      };
      campaign.time.push_back(time_ >= 0 ? value(time_, true) : static_cast<double>(row));
      JointVector q(campaign.dof);
      for (int j = 0; j < campaign.dof; ++j) q[j] = value(q_[static_cast<std::size_t>(j)], true) * angle;
      campaign.command.push_back(q);
      if (campaign.has_position) {
        const auto axis = [&](int column, int added) {
          return (value(column, false) + (added >= 0 ? value(added, false) : 0.0)) * length;
        };
        campaign.position.emplace_back(axis(x_, x_add_), axis(y_, y_add_), axis(z_, z_add_));
      } else {
        campaign.position.push_back(Eigen::Vector3d::Constant(kNaN));
      }
      if (campaign.has_measured_angles) {
        JointVector qm(campaign.dof);
        for (int j = 0; j < campaign.dof; ++j) qm[j] = value(qm_[static_cast<std::size_t>(j)], false) * angle;
        campaign.measured_angles.push_back(qm);
      }
      campaign.temperature.push_back(temperature_ >= 0 ? value(temperature_, false) : kNaN);
      campaign.wrench.push_back(Vector6::Zero());
      campaign.payload.push_back(payload_ >= 0 ? value(payload_, false) : 0.0);
      ++row;
    }
    if (row == 0) fail(static_cast<int>(lines.size()), "no data rows after the header");
    // The campaign's own rules (time order, measured positions or angles), in the campaign's words.
    try {
      campaign.validate();
    } catch (const MeasurementError& error) {
      throw MeasurementError(source_ + ": " + error.what());
    }
    return campaign;
  }

private:
  [[noreturn]] void fail(int line, const std::string& what) const {
    throw MeasurementError(source_ + ":" + std::to_string(line) + ": " + what);
  }

  // The header is the first line that, split by the separator, has at least two cells like the line after
  // it; lines before it are the export's metadata. ';' and tabs are tried before ',' (a ';' file's
  // numbers may hold decimal commas).
  std::size_t findHeader(const std::vector<std::string>& lines) {
    const std::vector<char> candidates =
        options_.separator ? std::vector<char>{options_.separator} : std::vector<char>{';', '\t', ','};
    for (std::size_t l = 0; l + 1 < lines.size() && l < 1000; ++l) {
      if (trim(lines[l]).empty()) continue;
      for (char separator : candidates) {
        const std::size_t cells = split(lines[l], separator).size();
        std::size_t next = l + 1;
        while (next < lines.size() && trim(lines[next]).empty()) ++next;
        if (cells >= 2 && next < lines.size() && split(lines[next], separator).size() == cells &&
            lines[l].find(separator) != std::string::npos) {
          separator_ = separator;
          return l;
        }
      }
    }
    fail(1, "no header row followed by data rows with the same number of cells (tried separators " +
                std::string(options_.separator ? separatorName(options_.separator) : "';', tab and ','") + ")");
  }

  void detectDecimalMark(const std::vector<std::string>& lines, std::size_t header) {
    if (options_.decimal_mark) {
      decimal_ = options_.decimal_mark;
    } else {
      decimal_ = '.';
      if (separator_ != ',') {
        for (std::size_t l = header + 1; l < lines.size() && l < header + 50; ++l) {
          for (const std::string& cell : split(lines[l], separator_)) {
            const auto comma = cell.find(',');
            if (comma != std::string::npos && comma > 0 && std::isdigit(static_cast<unsigned char>(cell[comma - 1])) &&
                comma + 1 < cell.size() && std::isdigit(static_cast<unsigned char>(cell[comma + 1]))) {
              decimal_ = ',';
            }
          }
        }
      }
    }
    if (decimal_ == separator_) {
      fail(static_cast<int>(header) + 1, "the decimal mark and the separator are both " + separatorName(separator_));
    }
  }

  // The header column named `wanted` (exactly, else ignoring case), -1 when none; two columns of that name
  // are refused (which one the user meant is not known).
  int headerColumn(const std::vector<std::string>& names, const std::string& wanted, int line) const {
    for (const bool exact : {true, false}) {
      std::vector<int> found;
      for (std::size_t c = 0; c < names.size(); ++c) {
        if (exact ? names[c] == wanted : lower(names[c]) == lower(wanted)) found.push_back(static_cast<int>(c));
      }
      if (found.size() > 1) {
        fail(line, "the header has " + std::to_string(found.size()) + " columns named '" + shortExcerpt(wanted) +
                       "' (columns " + std::to_string(found[0] + 1) + " and " + std::to_string(found[1] + 1) +
                       "): rename one so that it is clear which is meant");
      }
      if (found.size() == 1) return found[0];
    }
    return -1;
  }

  std::string headerList(const std::vector<std::string>& names) const {
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + shortExcerpt(n);
    return list;
  }

  // The columns of campaign column `name` (one, or the two of a derived "A+B"), empty when absent (an error
  // when it was mapped). Joint K is also found as joint_K or jointK when not mapped.
  std::vector<int> columnsOf(const std::vector<std::string>& names, const std::string& name, int line) const {
    const auto mapped = options_.columns.find(name);
    const std::string wanted = mapped != options_.columns.end() ? mapped->second : name;
    if (const int column = headerColumn(names, wanted, line); column >= 0) return {column};
    if (mapped == options_.columns.end()) {
      if (name.size() > 1 && name[0] == 'q' && std::isdigit(static_cast<unsigned char>(name[1]))) {
        for (const std::string& alias : {"joint_" + name.substr(1), "joint" + name.substr(1)}) {
          if (const int column = headerColumn(names, alias, line); column >= 0) return {column};
        }
      }
      return {};
    }
    const auto plus = wanted.find('+');
    if (plus != std::string::npos && (name == "x" || name == "y" || name == "z")) {
      const int first = headerColumn(names, trim(wanted.substr(0, plus)), line);
      const int second = headerColumn(names, trim(wanted.substr(plus + 1)), line);
      if (first >= 0 && second >= 0) return {first, second};
    }
    fail(line, "column '" + shortExcerpt(wanted) + "' (mapped to " + name + ") is not in the header (" +
                   headerList(names) + ")" +
                   (plus != std::string::npos ? "; a derived column is NAME+NAME of two header columns" : ""));
  }

  int columnOf(const std::vector<std::string>& names, const std::string& name, int line) {
    const std::vector<int> columns = columnsOf(names, name, line);
    if (columns.size() > 1) fail(line, "--columns: only x, y and z may be the sum of two columns, not " + name);
    if (!columns.empty()) used_.emplace_back(name, columns[0]);
    return columns.empty() ? -1 : columns[0];
  }

  void mapPositions(const std::vector<std::string>& names, int line) {
    int* const axes[3] = {&x_, &y_, &z_};
    int* const added[3] = {&x_add_, &y_add_, &z_add_};
    for (int a = 0; a < 3; ++a) {
      const std::string name(1, "xyz"[a]);
      const std::vector<int> columns = columnsOf(names, name, line);
      *axes[a] = columns.empty() ? -1 : columns[0];
      *added[a] = columns.size() > 1 ? columns[1] : -1;
      for (int column : columns) used_.emplace_back(name, column);
    }
    if ((x_ >= 0) != (y_ >= 0) || (x_ >= 0) != (z_ >= 0)) fail(line, "columns x, y and z go together");
  }

  // Every mapped campaign column must be used: a qK or qmK beyond the joints found (a gap in the mapping)
  // would otherwise be dropped.
  void checkMappingUsed(int line) const {
    for (const auto& entry : options_.columns) {
      const bool used = std::any_of(used_.begin(), used_.end(), [&](const auto& u) { return u.first == entry.first; });
      if (!used) {
        fail(line, "--columns maps " + entry.first + " but the joints before it are not all mapped (found " +
                       std::to_string(q_.size()) + " joints: q1 .. q" + std::to_string(q_.size()) + ")");
      }
    }
  }

  // One header column for one campaign column: mapping it twice is a mistake in --columns.
  void checkColumnsDistinct(const std::vector<std::string>& names, int line) const {
    for (std::size_t i = 0; i < used_.size(); ++i) {
      for (std::size_t k = i + 1; k < used_.size(); ++k) {
        if (used_[i].second == used_[k].second && used_[i].first != used_[k].first) {
          fail(line, "header column '" + shortExcerpt(names[static_cast<std::size_t>(used_[i].second)]) +
                         "' is mapped to both " + used_[i].first + " and " + used_[k].first);
        }
      }
    }
  }

  // A header column that looks like one more joint (the last joint's column name with its number one
  // higher, or q/joint_ of the next number) is refused unless --joints says how many there are: a joint
  // is never dropped silently.
  void checkNoJointLeft(const std::vector<std::string>& names, int line) const {
    const int n = static_cast<int>(q_.size());
    if (options_.joints > 0) {
      if (n != options_.joints) {
        fail(line, "--joints " + std::to_string(options_.joints) + " but " + std::to_string(n) +
                       " joint columns are mapped or found (q1 .. q" + std::to_string(n) + ")");
      }
      return;
    }
    const std::string last = names[static_cast<std::size_t>(q_.back())];
    std::size_t digits = last.size();
    while (digits > 0 && std::isdigit(static_cast<unsigned char>(last[digits - 1]))) --digits;
    std::vector<std::string> next = {"q" + std::to_string(n + 1), "joint_" + std::to_string(n + 1),
                                     "joint" + std::to_string(n + 1)};
    if (digits < last.size() && last.size() - digits < 4 && std::stoi(last.substr(digits)) == n) {
      next.push_back(last.substr(0, digits) + std::to_string(n + 1));
    }
    for (const std::string& candidate : next) {
      for (std::size_t c = 0; c < names.size(); ++c) {
        if (lower(names[c]) == lower(candidate)) {
          fail(line, "the header has a column '" + shortExcerpt(names[c]) + "' that looks like joint " +
                         std::to_string(n + 1) + ", but only " + std::to_string(n) +
                         " joints are mapped: map it (--columns q" + std::to_string(n + 1) + "=" +
                         shortExcerpt(names[c]) + ") or say --joints " + std::to_string(n));
        }
      }
    }
  }

  void mapColumns(const std::vector<std::string>& names, int line) {
    for (const auto& entry : options_.columns) {
      if (!isCampaignColumn(entry.first)) {
        fail(line, "--columns: '" + shortExcerpt(entry.first) +
                       "' is not a campaign column (t, q1 .. qN, x, y, z, qm1 .. qmN, temp, payload)");
      }
    }
    time_ = columnOf(names, "t", line);
    for (int j = 1; j <= kMaxJoints; ++j) {
      const int column = columnOf(names, "q" + std::to_string(j), line);
      if (column < 0) break;
      q_.push_back(column);
    }
    if (q_.empty()) {
      fail(line,
           "no joint columns: the header has no q1 or joint_1 (map the export's names with --columns q1=NAME,q2=...)");
    }
    for (std::size_t j = 1; j <= q_.size(); ++j) {
      const int column = columnOf(names, "qm" + std::to_string(j), line);
      if (column < 0) break;
      qm_.push_back(column);
    }
    if (!qm_.empty() && qm_.size() != q_.size()) fail(line, "qm columns for some joints only");
    mapPositions(names, line);
    if (x_ < 0 && qm_.empty()) {
      fail(line, "no measurement: the header has neither x, y, z nor qm1 .. (map them with --columns x=NAME,...)");
    }
    temperature_ = columnOf(names, "temp", line);
    payload_ = columnOf(names, "payload", line);
    checkMappingUsed(line);
    checkColumnsDistinct(names, line);
    checkNoJointLeft(names, line);
  }

  double number(const std::string& cell, int line, const std::string& column, bool required) const {
    if (cell.empty()) {
      if (required) fail(line, "column '" + shortExcerpt(column) + "': empty cell in a required column");
      return kNaN;
    }
    std::string text = cell;
    if (decimal_ == ',') std::replace(text.begin(), text.end(), ',', '.');
    const char* begin = text.data();
    const char* end = text.data() + text.size();
    if (*begin == '+') ++begin;
    double value = 0.0;
    const auto result = std::from_chars(begin, end, value);
    if (result.ec != std::errc() || result.ptr != end || !std::isfinite(value)) {
      fail(line, "column '" + shortExcerpt(column) + "': '" + shortExcerpt(cell) + "' is not a finite number" +
                     (decimal_ == '.' && cell.find(',') != std::string::npos ? " (a decimal comma? --decimal ,)" : ""));
    }
    return value;
  }

  std::string source_;
  CsvImportOptions options_;
  char separator_ = ',';
  char decimal_ = '.';
  int time_ = -1, x_ = -1, y_ = -1, z_ = -1, temperature_ = -1, payload_ = -1;
  int x_add_ = -1, y_add_ = -1, z_add_ = -1;  // the second column of a derived x, y, z (-1: none)
  std::vector<int> q_, qm_;
  std::vector<std::pair<std::string, int>> used_;  // campaign column, header column
};

}  // namespace

MeasurementCampaign importCsv(const std::string& text, const std::string& source_name,
                              const CsvImportOptions& options) {
  std::string storage;
  return CsvImporter(source_name, options).run(plainText<MeasurementError>(text, source_name, storage));
}

MeasurementCampaign importCsvFile(const std::string& path, const CsvImportOptions& options) {
  std::string text;
  try {
    text = readTextFile(path, "measurement export");
  } catch (const Error& error) {
    throw MeasurementError(error.what());
  }
  return importCsv(text, path, options);
}

std::map<std::string, std::string> parseColumnMapping(const std::string& text) {
  std::map<std::string, std::string> mapping;
  std::stringstream stream(text);
  for (std::string item; std::getline(stream, item, ',');) {
    if (trim(item).empty()) continue;
    const auto equals = item.find('=');
    if (equals == std::string::npos || trim(item.substr(0, equals)).empty() || trim(item.substr(equals + 1)).empty()) {
      throw MeasurementError("--columns: '" + shortExcerpt(item) + "' is not CAMPAIGN_COLUMN=EXPORT_NAME");
    }
    mapping[trim(item.substr(0, equals))] = trim(item.substr(equals + 1));
  }
  return mapping;
}

}  // namespace jointcomp
