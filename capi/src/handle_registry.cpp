#include "handle_registry.hpp"

#include <algorithm>
#include <array>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "api_support.hpp"

namespace jointcomp::capi {
namespace {

struct Entry {
  HandleKind kind;
  std::atomic<int>* busy;
};

// The library's one table of live handles (the bookkeeping of the API, not model state: handles still
// share nothing observable). Calls take the shared lock for a lookup; register and retire the exclusive one.
struct Registry {
  std::shared_mutex mutex;
  std::unordered_map<const void*, Entry> live;
  std::array<const void*, 256> recently_freed{};  // for the message only: "already freed" or "never one"
  std::size_t next_freed = 0;
};

Registry& registry() {
  static Registry* const table = new Registry();  // never destroyed: handles may outlive static destruction
  return *table;
}

struct Held {
  const void* handle;
  std::atomic<int>* busy;
};
thread_local std::vector<Held> held;  // the handles the entry points running on this thread use

const char* kindName(HandleKind kind) {
  switch (kind) {
    case HandleKind::Robot: return "jc_robot";
    case HandleKind::Plant: return "jc_plant";
    case HandleKind::Report: return "jc_report";
    case HandleKind::SpiralJob: return "jc_spiral_job";
  }
  return "handle";
}

// Called with the registry locked.
[[noreturn]] void wrongHandle(const Registry& table, const void* handle, HandleKind expected) {
  std::string found = "a pointer that is not a live jointcomp handle (already freed, or never one)";
  const auto entry = table.live.find(handle);
  if (entry != table.live.end()) {
    found = std::string("a ") + kindName(entry->second.kind);
  } else if (std::find(table.recently_freed.begin(), table.recently_freed.end(), handle) !=
             table.recently_freed.end()) {
    found = "a handle that was already freed";
  }
  throw ApiError(JC_ERROR_WRONG_HANDLE, std::string("expected a ") + kindName(expected) + ", got " + found);
}

}  // namespace

void registerHandle(const HandleHeader* handle, HandleKind kind) {
  Registry& table = registry();
  const std::unique_lock<std::shared_mutex> lock(table.mutex);
  std::replace(table.recently_freed.begin(), table.recently_freed.end(), static_cast<const void*>(handle),
               static_cast<const void*>(nullptr));
  table.live[handle] = Entry{kind, const_cast<std::atomic<int>*>(&handle->busy)};
}

void acquireHandle(const void* handle, HandleKind kind, const char* name) {
  if (!handle) invalid(std::string(name) + " is NULL");
  held.reserve(held.size() + 1);  // may throw: before the count is taken
  Registry& table = registry();
  const std::shared_lock<std::shared_mutex> lock(table.mutex);
  const auto entry = table.live.find(handle);
  if (entry == table.live.end() || entry->second.kind != kind) wrongHandle(table, handle, kind);
  // Under the shared lock: a retire (exclusive lock) sees either no count or this one.
  entry->second.busy->fetch_add(1, std::memory_order_acquire);
  held.push_back({handle, entry->second.busy});
}

void retireHandle(const void* handle, HandleKind kind, const char* name) {
  Registry& table = registry();
  const std::unique_lock<std::shared_mutex> lock(table.mutex);
  const auto entry = table.live.find(handle);
  if (entry == table.live.end() || entry->second.kind != kind) wrongHandle(table, handle, kind);
  const int calls = entry->second.busy->load(std::memory_order_acquire);
  if (calls > 0) {
    const bool ours = std::any_of(held.begin(), held.end(), [&](const Held& h) { return h.handle == handle; });
    throw ApiError(JC_ERROR_BUSY,
                   std::string(name) + " is in use by " + std::to_string(calls) + " call(s) in progress" +
                       (ours ? ", one of them on this thread (a callback may not free the handle of the call "
                               "that runs it)"
                             : " on other threads") +
                       ": free it when they have returned; it was not freed");
  }
  table.live.erase(entry);
  table.recently_freed[table.next_freed] = handle;
  table.next_freed = (table.next_freed + 1) % table.recently_freed.size();
}

EntryScope::EntryScope() noexcept : mark_(held.size()) {}

EntryScope::~EntryScope() {
  while (held.size() > mark_) {
    held.back().busy->fetch_sub(1, std::memory_order_release);
    held.pop_back();
  }
}

}  // namespace jointcomp::capi
