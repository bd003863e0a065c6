// SPDX-License-Identifier: MIT
#include "pmz/huge_pages.hpp"

#if defined(__linux__) && defined(MADV_HUGEPAGE)
namespace pmz::huge_pages {

namespace {
size_t mapped_bytes(size_t bytes) { return (bytes + kPage - 1) & ~(kPage - 1); }
}  // namespace

void* allocate(size_t bytes) {
  if (bytes < kPage) return ::operator new(bytes);
  const size_t len = mapped_bytes(bytes);
  if (len < bytes || len + kPage < len) throw std::bad_alloc();
  // Over-map by one page, then return the unaligned head and the tail to the system.
  void* m = mmap(nullptr, len + kPage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (m == MAP_FAILED) throw std::bad_alloc();
  const uintptr_t b = reinterpret_cast<uintptr_t>(m);
  const uintptr_t a = (b + kPage - 1) & ~uintptr_t(kPage - 1);
  if (a > b) munmap(m, a - b);
  munmap(reinterpret_cast<void*>(a + len), b + kPage - a);
  madvise(reinterpret_cast<void*>(a), len, MADV_HUGEPAGE);  // a hint: ignored where THP is off
  return reinterpret_cast<void*>(a);
}

void deallocate(void* p, size_t bytes) noexcept {
  if (bytes < kPage)
    ::operator delete(p);
  else
    munmap(p, mapped_bytes(bytes));
}

}  // namespace pmz::huge_pages
#endif
