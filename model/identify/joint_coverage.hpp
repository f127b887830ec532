// Which joint angles a campaign visited: per joint, the union of the intervals [q - h, q + h] around every
// row's angle. A model fitted on data says nothing about angles outside its coverage, so discovery reports
// it, flags held-out campaigns that go beyond it, and periodic tables stay zero outside it.
#pragma once

#include <string>
#include <vector>

#include "model/common/types.hpp"

namespace jointcomp {

struct AngleInterval {
  double low = 0.0, high = 0.0;  // rad
};

struct JointCoverage {
  double half_width = 0.0;                          // rad
  std::vector<std::vector<AngleInterval>> visited;  // per joint, sorted and disjoint
  bool covers(int joint, double angle) const;
  // Fraction of the given rows whose angle of `joint` lies outside the coverage.
  double fractionOutside(int joint, const std::vector<JointVector>& rows) const;
  // "-120.0..35.5, 40.0..60.0" in degrees.
  std::string describe(int joint) const;
};

// Throws InvalidArgument for no rows, rows of different sizes, non-finite angles or a half width <= 0.
JointCoverage jointCoverage(const std::vector<JointVector>& rows, double half_width);

// The median over `rows` of the distance (rad, joint space, all joints) to the nearest of `fitted`: every joint
// inside its coverage does not make a pose near the fitted ones (a held-out campaign that reaches its goals in
// other configurations combines visited angles into unvisited poses). At most max_rows rows are scored and
// at most max_fitted fitted rows searched (strides: the work stays bounded for campaigns of millions of rows;
// with fewer fitted rows searched the distance can only come out larger). Throws InvalidArgument for empty
// inputs, rows of different sizes, non-finite angles or limits below 1.
double medianDistanceToNearest(const std::vector<JointVector>& fitted, const std::vector<JointVector>& rows,
                               int max_rows = 4000, int max_fitted = 50000);

}  // namespace jointcomp
