// Counts global heap allocations, to prove that per-step paths never allocate, and records the
// largest single one, to prove that loaders allocate what the bytes present justify.
// Include in exactly ONE translation unit of a test executable: it replaces global operator new/delete.
// Another translation unit of the same executable defines SPARSEBODY_ALLOC_COUNTER_USE_ONLY first and
// gets the counters without a second definition of the operators.
#pragma once
#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

namespace sparsebody_test {
inline std::atomic<long long> g_allocations{0};
inline std::atomic<bool> g_counting{false};
inline std::atomic<std::size_t> g_largest{0};     // largest single request while a LargestAllocation lives
inline std::atomic<bool> g_recording_largest{false};

// RAII scope: counts allocations made while it is alive.
struct AllocationCounter {
  long long start;
  AllocationCounter() : start(g_allocations.load()) { g_counting = true; }
  ~AllocationCounter() { g_counting = false; }
  long long count() const { return g_allocations.load() - start; }
};

// RAII scope: the largest single allocation made while it is alive (loaders must not reserve what
// a file merely claims: tests/loaders).
struct LargestAllocation {
  LargestAllocation() { g_largest = 0; g_recording_largest = true; }
  ~LargestAllocation() { g_recording_largest = false; }
  std::size_t bytes() const { return g_largest.load(); }
};
}  // namespace sparsebody_test

#ifndef SPARSEBODY_ALLOC_COUNTER_USE_ONLY
inline void* sparsebody_test_alloc(std::size_t n, std::size_t align) {
  sparsebody_test::g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (sparsebody_test::g_recording_largest.load(std::memory_order_relaxed)) {
    std::size_t cur = sparsebody_test::g_largest.load();
    while (n > cur && !sparsebody_test::g_largest.compare_exchange_weak(cur, n)) {}
  }
  if (n == 0) n = 1;
  void* p = nullptr;
  if (align > alignof(std::max_align_t)) {
    if (posix_memalign(&p, align, n) != 0) p = nullptr;
  } else {
    p = std::malloc(n);
  }
  if (!p) throw std::bad_alloc();
  return p;
}
void* operator new(std::size_t n) { return sparsebody_test_alloc(n, 0); }
void* operator new[](std::size_t n) { return sparsebody_test_alloc(n, 0); }
void* operator new(std::size_t n, std::align_val_t a) { return sparsebody_test_alloc(n, static_cast<std::size_t>(a)); }
void* operator new[](std::size_t n, std::align_val_t a) { return sparsebody_test_alloc(n, static_cast<std::size_t>(a)); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try { return sparsebody_test_alloc(n, 0); } catch (...) { return nullptr; }
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
#endif  // SPARSEBODY_ALLOC_COUNTER_USE_ONLY
