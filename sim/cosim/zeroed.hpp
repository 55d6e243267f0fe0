// Storage for long traces that are sized once and then written in place
// (the co-simulation's records: millions of doubles). std::allocator would
// zero them on resize() and the simulation write them again; this allocator
// takes large blocks as fresh anonymous pages, which the kernel zeroes and
// (MAP_POPULATE) maps in one call rather than one page fault at a time, so
// value-initializing an element writes nothing (a page mapped so costs
// less than a page fault, and the trace's pages are most of a short run's
// set-up: RunResult::setup_s). Small blocks come from
// std::allocator, zeroed. So a column is sized once: grown again after
// shrinking (resize() after a smaller resize() or clear()), it would show
// the old values where zeros belong.
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <cstring>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

namespace mc::sim {

template <typename T>
class ZeroedAllocator {
  static_assert(std::is_trivially_default_constructible_v<T> && std::is_trivially_destructible_v<T>,
                "ZeroedAllocator: zero bytes must be a T");

 public:
  using value_type = T;
  ZeroedAllocator() = default;
  template <typename U>
  ZeroedAllocator(const ZeroedAllocator<U>& /*other*/) {}  // NOLINT(google-explicit-constructor): rebinding

  T* allocate(size_t n) {
    if (n > std::allocator_traits<std::allocator<T>>::max_size(std::allocator<T>()))
      throw std::bad_array_new_length();
    const size_t bytes = n * sizeof(T);
    if (bytes < kMapped) {
      T* p = std::allocator<T>().allocate(n);
      std::memset(static_cast<void*>(p), 0, bytes);
      return p;
    }
    void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_POPULATE, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    return static_cast<T*>(p);
  }
  void deallocate(T* p, size_t n) {
    const size_t bytes = n * sizeof(T);
    if (bytes < kMapped)
      std::allocator<T>().deallocate(p, n);
    else
      munmap(p, bytes);
  }
  // Value-initialization: the bytes are zero already (an implicit-lifetime
  // T lives in them). Anything else is constructed as usual.
  template <typename U>
  void construct(U* /*p*/) {}
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }

  friend bool operator==(const ZeroedAllocator&, const ZeroedAllocator&) { return true; }

 private:
  static constexpr size_t kMapped = size_t(1) << 17;  // blocks from here on are mapped
};

// A trace's column.
template <typename T>
using TraceVector = std::vector<T, ZeroedAllocator<T>>;

}  // namespace mc::sim
