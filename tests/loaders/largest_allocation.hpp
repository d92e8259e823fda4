// Records the largest single heap allocation while a scope is alive (replaces operator new: include
// in exactly one translation unit).
#pragma once
#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

namespace loader_test {
inline std::atomic<std::size_t> g_largest{0};
inline std::atomic<bool> g_recording{false};
struct LargestAllocation {
  LargestAllocation() { g_largest = 0; g_recording = true; }
  ~LargestAllocation() { g_recording = false; }
  std::size_t bytes() const { return g_largest.load(); }
};
}  // namespace loader_test

inline void* loader_test_alloc(std::size_t n, std::size_t align) {
  if (loader_test::g_recording) {
    std::size_t cur = loader_test::g_largest.load();
    while (n > cur && !loader_test::g_largest.compare_exchange_weak(cur, n)) {}
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
void* operator new(std::size_t n) { return loader_test_alloc(n, 0); }
void* operator new[](std::size_t n) { return loader_test_alloc(n, 0); }
void* operator new(std::size_t n, std::align_val_t a) { return loader_test_alloc(n, static_cast<std::size_t>(a)); }
void* operator new[](std::size_t n, std::align_val_t a) { return loader_test_alloc(n, static_cast<std::size_t>(a)); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
