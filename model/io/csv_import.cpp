#include "model/io/csv_import.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

#include "model/common/errors.hpp"
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
        campaign.position.emplace_back(value(x_, false) * length, value(y_, false) * length, value(z_, false) * length);
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

  // The column of campaign column `name` in the header, -1 when absent (an error when it was mapped).
  int columnOf(const std::vector<std::string>& names, const std::string& name, int line) const {
    const auto mapped = options_.columns.find(name);
    const std::string wanted = mapped != options_.columns.end() ? mapped->second : name;
    for (std::size_t c = 0; c < names.size(); ++c) {
      if (names[c] == wanted) return static_cast<int>(c);
    }
    for (std::size_t c = 0; c < names.size(); ++c) {
      if (lower(names[c]) == lower(wanted)) return static_cast<int>(c);
    }
    if (mapped != options_.columns.end()) {
      std::string list;
      for (const std::string& n : names) list += (list.empty() ? "" : ", ") + shortExcerpt(n);
      fail(line, "column '" + shortExcerpt(wanted) + "' (mapped to " + name + ") is not in the header (" + list + ")");
    }
    return -1;
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
      fail(line, "no joint columns: the header has no q1 (map the export's names with --columns q1=NAME,q2=...)");
    }
    for (std::size_t j = 1; j <= q_.size(); ++j) {
      const int column = columnOf(names, "qm" + std::to_string(j), line);
      if (column < 0) break;
      qm_.push_back(column);
    }
    if (!qm_.empty() && qm_.size() != q_.size()) fail(line, "qm columns for some joints only");
    x_ = columnOf(names, "x", line);
    y_ = columnOf(names, "y", line);
    z_ = columnOf(names, "z", line);
    if ((x_ >= 0) != (y_ >= 0) || (x_ >= 0) != (z_ >= 0)) fail(line, "columns x, y and z go together");
    if (x_ < 0 && qm_.empty()) {
      fail(line, "no measurement: the header has neither x, y, z nor qm1 .. (map them with --columns x=NAME,...)");
    }
    temperature_ = columnOf(names, "temp", line);
    payload_ = columnOf(names, "payload", line);
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
  std::vector<int> q_, qm_;
};

}  // namespace

MeasurementCampaign importCsv(const std::string& text, const std::string& source_name,
                              const CsvImportOptions& options) {
  return CsvImporter(source_name, options).run(text);
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
