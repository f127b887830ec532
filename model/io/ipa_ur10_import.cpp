#include "model/io/ipa_ur10_import.hpp"

#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "model/common/errors.hpp"
#include "model/common/plain_text.hpp"
#include "model/common/strict_json.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/text_cells.hpp"

namespace jointcomp {
namespace {

// A number with a decimal comma ("0,365141", "2,02011E+13").
bool parseDecimalComma(std::string text, double& value) {
  for (char& c : text) {
    if (c == ',') c = '.';
  }
  if (text.empty()) return false;
  const char* begin = text.data();
  const char* end = begin + text.size();
  if (*begin == '+') ++begin;
  const auto result = std::from_chars(begin, end, value);
  return result.ec == std::errc() && result.ptr == end && std::isfinite(value);
}

// Days since 1970-01-01 of a proleptic Gregorian date (the standard civil-calendar arithmetic).
long daysFromCivil(long year, long month, long day) {
  year -= month <= 2;
  const long era = (year >= 0 ? year : year - 399) / 400;
  const long year_of_era = year - era * 400;
  const long day_of_year = (153 * (month + (month > 2 ? -3 : 9)) + 2) / 5 + day - 1;
  const long day_of_era = year_of_era * 365 + year_of_era / 4 - year_of_era / 100 + day_of_year;
  return era * 146097 + day_of_era - 719468;
}

// Seconds of a yyyymmddHHMMSS timestamp, or NaN when the cell is not one (Series B's are mangled).
double timestampSeconds(const std::string& cell) {
  if (cell.size() != 14 || cell.find_first_not_of("0123456789") != std::string::npos) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  auto field = [&](int from, int length) { return std::stol(cell.substr(from, length)); };
  const long year = field(0, 4), month = field(4, 2), day = field(6, 2);
  const long hour = field(8, 2), minute = field(10, 2), second = field(12, 2);
  if (month < 1 || month > 12 || day < 1 || day > 31 || hour > 23 || minute > 59 || second > 60) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return static_cast<double>(daysFromCivil(year, month, day) * 86400 + hour * 3600 + minute * 60 + second);
}

}  // namespace

Eigen::Vector3d ipaTargetInFlange(const std::string& trafo_path) {
  std::string text;
  try {
    text = readTextFile(trafo_path, "transform file");
  } catch (const Error& error) {
    throw MeasurementError(error.what());
  }
  std::string storage;
  std::istringstream stream(plainText<MeasurementError>(text, trafo_path, storage));
  Eigen::Matrix4d transform;
  for (int i = 0; i < 16; ++i) {
    std::string token;
    if (!(stream >> token))
      throw MeasurementError(trafo_path + ": expected 16 numbers (a 4x4 matrix), found " + std::to_string(i));
    double value = 0.0;
    if (!parseDecimalComma(token, value))
      throw MeasurementError(trafo_path + ": '" + shortExcerpt(token) + "' is not a number");
    transform(i / 4, i % 4) = value;
  }
  if (!transform.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 1e-9)) {
    throw MeasurementError(trafo_path + ": the last row of the transform is not 0 0 0 1");
  }
  const Eigen::Matrix3d rotation = transform.topLeftCorner<3, 3>();
  if (!(rotation.transpose() * rotation).isApprox(Eigen::Matrix3d::Identity(), 1e-5)) {
    throw MeasurementError(trafo_path + ": the rotation part is not a rotation");
  }
  return -(rotation.transpose() * transform.topRightCorner<3, 1>()) * 1e-3;
}

MeasurementCampaign importIpaUr10(const std::string& measurements_path, const std::string& trafo_path) {
  std::string text;
  try {
    text = readTextFile(measurements_path, "IPA measurement file");
  } catch (const Error& error) {
    throw MeasurementError(error.what());
  }
  MeasurementCampaign campaign = parseIpaUr10(text, measurements_path);
  if (!trafo_path.empty()) {
    campaign.has_target = true;
    campaign.target_in_flange = ipaTargetInFlange(trafo_path);
  }
  return campaign;
}

MeasurementCampaign parseIpaUr10(const std::string& text, const std::string& measurements_path) {
  auto fail = [&](int line, const std::string& what) {
    throw MeasurementError(measurements_path + ":" + std::to_string(line) + ": " + what);
  };
  std::string storage;
  std::istringstream stream(plainText<MeasurementError>(text, measurements_path, storage));
  std::string raw;
  if (!std::getline(stream, raw)) fail(1, "the file is empty");
  const std::vector<std::string> header = splitCells(trimmed(raw), ';');
  std::map<std::string, int> column_of;
  for (std::size_t c = 0; c < header.size(); ++c) column_of[header[c]] = static_cast<int>(c);
  const char* joints[6] = {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                           "wrist_1_joint",      "wrist_2_joint",       "wrist_3_joint"};
  const char* required[] = {"Timestamp", "measurement_x", "measurement_y", "measurement_z"};
  for (const char* name : required) {
    if (!column_of.count(name)) fail(1, std::string("column '") + name + "' is missing");
  }
  for (const char* name : joints) {
    if (!column_of.count(name)) fail(1, std::string("column '") + name + "' is missing");
  }
  const bool has_temperature = column_of.count("measurement_temperature") > 0;

  MeasurementCampaign campaign;
  campaign.source = measurements_path;
  campaign.robot = "ur10";
  campaign.frame = MeasurementFrame::Instrument;
  campaign.dof = 6;
  campaign.has_position = true;
  campaign.metadata["source"] = "IPA UR10 laser-tracker data (Landgraf et al., IEEE CASE 2021), MIT license";
  std::vector<double> stamps;
  int line_number = 1;
  while (std::getline(stream, raw)) {
    ++line_number;
    const std::string line = trimmed(raw);
    if (line.empty()) continue;
    const std::vector<std::string> cells = splitCells(line, ';');
    if (cells.size() != header.size()) {
      fail(line_number,
           "row has " + std::to_string(cells.size()) + " cells, the header has " + std::to_string(header.size()));
    }
    auto number = [&](const std::string& column) {
      double value = 0.0;
      const std::string& cell = cells[column_of.at(column)];
      if (!parseDecimalComma(cell, value))
        fail(line_number, "column '" + shortExcerpt(column) + "': '" + shortExcerpt(cell) + "' is not a finite number");
      return value;
    };
    JointVector command(6);
    for (int j = 0; j < 6; ++j) command[j] = number(joints[j]);
    campaign.command.push_back(command);
    campaign.position.emplace_back(number("measurement_x") * 1e-3, number("measurement_y") * 1e-3,
                                   number("measurement_z") * 1e-3);
    campaign.temperature.push_back(has_temperature ? number("measurement_temperature")
                                                   : std::numeric_limits<double>::quiet_NaN());
    campaign.wrench.emplace_back(Vector6::Zero());
    campaign.payload.push_back(0.0);
    stamps.push_back(timestampSeconds(cells[column_of.at("Timestamp")]));
  }
  if (campaign.command.empty()) fail(line_number, "no data rows");
  bool all_stamped = true;
  for (double stamp : stamps) all_stamped = all_stamped && std::isfinite(stamp);
  int held = 0;
  for (std::size_t k = 0; k < stamps.size(); ++k) {
    double t = all_stamped ? stamps[k] - stamps[0] : static_cast<double>(k);
    if (k > 0 && t < campaign.time.back()) {
      t = campaign.time.back();
      ++held;
    }
    campaign.time.push_back(t);
  }
  campaign.metadata["time_from"] = all_stamped ? "timestamps (s since the first row)" : "row order (1 s per row)";
  campaign.metadata["time_held_rows"] = std::to_string(held);
  campaign.validate();
  return campaign;
}

}  // namespace jointcomp
