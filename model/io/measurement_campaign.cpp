#include "model/io/measurement_campaign.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "model/common/errors.hpp"
#include "model/common/plain_text.hpp"
#include "model/common/strict_json.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/text_cells.hpp"
#include "model/io/urdf_writer.hpp"

namespace jointcomp {
namespace {

// The plausible ranges of a campaign's values, in the file's units: far beyond any robot cell, yet wide
// enough for any real campaign (a laser tracker reaches 80 m; a continuous joint may wind many turns). The
// reader refuses values beyond them and the writer does not write them.
constexpr double kMaxTimeS = 1e10;
constexpr double kMaxAngleDeg = 1e5;
constexpr double kMaxLengthMm = 1e6;
constexpr double kMaxTemperatureDegC = 1000.0;
constexpr double kMaxWrench = 1e7;  // N, N m
constexpr double kMaxPayloadKg = 1e5;

constexpr const char* kFormatLine = "jointcomp-measurements/1";
constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;
constexpr double kNotMeasured = std::numeric_limits<double>::quiet_NaN();

class CampaignParser {
public:
  explicit CampaignParser(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(int line, const std::string& what) const {
    throw MeasurementError(source_ + ":" + std::to_string(line) + ": " + what);
  }

  // A cell as a number; empty cells give `empty_value`, or fail when the column is required.
  double number(const std::string& cell, int line, const std::string& column, bool required, double empty_value) const {
    if (cell.empty()) {
      if (required) fail(line, "column '" + shortExcerpt(column) + "': empty cell in a required column");
      return empty_value;
    }
    double value = 0.0;
    const char* begin = cell.data();
    const char* end = cell.data() + cell.size();
    if (*begin == '+') ++begin;
    const auto result = std::from_chars(begin, end, value);
    if (result.ec == std::errc::result_out_of_range)
      fail(line, "column '" + shortExcerpt(column) + "': '" + shortExcerpt(cell) + "' is not finite");
    if (result.ec != std::errc() || result.ptr != end) {
      fail(line, "column '" + shortExcerpt(column) + "': '" + shortExcerpt(cell) + "' is not a number");
    }
    if (!std::isfinite(value))
      fail(line, "column '" + shortExcerpt(column) + "': '" + shortExcerpt(cell) + "' is not finite");
    return value;
  }

  // Absurd values are refused where they stand, before they reach a fit: far beyond any robot cell, yet
  // wide enough for any real campaign (a laser tracker reaches 80 m; a continuous joint may wind many turns).
  void requirePlausible(double value, double limit, int line, const std::string& column, const char* unit) const {
    if (std::isnan(value) || std::abs(value) <= limit) return;
    char text[200];
    std::snprintf(text, sizeof text, "column '%s': %.15g %s is beyond the plausible range of +-%g %s", column.c_str(),
                  value, unit, limit, unit);
    fail(line, text);
  }

  MeasurementCampaign parse(const std::string& text) {
    MeasurementCampaign campaign;
    campaign.source = source_;
    std::istringstream stream(text);
    std::string raw;
    int line_number = 0;
    bool header_seen = false;
    std::vector<std::string> header;
    std::map<std::string, int> column_of;
    while (std::getline(stream, raw)) {
      ++line_number;
      if (line_number == 1 && raw.rfind("\xEF\xBB\xBF", 0) == 0) raw = raw.substr(3);  // UTF-8 byte-order mark
      const std::string line = trimmed(raw);
      if (!header_seen) {
        if (line_number == 1) {
          if (line.rfind('#', 0) != 0 || trimmed(line.substr(1)) != std::string("format: ") + kFormatLine) {
            fail(1, std::string("the first line must be '# format: ") + kFormatLine + "'");
          }
        }
        if (line.rfind('#', 0) == 0) {
          const std::string entry = trimmed(line.substr(1));
          const auto colon = entry.find(':');
          if (colon == std::string::npos) fail(line_number, "metadata line is not '# key: value'");
          campaign.metadata[trimmed(entry.substr(0, colon))] = trimmed(entry.substr(colon + 1));
          continue;
        }
        if (line.empty()) continue;
        header = splitCells(line, ',');
        requireCommaSeparated(header, line, line_number);
        for (std::size_t c = 0; c < header.size(); ++c) {
          if (header[c].empty()) fail(line_number, "column " + std::to_string(c + 1) + " of the header has no name");
          if (column_of.count(header[c])) fail(line_number, "column '" + shortExcerpt(header[c]) + "' appears twice");
          column_of[header[c]] = static_cast<int>(c);
        }
        header_seen = true;
        interpretHeader(campaign, column_of, line_number);
        continue;
      }
      if (line.empty()) continue;
      const std::vector<std::string> cells = splitCells(line, ',');
      if (cells.size() != header.size()) {
        // More cells than columns, in a file of numbers: most likely decimal commas ("0,365").
        const bool decimal_commas = cells.size() > header.size() && line.find_first_of(";\t") == std::string::npos;
        fail(line_number, "row has " + std::to_string(cells.size()) + " cells, the header has " +
                              std::to_string(header.size()) +
                              (decimal_commas ? " (decimal commas? the format's decimal mark is '.', as in 0.365, "
                                                "and ',' only separates cells)"
                                              : ""));
      }
      addRow(campaign, cells, column_of, line_number);
    }
    if (line_number == 0) fail(1, "the file is empty (the first line must be '# format: jointcomp-measurements/1')");
    if (!header_seen) fail(line_number, "no header row");
    interpretMetadata(campaign);
    return campaign;
  }

private:
  // A header that is one cell holding ';' or tabs is a file written with another separator (spreadsheets
  // in locales with decimal commas use ';'): say so, instead of "required column 't' is missing".
  void requireCommaSeparated(const std::vector<std::string>& header, const std::string& line, int line_number) const {
    if (header.size() != 1) return;
    const char* separator = line.find(';') != std::string::npos    ? "';'"
                            : line.find('\t') != std::string::npos ? "tabs"
                                                                   : nullptr;
    if (!separator) return;
    fail(line_number, std::string("the header's columns are separated by ") + separator +
                          "; the campaign format separates cells with ',' and writes numbers with '.' as the "
                          "decimal mark (0.365, not 0,365): convert it with jointcomp import-csv "
                          "(docs/measurement-campaign.md)");
  }

  void interpretHeader(MeasurementCampaign& campaign, const std::map<std::string, int>& column_of, int line) {
    if (!column_of.count("t")) fail(line, "required column 't' is missing");
    int dof = 0;
    while (column_of.count("q" + std::to_string(dof + 1))) ++dof;
    if (dof == 0) fail(line, "required columns q1 ... qN are missing");
    if (dof > kMaxJoints) fail(line, "more than " + std::to_string(kMaxJoints) + " joint columns");
    for (const auto& entry : column_of) {
      const std::string& name = entry.first;
      for (const char* prefix : {"q", "qm"}) {
        const std::string p = prefix;
        if (name.size() > p.size() && name.compare(0, p.size(), p) == 0 &&
            name.find_first_not_of("0123456789", p.size()) == std::string::npos) {
          // More digits than any joint count: out of range (std::stoi would throw on a long one).
          const std::string digits = name.substr(p.size());
          const int index = digits.size() > 4 ? kMaxJoints + 1 : std::stoi(digits);
          if (index < 1 || index > dof) {
            fail(line, "column '" + shortExcerpt(name) + "' but the joints are q1 ... q" + std::to_string(dof));
          }
        }
      }
    }
    campaign.dof = dof;
    const int xyz = static_cast<int>(column_of.count("x") + column_of.count("y") + column_of.count("z"));
    if (xyz != 0 && xyz != 3) fail(line, "columns x, y and z go together");
    campaign.has_position = xyz == 3;
    for (int j = 1; j <= dof; ++j) campaign.has_measured_angles |= column_of.count("qm" + std::to_string(j)) > 0;
    if (!campaign.has_position && !campaign.has_measured_angles) {
      fail(line, "a campaign needs measured positions (x, y, z) or measured joint angles (qm1 ...)");
    }
  }

  void addRow(MeasurementCampaign& campaign, const std::vector<std::string>& cells,
              const std::map<std::string, int>& column_of, int line) {
    auto cell = [&](const std::string& column) -> const std::string* {
      const auto found = column_of.find(column);
      return found == column_of.end() ? nullptr : &cells[found->second];
    };
    // `limit` in the file's unit (mm, deg, degC, N, N m, kg).
    auto optional = [&](const std::string& column, double scale, double absent, double limit, const char* unit) {
      const std::string* text = cell(column);
      if (!text) return absent;
      const double value = number(*text, line, column, false, kNotMeasured);
      requirePlausible(value, limit, line, column, unit);
      return std::isnan(value) ? absent : value * scale;
    };
    const double t = number(*cell("t"), line, "t", true, 0.0);
    requirePlausible(t, kMaxTimeS, line, "t", "s");
    if (!campaign.time.empty() && t < campaign.time.back()) {
      fail(line, "column 't': time decreases (" + cell("t")->substr(0, 32) + " after " +
                     std::to_string(campaign.time.back()) + ")");
    }
    campaign.time.push_back(t);
    JointVector command(campaign.dof);
    for (int j = 0; j < campaign.dof; ++j) {
      const std::string column = "q" + std::to_string(j + 1);
      const double degrees = number(*cell(column), line, column, true, 0.0);
      requirePlausible(degrees, kMaxAngleDeg, line, column, "deg");
      command[j] = degrees * kDegree;
    }
    campaign.command.push_back(command);
    if (campaign.has_position) {
      campaign.position.emplace_back(optional("x", 1e-3, kNotMeasured, kMaxLengthMm, "mm"),
                                     optional("y", 1e-3, kNotMeasured, kMaxLengthMm, "mm"),
                                     optional("z", 1e-3, kNotMeasured, kMaxLengthMm, "mm"));
      const Eigen::Vector3d& p = campaign.position.back();
      if (std::isnan(p.x()) != std::isnan(p.y()) || std::isnan(p.x()) != std::isnan(p.z())) {
        fail(line, "columns x, y, z: measured in part only (all three or none)");
      }
    }
    if (campaign.has_measured_angles) {
      JointVector measured(campaign.dof);
      for (int j = 0; j < campaign.dof; ++j)
        measured[j] = optional("qm" + std::to_string(j + 1), kDegree, kNotMeasured, kMaxAngleDeg, "deg");
      campaign.measured_angles.push_back(measured);
    }
    campaign.temperature.push_back(optional("temp", 1.0, kNotMeasured, kMaxTemperatureDegC, "degC"));
    Vector6 wrench;
    const char* names[6] = {"fx", "fy", "fz", "mx", "my", "mz"};
    for (int k = 0; k < 6; ++k) wrench[k] = optional(names[k], 1.0, 0.0, kMaxWrench, k < 3 ? "N" : "N m");
    campaign.wrench.push_back(wrench);
    const double payload = optional("payload", 1.0, 0.0, kMaxPayloadKg, "kg");
    if (payload < 0.0) fail(line, "column 'payload': negative mass");
    campaign.payload.push_back(payload);
  }

  // The comma-separated numbers of metadata `key`.
  std::vector<double> numberList(const std::string& text, const std::string& key) const {
    std::stringstream list(text);
    std::string item;
    std::vector<double> values;
    while (std::getline(list, item, ',')) values.push_back(number(trimmed(item), 1, "# " + key, true, 0.0));
    return values;
  }

  void interpretMetadata(MeasurementCampaign& campaign) const {
    const auto& meta = campaign.metadata;
    auto metaNumber = [&](const std::string& key, const std::string& text) {
      const double value = number(trimmed(text), 1, "# " + key, true, 0.0);
      return value;
    };
    if (meta.count("robot")) campaign.robot = meta.at("robot");
    if (meta.count("frame")) {
      const std::string frame = meta.at("frame");
      if (frame == "base") {
        campaign.frame = MeasurementFrame::Base;
      } else if (frame == "instrument") {
        campaign.frame = MeasurementFrame::Instrument;
      } else {
        throw MeasurementError(source_ + ": metadata 'frame' must be 'base' or 'instrument', is '" +
                               shortExcerpt(frame) + "'");
      }
    }
    if (meta.count("target")) {
      std::vector<double> values = numberList(meta.at("target"), "target");
      for (double& mm : values) {
        requirePlausible(mm, kMaxLengthMm, 1, "# target", "mm");
        mm *= 1e-3;
      }
      if (values.size() != 3) throw MeasurementError(source_ + ": metadata 'target' must be 'x,y,z' in mm");
      campaign.has_target = true;
      campaign.target_in_flange = Eigen::Vector3d(values[0], values[1], values[2]);
    }
    if (meta.count("base_frame")) {
      const std::vector<double> values = numberList(meta.at("base_frame"), "base_frame");
      if (values.size() != 6) {
        throw MeasurementError(source_ + ": metadata 'base_frame' must be 'x,y,z,rx,ry,rz' in mm and deg");
      }
      if (campaign.frame != MeasurementFrame::Instrument) {
        throw MeasurementError(source_ +
                               ": metadata 'base_frame' places the base in an instrument's frame; the "
                               "campaign says 'frame: base' (give 'frame: instrument')");
      }
      for (int k = 0; k < 6; ++k)
        requirePlausible(values[k], k < 3 ? kMaxLengthMm : 360.0, 1, "# base_frame", k < 3 ? "mm" : "deg");
      campaign.has_base_frame = true;
      campaign.base_frame = baseFrameFromValues(values);
    }
    if (meta.count("noise_mm")) campaign.position_noise = metaNumber("noise_mm", meta.at("noise_mm")) * 1e-3;
    if (meta.count("noise_deg")) campaign.angle_noise = metaNumber("noise_deg", meta.at("noise_deg")) * kDegree;
    if (campaign.position_noise < 0.0 || campaign.angle_noise < 0.0) {
      throw MeasurementError(source_ + ": metadata noise_mm and noise_deg must not be negative");
    }
  }

  std::string source_;
};

std::string formatNumber(double value) {
  char buffer[40];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

// The writer applies the reader's rules: a value the reader would refuse (not finite where a number is
// required, beyond its plausible range) is not written. Throws MeasurementError naming the row and column.
void checkReadable(const MeasurementCampaign& c) {
  auto check = [&](double value, double limit, bool optional, const std::string& where, const char* unit) {
    if ((optional && std::isnan(value)) || (std::isfinite(value) && std::abs(value) <= limit)) return;
    char text[160];
    std::snprintf(text, sizeof text, "%.15g %s cannot be written: the reader takes at most +-%g %s", value, unit, limit,
                  unit);
    throw MeasurementError(c.source + ": " + where + ": " + text);
  };
  const char* wrench[6] = {"fx", "fy", "fz", "mx", "my", "mz"};
  const char* xyz[3] = {"x", "y", "z"};
  for (std::size_t k = 0; k < c.size(); ++k) {
    const std::string row = "row " + std::to_string(k + 1) + ", column '";
    check(c.time[k], kMaxTimeS, false, row + "t'", "s");
    for (int j = 0; j < c.dof; ++j) {
      check(c.command[k][j] / kDegree, kMaxAngleDeg, false, row + "q" + std::to_string(j + 1) + "'", "deg");
      if (c.has_measured_angles) {
        check(c.measured_angles[k][j] / kDegree, kMaxAngleDeg, true, row + "qm" + std::to_string(j + 1) + "'", "deg");
      }
    }
    for (int a = 0; a < 3 && c.has_position; ++a)
      check(c.position[k][a] * 1e3, kMaxLengthMm, true, row + xyz[a] + "'", "mm");
    check(c.temperature[k], kMaxTemperatureDegC, true, row + "temp'", "degC");
    for (int a = 0; a < 6; ++a) check(c.wrench[k][a], kMaxWrench, false, row + wrench[a] + "'", a < 3 ? "N" : "N m");
    check(c.payload[k], kMaxPayloadKg, false, row + "payload'", "kg");
    if (c.payload[k] < 0.0) throw MeasurementError(c.source + ": " + row + "payload': negative mass cannot be written");
  }
  for (int a = 0; a < 3 && c.has_target; ++a)
    check(c.target_in_flange[a] * 1e3, kMaxLengthMm, false, "metadata 'target'", "mm");
}

}  // namespace

void MeasurementCampaign::validate() const {
  const std::size_t n = time.size();
  auto fail = [&](const std::string& what) { throw MeasurementError(source + ": " + what); };
  if (command.size() != n || temperature.size() != n || wrench.size() != n || payload.size() != n ||
      (has_position && position.size() != n) || (has_measured_angles && measured_angles.size() != n)) {
    fail("columns of different lengths");
  }
  if (!has_position && !has_measured_angles) fail("neither positions nor joint angles were measured");
  for (std::size_t k = 0; k < n; ++k) {
    if (!std::isfinite(time[k]) || (k > 0 && time[k] < time[k - 1]))
      fail("time is not finite and non-decreasing at row " + std::to_string(k));
    if (command[k].size() != dof || !command[k].allFinite())
      fail("command of row " + std::to_string(k) + " is invalid");
  }
}

Eigen::Isometry3d baseFrameFromValues(const std::vector<double>& v) {
  if (v.size() != 6) throw InvalidArgument("a base frame is x,y,z,rx,ry,rz (mm, deg): 6 numbers");
  Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
  frame.translation() = Eigen::Vector3d(v[0], v[1], v[2]) * 1e-3;
  frame.linear() = rpyToRotation(Eigen::Vector3d(v[3], v[4], v[5]) * kDegree);
  return frame;
}

std::string baseFrameText(const Eigen::Isometry3d& base_frame) {
  const Eigen::Vector3d rpy = rotationToRpy(base_frame.linear()) / kDegree;
  const Eigen::Vector3d mm = base_frame.translation() * 1e3;
  return formatNumber(mm.x()) + "," + formatNumber(mm.y()) + "," + formatNumber(mm.z()) + "," + formatNumber(rpy.x()) +
         "," + formatNumber(rpy.y()) + "," + formatNumber(rpy.z());
}

MeasurementCampaign parseCampaign(const std::string& text, const std::string& source_name) {
  std::string storage;
  return CampaignParser(source_name).parse(plainText<MeasurementError>(text, source_name, storage));
}

MeasurementCampaign readCampaignFile(const std::string& path) {
  std::string text;
  try {
    text = readTextFile(path, "measurement file");
  } catch (const Error& error) {
    throw MeasurementError(error.what());
  }
  return parseCampaign(text, path);
}

std::string campaignToText(const MeasurementCampaign& campaign) {
  campaign.validate();
  checkReadable(campaign);
  std::ostringstream out;
  out << "# format: " << kFormatLine << "\n";
  std::map<std::string, std::string> metadata = campaign.metadata;
  metadata.erase("format");
  if (!campaign.robot.empty()) metadata["robot"] = campaign.robot;
  metadata["frame"] = campaign.frame == MeasurementFrame::Base ? "base" : "instrument";
  if (campaign.has_target) {
    metadata["target"] = formatNumber(campaign.target_in_flange.x() * 1e3) + "," +
                         formatNumber(campaign.target_in_flange.y() * 1e3) + "," +
                         formatNumber(campaign.target_in_flange.z() * 1e3);
  }
  if (campaign.has_base_frame) metadata["base_frame"] = baseFrameText(campaign.base_frame);
  if (campaign.position_noise > 0.0) metadata["noise_mm"] = formatNumber(campaign.position_noise * 1e3);
  if (campaign.angle_noise > 0.0) metadata["noise_deg"] = formatNumber(campaign.angle_noise / kDegree);
  for (const auto& entry : metadata) {
    // A line break would start another line the reader takes for metadata, a header or a row (a newline in
    // import-csv --robot or in the input's path corrupted the header): refused, naming the key.
    const auto control = [](const std::string& text) {
      return std::any_of(text.begin(), text.end(),
                         [](char c) { return static_cast<unsigned char>(c) < 0x20 && c != '\t'; });
    };
    if (control(entry.first) || control(entry.second) || entry.first.find(':') != std::string::npos) {
      throw MeasurementError("campaign metadata '" + shortExcerpt(entry.first) +
                             "': a line break, control character or ':' in a key cannot be written (value '" +
                             shortExcerpt(entry.second) + "')");
    }
    out << "# " << entry.first << ": " << entry.second << "\n";
  }

  bool any_temperature = false, any_wrench = false, any_payload = false;
  for (std::size_t k = 0; k < campaign.size(); ++k) {
    any_temperature |= !std::isnan(campaign.temperature[k]);
    any_wrench |= !campaign.wrench[k].isZero(0.0);
    any_payload |= campaign.payload[k] != 0.0;
  }
  out << "t";
  for (int j = 1; j <= campaign.dof; ++j) out << ",q" << j;
  if (campaign.has_position) out << ",x,y,z";
  if (campaign.has_measured_angles) {
    for (int j = 1; j <= campaign.dof; ++j) out << ",qm" << j;
  }
  if (any_temperature) out << ",temp";
  if (any_wrench) out << ",fx,fy,fz,mx,my,mz";
  if (any_payload) out << ",payload";
  out << "\n";
  auto cell = [](double value, double scale) {
    return std::isnan(value) ? std::string() : formatNumber(value * scale);
  };
  for (std::size_t k = 0; k < campaign.size(); ++k) {
    out << formatNumber(campaign.time[k]);
    for (int j = 0; j < campaign.dof; ++j) out << ',' << formatNumber(campaign.command[k][j] / kDegree);
    if (campaign.has_position) {
      for (int a = 0; a < 3; ++a) out << ',' << cell(campaign.position[k][a], 1e3);
    }
    if (campaign.has_measured_angles) {
      for (int j = 0; j < campaign.dof; ++j) out << ',' << cell(campaign.measured_angles[k][j], 1.0 / kDegree);
    }
    if (any_temperature) out << ',' << cell(campaign.temperature[k], 1.0);
    if (any_wrench) {
      for (int a = 0; a < 6; ++a) out << ',' << formatNumber(campaign.wrench[k][a]);
    }
    if (any_payload) out << ',' << formatNumber(campaign.payload[k]);
    out << "\n";
  }
  return out.str();
}

void writeCampaignFile(const MeasurementCampaign& campaign, const std::string& path) {
  writeFileAtomically(path, campaignToText(campaign));
}

MeasurementCampaign campaignRows(const MeasurementCampaign& campaign, const std::function<bool(std::size_t)>& keep) {
  MeasurementCampaign out = campaign;
  out.time.clear();
  out.command.clear();
  out.position.clear();
  out.measured_angles.clear();
  out.temperature.clear();
  out.wrench.clear();
  out.payload.clear();
  for (std::size_t k = 0; k < campaign.size(); ++k) {
    if (!keep(k)) continue;
    out.time.push_back(campaign.time[k]);
    out.command.push_back(campaign.command[k]);
    if (k < campaign.position.size()) out.position.push_back(campaign.position[k]);
    if (k < campaign.measured_angles.size()) out.measured_angles.push_back(campaign.measured_angles[k]);
    if (k < campaign.temperature.size()) out.temperature.push_back(campaign.temperature[k]);
    if (k < campaign.wrench.size()) out.wrench.push_back(campaign.wrench[k]);
    if (k < campaign.payload.size()) out.payload.push_back(campaign.payload[k]);
  }
  return out;
}

}  // namespace jointcomp
