#pragma once
// Include in exactly one translation unit of a test executable of its own: replaces the global
// operator new/delete with counting versions so a test can prove a code path never touches the
// heap (test::allocations() before and after). Other test binaries are unaffected.
#include <atomic>
#include <cstdlib>
#include <new>

namespace overstep::test {
inline std::atomic<long>& allocationCounter() {
  static std::atomic<long> n{0};
  return n;
}
inline long allocations() { return allocationCounter().load(); }
}  // namespace overstep::test

// GCC 12 at -O1 (the sanitizer build) inlines gtest's new/delete pairs and then flags this
// malloc/free-based replacement as mismatched: it is not.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

void* operator new(std::size_t n) {
  ++overstep::test::allocationCounter();
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
