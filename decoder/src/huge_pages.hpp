// Internal: the transparent-huge-page hint for the decoder's large buffers.
#pragma once
#include <cstdint>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace pmz {

// Refinement reads the mesh buffers at random: ask the OS to back their untouched capacity
// with transparent huge pages (fewer page faults and TLB misses). Only a hint: where
// unsupported or disabled it does nothing, and results never depend on it.
template <typename T>
void advise_huge_pages([[maybe_unused]] const std::vector<T>& v) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr uintptr_t kHuge = uintptr_t(2) << 20;
  const uintptr_t p = reinterpret_cast<uintptr_t>(v.data());
  const uintptr_t b = (p + kHuge - 1) & ~(kHuge - 1),
                  e = (p + v.capacity() * sizeof(T)) & ~(kHuge - 1);
  if (e > b) madvise(reinterpret_cast<void*>(b), e - b, MADV_HUGEPAGE);
#endif
}

}  // namespace pmz
