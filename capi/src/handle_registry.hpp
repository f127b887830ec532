// The table of live handles and the rule that enforces the handle lifetimes of the header: every entry point
// that takes a handle marks it busy until it returns, and *_free refuses a busy handle (JC_ERROR_BUSY)
// instead of freeing memory another call (or the caller's own outer call, from a callback) still uses.
// A pointer is looked up in the table, never dereferenced, before it is trusted: a freed handle or a
// pointer that never was one is JC_ERROR_WRONG_HANDLE without reading its memory.
#pragma once

#include <atomic>
#include <cstddef>
#include <memory>

namespace jointcomp::capi {

enum class HandleKind { Robot, Plant, Report, SpiralJob };

// What every handle carries: the number of calls in progress on it.
struct HandleHeader {
  std::atomic<int> busy{0};
};

// Enters `handle` (of `kind`) in the table: it becomes usable by the API's calls.
void registerHandle(const HandleHeader* handle, HandleKind kind);

// Marks `handle` busy until the entry point running on this thread returns (see EntryScope). Throws
// JC_ERROR_WRONG_HANDLE when it is not a live handle of `kind`; `name` is the parameter's name.
void acquireHandle(const void* handle, HandleKind kind, const char* name);

// Removes `handle` from the table so that its memory may be released; JC_ERROR_BUSY when a call is in
// progress on it, JC_ERROR_WRONG_HANDLE when it is not a live handle of `kind`.
void retireHandle(const void* handle, HandleKind kind, const char* name);

// Lives for one entry point's call: releases the handles acquired on this thread since it began (nested
// entry points, called from a progress callback, release only their own).
class EntryScope {
public:
  EntryScope() noexcept;
  ~EntryScope();
  EntryScope(const EntryScope&) = delete;
  EntryScope& operator=(const EntryScope&) = delete;

private:
  std::size_t mark_;
};

// A handle made by a call, entered in the table and handed over to the caller.
template <class Handle>
Handle* publish(std::unique_ptr<Handle> handle) {
  registerHandle(handle.get(), Handle::kKind);
  return handle.release();
}

}  // namespace jointcomp::capi
