// Counts global heap allocations, to prove that per-step paths never allocate.
// Include in exactly ONE translation unit of a test executable: it replaces global operator new/delete.
#pragma once
#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

namespace sparsebody_test {
inline std::atomic<long long> g_allocations{0};
inline std::atomic<bool> g_counting{false};

// RAII scope: counts allocations made while it is alive.
struct AllocationCounter {
  long long start;
  AllocationCounter() : start(g_allocations.load()) { g_counting = true; }
  ~AllocationCounter() { g_counting = false; }
  long long count() const { return g_allocations.load() - start; }
};
}  // namespace sparsebody_test

inline void* sparsebody_test_alloc(std::size_t n, std::size_t align) {
  sparsebody_test::g_allocations.fetch_add(1, std::memory_order_relaxed);
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
