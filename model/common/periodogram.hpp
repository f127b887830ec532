// The strongest periodic order of an irregularly sampled signal: each order k of the angle x is fitted
// alone, y ~ c + a cos(k x) + b sin(k x), by least squares, and the order with the largest amplitude
// sqrt(a^2 + b^2) wins (a least-squares periodogram, which needs no even sampling: measurement poses are
// scattered). It stands out when its amplitude exceeds kOrderStandsOut times the median over the scanned
// orders: noise spreads evenly over the orders, a real periodic error piles up in one.
#pragma once

#include <vector>

namespace jointcomp {

constexpr double kOrderStandsOut = 3.0;

struct OrderPeak {
  int order = 0;           // 0: too few rows (fewer than 8) or no order scanned
  double amplitude = 0.0;  // in the unit of the signal
  bool stands_out = false;
};

// Orders first_order .. last_order of `angle` (rad) in `signal`, rows paired by index.
OrderPeak strongestOrder(const std::vector<double>& signal, const std::vector<double>& angle, int first_order,
                         int last_order);

}  // namespace jointcomp
