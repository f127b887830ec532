#include "model/compensation/path.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <string_view>
#include <utility>

#include "model/common/errors.hpp"

namespace jointcomp {

namespace {

constexpr double kMillimetre = 1e-3;
// Arc lengths this far (relative to the path length) outside [0, length] are rounding, not mistakes.
constexpr double kArcLengthTolerance = 1e-9;

// Shortest text that reads back as the same double, independent of the locale.
std::string formatNumber(double value) {
  std::array<char, 32> text{};
  const auto result = std::to_chars(text.data(), text.data() + text.size(), value);
  return std::string(text.data(), result.ptr);
}

void requireFinite(double value, const char* field) {
  if (!std::isfinite(value)) {
    throw InvalidArgument(std::string(field) + " must be finite, got " + formatNumber(value));
  }
}

// ---- CSV reading -------------------------------------------------------------------------------

std::string_view trimmed(std::string_view text) {
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
  return text;
}

std::vector<std::string_view> splitCells(std::string_view line) {
  std::vector<std::string_view> cells;
  std::size_t begin = 0;
  while (true) {
    const std::size_t comma = line.find(',', begin);
    if (comma == std::string_view::npos) {
      cells.push_back(trimmed(line.substr(begin)));
      return cells;
    }
    cells.push_back(trimmed(line.substr(begin, comma - begin)));
    begin = comma + 1;
  }
}

std::string lowerCase(std::string_view text) {
  std::string result(text);
  std::transform(result.begin(), result.end(), result.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return result;
}

// Header names may be quoted ("x"); the quotes are not part of the name.
std::string_view unquoted(std::string_view cell) {
  if (cell.size() >= 2 && cell.front() == '"' && cell.back() == '"') {
    return trimmed(cell.substr(1, cell.size() - 2));
  }
  return cell;
}

enum class CellParse { ok, not_a_number, not_finite };

// Locale-independent (std::from_chars), and the whole cell must be the number.
CellParse parseCell(std::string_view cell, double& value) {
  if (!cell.empty() && cell.front() == '+') cell.remove_prefix(1);
  if (cell.empty()) return CellParse::not_a_number;
  const char* end = cell.data() + cell.size();
  const auto [parsed_to, error] = std::from_chars(cell.data(), end, value);
  if (parsed_to != end) return CellParse::not_a_number;
  if (error == std::errc::result_out_of_range) return CellParse::not_finite;
  if (error != std::errc()) return CellParse::not_a_number;
  return std::isfinite(value) ? CellParse::ok : CellParse::not_finite;
}

bool isSkippedLine(std::string_view line) {
  const std::string_view content = trimmed(line);
  return content.empty() || content.front() == '#';
}

}  // namespace

// ---- Path --------------------------------------------------------------------------------------

Path::Path(Spiral spiral, double length) : geometry_(std::move(spiral)), length_(length) {}
Path::Path(Polyline line, double length) : geometry_(std::move(line)), length_(length) {}

double Path::clampedArcLength(double s, const char* argument) const {
  const double tolerance = kArcLengthTolerance * length_;
  if (!std::isfinite(s) || s < -tolerance || s > length_ + tolerance) {
    throw InvalidArgument(std::string("Path::") + argument + ": arc length s = " + formatNumber(s) +
                          " is outside [0, " + formatNumber(length_) + "]");
  }
  return std::clamp(s, 0.0, length_);
}

// Inverse of s(theta) = speed_factor / b (exp(b theta) - exp(b theta_start)); log1p keeps the small-s
// end accurate.
double Path::spiralAngleAt(const Spiral& spiral, double s) const {
  const double b = spiral.spec.b;
  return spiral.spec.theta_start + std::log1p(s * b / (spiral.speed_factor * spiral.start_growth)) / b;
}

std::size_t Path::polylineSegmentAt(const Polyline& line, double s) const {
  const auto after = std::upper_bound(line.arc_length.begin(), line.arc_length.end(), s);
  const auto index =
      static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, std::distance(line.arc_length.begin(), after) - 1));
  return std::min(index, line.points.size() - 2);
}

Eigen::Vector3d Path::pointAt(double s) const {
  const double arc = clampedArcLength(s, "pointAt");
  if (const auto* spiral = std::get_if<Spiral>(&geometry_)) {
    const double theta = spiralAngleAt(*spiral, arc);
    const double radius = spiral->spec.a * std::exp(spiral->spec.b * theta);
    return spiral->spec.centre + radius * Eigen::Vector3d(std::cos(theta), std::sin(theta), 0.0);
  }
  const auto& line = std::get<Polyline>(geometry_);
  const std::size_t i = polylineSegmentAt(line, arc);
  const double fraction = (arc - line.arc_length[i]) / (line.arc_length[i + 1] - line.arc_length[i]);
  return line.points[i] + fraction * (line.points[i + 1] - line.points[i]);
}

Eigen::Vector3d Path::tangentAt(double s) const {
  const double arc = clampedArcLength(s, "tangentAt");
  if (const auto* spiral = std::get_if<Spiral>(&geometry_)) {
    const double theta = spiralAngleAt(*spiral, arc);
    const double b = spiral->spec.b;
    const double c = std::cos(theta);
    const double si = std::sin(theta);
    // dp/dtheta = a exp(b theta) (b cos - sin, b sin + cos), of norm a exp(b theta) sqrt(1 + b^2).
    return Eigen::Vector3d(b * c - si, b * si + c, 0.0) / std::sqrt(1.0 + b * b);
  }
  const auto& line = std::get<Polyline>(geometry_);
  const std::size_t i = polylineSegmentAt(line, arc);
  return (line.points[i + 1] - line.points[i]).normalized();
}

Eigen::Vector3d Path::curvatureVectorAt(double s) const {
  const double arc = clampedArcLength(s, "curvatureVectorAt");
  if (const auto* spiral = std::get_if<Spiral>(&geometry_)) {
    const double theta = spiralAngleAt(*spiral, arc);
    const double b = spiral->spec.b;
    const double radius = spiral->spec.a * std::exp(b * theta);
    const double c = std::cos(theta);
    const double si = std::sin(theta);
    // d(tangent)/dtheta divided by ds/dtheta = radius sqrt(1 + b^2).
    return Eigen::Vector3d(-c - b * si, -si + b * c, 0.0) / (radius * (1.0 + b * b));
  }
  return Eigen::Vector3d::Zero();
}

// ---- factories ---------------------------------------------------------------------------------

Path logarithmicSpiral(const SpiralSpec& spec) {
  requireFinite(spec.a, "SpiralSpec.a");
  requireFinite(spec.b, "SpiralSpec.b");
  requireFinite(spec.theta_start, "SpiralSpec.theta_start");
  requireFinite(spec.theta_end, "SpiralSpec.theta_end");
  for (int axis = 0; axis < 3; ++axis) {
    static constexpr std::array<const char*, 3> kFields = {"SpiralSpec.centre.x", "SpiralSpec.centre.y",
                                                           "SpiralSpec.centre.z"};
    requireFinite(spec.centre[axis], kFields[static_cast<std::size_t>(axis)]);
  }
  if (spec.a <= 0.0) {
    throw InvalidArgument("SpiralSpec.a must be positive, got " + formatNumber(spec.a));
  }
  if (spec.b == 0.0) {
    throw InvalidArgument("SpiralSpec.b must not be zero (b = 0 is a circle, not a spiral)");
  }
  if (!(spec.theta_end > spec.theta_start)) {
    throw InvalidArgument("SpiralSpec.theta_end (" + formatNumber(spec.theta_end) +
                          ") must be greater than SpiralSpec.theta_start (" + formatNumber(spec.theta_start) + ")");
  }

  Path::Spiral spiral;
  spiral.spec = spec;
  spiral.speed_factor = spec.a * std::sqrt(1.0 + spec.b * spec.b);
  spiral.start_growth = std::exp(spec.b * spec.theta_start);
  // expm1 keeps short theta ranges and small b accurate.
  const double length =
      spiral.speed_factor * spiral.start_growth * std::expm1(spec.b * (spec.theta_end - spec.theta_start)) / spec.b;
  if (!std::isfinite(length) || !(length > 0.0) || !(spiral.start_growth > 0.0) ||
      !std::isfinite(spiral.start_growth)) {
    throw InvalidArgument("SpiralSpec: a = " + formatNumber(spec.a) + ", b = " + formatNumber(spec.b) +
                          " and theta in [" + formatNumber(spec.theta_start) + ", " + formatNumber(spec.theta_end) +
                          "] give an arc length that is not a positive finite number");
  }
  return Path(std::move(spiral), length);
}

Path polyline(std::vector<Eigen::Vector3d> points) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      throw InvalidArgument("polyline: points[" + std::to_string(i) + "] is not finite");
    }
  }
  // Consecutive duplicates make zero-length segments, which have no tangent.
  points.erase(std::unique(points.begin(), points.end(),
                           [](const Eigen::Vector3d& p, const Eigen::Vector3d& q) { return p == q; }),
               points.end());
  if (points.size() < 2) {
    throw InvalidArgument("polyline: points must hold at least 2 distinct points (a path of positive length)");
  }
  Path::Polyline line;
  line.arc_length.reserve(points.size());
  line.arc_length.push_back(0.0);
  for (std::size_t i = 1; i < points.size(); ++i) {
    line.arc_length.push_back(line.arc_length.back() + (points[i] - points[i - 1]).norm());
  }
  const double length = line.arc_length.back();
  if (!std::isfinite(length)) {
    throw InvalidArgument("polyline: points span a length that is not finite");
  }
  line.points = std::move(points);
  return Path(std::move(line), length);
}

Path straightLine(const Eigen::Vector3d& start, const Eigen::Vector3d& end) {
  if (!start.allFinite()) throw InvalidArgument("straightLine: start is not finite");
  if (!end.allFinite()) throw InvalidArgument("straightLine: end is not finite");
  if (start == end) throw InvalidArgument("straightLine: start and end coincide (zero-length path)");
  return polyline({start, end});
}

namespace {

constexpr std::array<const char*, 3> kAxisNames = {"x", "y", "z"};

// The cells (0-based) of x, y and z in a path file's header; `where` (file:line: ) starts the error when one
// is missing or repeated.
std::array<std::size_t, 3> axisColumns(const std::vector<std::string>& header, const std::string& where) {
  std::array<std::size_t, 3> axis_column{};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const auto first = std::find(header.begin(), header.end(), kAxisNames[axis]);
    if (first == header.end()) {
      throw InvalidArgument(where + "header has no column '" + kAxisNames[axis] +
                            "' (x, y, z in millimetres are required)");
    }
    const auto column = static_cast<std::size_t>(std::distance(header.begin(), first));
    if (std::find(first + 1, header.end(), kAxisNames[axis]) != header.end()) {
      const auto again =
          static_cast<std::size_t>(std::distance(header.begin(), std::find(first + 1, header.end(), kAxisNames[axis])));
      throw InvalidArgument(where + "column " + std::to_string(again + 1) + " ('" + kAxisNames[axis] +
                            "') repeats column " + std::to_string(column + 1));
    }
    axis_column[axis] = column;
  }
  return axis_column;
}

// The point of a data row, in metres, from its x, y and z cells (millimetres); the row must have the header's
// cell count (the header on line header_line). `where` (file:line: ) starts the error.
Eigen::Vector3d pointOfRow(const std::vector<std::string_view>& cells, const std::vector<std::string>& header,
                           std::size_t header_line, const std::array<std::size_t, 3>& axis_column,
                           const std::string& where) {
  if (cells.size() != header.size()) {
    const std::size_t column = std::min(cells.size(), header.size()) + 1;
    const std::string problem = cells.size() < header.size()
                                    ? "column " + std::to_string(column) + " ('" + header[column - 1] + "') is missing"
                                    : "column " + std::to_string(column) + " is not in the header";
    throw InvalidArgument(where + "expected " + std::to_string(header.size()) + " cells as in the header (line " +
                          std::to_string(header_line) + "), found " + std::to_string(cells.size()) + ": " + problem);
  }
  Eigen::Vector3d point;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const std::size_t column = axis_column[axis];
    double value = 0.0;
    const CellParse result = parseCell(cells[column], value);
    if (result != CellParse::ok) {
      throw InvalidArgument(where + "column " + std::to_string(column + 1) + " ('" + kAxisNames[axis] +
                            "'): " + (result == CellParse::not_finite ? "non-finite value '" : "non-numeric cell '") +
                            std::string(cells[column]) + "'");
    }
    point[static_cast<Eigen::Index>(axis)] = value * kMillimetre;
  }
  return point;
}

}  // namespace

Path polylineFromCsv(const std::string& file_path) {
  std::ifstream file(file_path);
  if (!file) {
    throw InvalidArgument("polylineFromCsv: cannot open file '" + file_path + "'");
  }
  const auto at_line = [&file_path](std::size_t line_number) {
    return file_path + ":" + std::to_string(line_number) + ": ";
  };

  std::array<std::size_t, 3> axis_column{};  // 0-based cell index of x, y, z
  std::vector<std::string> header;
  std::size_t header_line = 0;
  std::size_t first_point_line = 0;
  std::size_t last_point_line = 0;
  std::vector<Eigen::Vector3d> points;

  std::string text;
  std::size_t line_number = 0;
  while (std::getline(file, text)) {
    ++line_number;
    std::string_view line(text);
    if (line_number == 1 && line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);  // UTF-8 BOM
    if (isSkippedLine(line)) continue;
    const std::vector<std::string_view> cells = splitCells(line);

    if (header.empty()) {
      header_line = line_number;
      for (const std::string_view cell : cells) header.push_back(lowerCase(unquoted(cell)));
      axis_column = axisColumns(header, at_line(line_number));
      continue;
    }

    const Eigen::Vector3d point = pointOfRow(cells, header, header_line, axis_column, at_line(line_number));
    if (points.empty()) first_point_line = line_number;
    last_point_line = line_number;
    points.push_back(point);
  }
  if (file.bad()) {
    throw InvalidArgument(at_line(line_number) + "read error");
  }

  if (header.empty()) {
    throw InvalidArgument(at_line(line_number) + "no header row found (columns x, y, z in millimetres are required)");
  }
  if (points.size() < 2) {
    throw InvalidArgument(at_line(line_number) + "only " + std::to_string(points.size()) +
                          " data point(s) after the header on line " + std::to_string(header_line) +
                          " (columns x, y, z); a path needs at least 2");
  }
  const bool all_coincide =
      std::all_of(points.begin(), points.end(), [&](const Eigen::Vector3d& p) { return p == points.front(); });
  if (all_coincide) {
    throw InvalidArgument(file_path + ":" + std::to_string(first_point_line) + "-" + std::to_string(last_point_line) +
                          ": all points (columns x, y, z) coincide, the path has zero length");
  }
  return polyline(std::move(points));
}

}  // namespace jointcomp
