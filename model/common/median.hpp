// The median of a set of values (the upper middle one for an even count), as the robust scales and the
// reports use it; 0 for no values.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace jointcomp {

inline double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

}  // namespace jointcomp
