// Heap allocations of a benchmark binary, counted: this unit replaces the global operator new/delete
// (every form) and interposes glibc's malloc family (Eigen's dynamic matrices, and so KDL's JntArray and
// JntSpaceInertiaMatrix, allocate with malloc, not operator new), forwarding to glibc's allocator so that
// memory from either side may be freed by the other. Linked into the benchmarks as an object, so that the
// replacements always take effect.
#include "bench/support/allocation_counting.hpp"

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <new>

namespace {
std::atomic<std::uint64_t> g_allocations{0};  // constant-initialised: safe before any constructor runs
inline void countAllocation() { g_allocations.fetch_add(1, std::memory_order_relaxed); }
}  // namespace

namespace jointcomp::bench {

std::uint64_t allocationCount() { return g_allocations.load(std::memory_order_relaxed); }

void AllocationCounter::report(benchmark::State& state) const {
  const std::uint64_t made = allocationCount() - start;
  state.counters["allocs_per_call"] = benchmark::Counter(
      state.iterations() > 0 ? static_cast<double>(made) / static_cast<double>(state.iterations()) : 0.0);
}

}  // namespace jointcomp::bench

extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* pointer, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void* __libc_valloc(std::size_t size);
void* __libc_pvalloc(std::size_t size);
void __libc_free(void* pointer);

// The malloc family, forwarded to glibc's allocator (so that memory from either side may be freed by the
// other) and counted.
void* malloc(std::size_t size) {
  countAllocation();
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
  countAllocation();
  return __libc_calloc(count, size);
}
void* realloc(void* pointer, std::size_t size) {
  countAllocation();
  return __libc_realloc(pointer, size);
}
void* memalign(std::size_t alignment, std::size_t size) {
  countAllocation();
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  countAllocation();
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** result, std::size_t alignment, std::size_t size) {
  if (alignment % sizeof(void*) != 0 || (alignment & (alignment - 1)) != 0) return EINVAL;
  countAllocation();
  void* pointer = __libc_memalign(alignment, size);
  if (pointer == nullptr && size != 0) return ENOMEM;
  *result = pointer;
  return 0;
}
void* valloc(std::size_t size) {
  countAllocation();
  return __libc_valloc(size);
}
void* pvalloc(std::size_t size) {
  countAllocation();
  return __libc_pvalloc(size);
}
void free(void* pointer) { __libc_free(pointer); }
}  // extern "C"

namespace {
// operator new goes to glibc directly so that one allocation counts once.
void* countedNew(std::size_t size) {
  countAllocation();
  if (size == 0) size = 1;
  if (void* pointer = __libc_malloc(size)) return pointer;
  throw std::bad_alloc();
}
void* countedAlignedNew(std::size_t size, std::align_val_t alignment) {
  countAllocation();
  if (size == 0) size = 1;
  if (void* pointer = __libc_memalign(static_cast<std::size_t>(alignment), size)) return pointer;
  throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t size) { return countedNew(size); }
void* operator new[](std::size_t size) { return countedNew(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return countedNew(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return countedNew(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t size, std::align_val_t alignment) { return countedAlignedNew(size, alignment); }
void* operator new[](std::size_t size, std::align_val_t alignment) { return countedAlignedNew(size, alignment); }
void* operator new(std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  try {
    return countedAlignedNew(size, alignment);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  try {
    return countedAlignedNew(size, alignment);
  } catch (...) {
    return nullptr;
  }
}
void operator delete(void* pointer) noexcept { __libc_free(pointer); }
void operator delete[](void* pointer) noexcept { __libc_free(pointer); }
void operator delete(void* pointer, std::size_t) noexcept { __libc_free(pointer); }
void operator delete[](void* pointer, std::size_t) noexcept { __libc_free(pointer); }
void operator delete(void* pointer, const std::nothrow_t&) noexcept { __libc_free(pointer); }
void operator delete[](void* pointer, const std::nothrow_t&) noexcept { __libc_free(pointer); }
void operator delete(void* pointer, std::align_val_t) noexcept { __libc_free(pointer); }
void operator delete[](void* pointer, std::align_val_t) noexcept { __libc_free(pointer); }
void operator delete(void* pointer, std::size_t, std::align_val_t) noexcept { __libc_free(pointer); }
void operator delete[](void* pointer, std::size_t, std::align_val_t) noexcept { __libc_free(pointer); }
void operator delete(void* pointer, std::align_val_t, const std::nothrow_t&) noexcept { __libc_free(pointer); }
void operator delete[](void* pointer, std::align_val_t, const std::nothrow_t&) noexcept { __libc_free(pointer); }
