// Geometric paths of the tool point, parameterised by arc length s in [0, length()] (metres).
// A Path is immutable once built; it is cheap to query and safe to share between threads.
#pragma once

#include <string>
#include <variant>
#include <vector>

#include <Eigen/Core>

namespace jointcomp {

// Logarithmic spiral R = a exp(b theta) in the XY plane through `centre` (the paper's test path).
// Defaults are the paper's: a = 24 mm, b = 0.15, theta from 0 to 4 pi. The caller sets the centre.
struct SpiralSpec {
  double a = 0.024;                                  // m, radius at theta = 0
  double b = 0.15;                                   // growth rate per radian; negative winds inwards
  double theta_start = 0.0;                          // rad
  double theta_end = 4.0 * EIGEN_PI;                 // rad, must exceed theta_start
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // m; the spiral lies in the plane z = centre.z()
};

class Path {
public:
  // Total arc length, m. Always positive.
  double length() const { return length_; }

  // Point at arc length s. s must be finite and within [0, length()]; values outside by no more than
  // a rounding error (1e-9 of the length) are clamped, larger ones throw InvalidArgument.
  Eigen::Vector3d pointAt(double s) const;

  // Unit tangent dp/ds at s. On a polyline vertex the tangent of the segment that starts there is
  // returned (of the last segment at the end of the path).
  Eigen::Vector3d tangentAt(double s) const;

  // Curvature vector d2p/ds2 at s (points to the centre of curvature, its norm is the curvature).
  // Zero on polylines: their corners are kinks, not smoothed.
  Eigen::Vector3d curvatureVectorAt(double s) const;

private:
  struct Spiral {
    SpiralSpec spec;
    double speed_factor = 0.0;  // a sqrt(1 + b^2): |dp/dtheta| = speed_factor exp(b theta)
    double start_growth = 0.0;  // exp(b theta_start)
  };
  struct Polyline {
    std::vector<Eigen::Vector3d> points;  // no two consecutive points coincide
    std::vector<double> arc_length;       // cumulative, arc_length[0] = 0, back() = length
  };

  Path(Spiral spiral, double length);
  Path(Polyline line, double length);

  double clampedArcLength(double s, const char* argument) const;
  double spiralAngleAt(const Spiral& spiral, double s) const;
  std::size_t polylineSegmentAt(const Polyline& polyline, double s) const;

  std::variant<Spiral, Polyline> geometry_;
  double length_ = 0.0;

  friend Path logarithmicSpiral(const SpiralSpec& spec);
  friend Path polyline(std::vector<Eigen::Vector3d> points);
};

// The paper's spiral, with arc length and its inverse in closed form. Throws InvalidArgument naming
// the SpiralSpec field at fault (non-finite values, a <= 0, b == 0, theta_end <= theta_start).
Path logarithmicSpiral(const SpiralSpec& spec);

// The segment from `start` to `end`. Throws InvalidArgument for non-finite or coincident points.
Path straightLine(const Eigen::Vector3d& start, const Eigen::Vector3d& end);

// Piecewise-linear path through `points` (metres), interpolated linearly by arc length. Consecutive
// duplicates are dropped. Throws InvalidArgument naming the index of a non-finite point, for fewer
// than 2 points, or when all points coincide.
Path polyline(std::vector<Eigen::Vector3d> points);

// Polyline read from a CSV file: a header row naming (among others, in any order, case-insensitively)
// the columns x, y, z in millimetres, then one row per point with as many cells as the header. Lines
// starting with `#` (comments) and blank lines are skipped wherever they are. Other columns are
// ignored. Values are converted to metres.
// Throws InvalidArgument whose message names the file, the line (1-based) and the column (1-based
// number and name): unreadable file, missing or duplicate column, wrong cell count, non-numeric or
// non-finite cell, fewer than 2 points, zero-length path.
Path polylineFromCsv(const std::string& file_path);

}  // namespace jointcomp
