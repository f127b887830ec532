// Counting heap allocations in the benchmarks' timed loops (see allocation_counting.cpp).
#pragma once

#include <cstdint>

#include <benchmark/benchmark.h>

namespace jointcomp::bench {

// Allocations made by this process so far (malloc family and operator new, every form).
std::uint64_t allocationCount();

// Counts from construction; report() sets the counter "allocs_per_call": allocations per iteration.
struct AllocationCounter {
  std::uint64_t start = allocationCount();
  void report(benchmark::State& state) const;
};

}  // namespace jointcomp::bench
