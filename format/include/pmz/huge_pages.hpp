// SPDX-License-Identifier: MIT
// Buffers that refinement reads at random (the mesh, coordinates, per-vertex contexts): on Linux,
// blocks of at least 2 MiB are mapped 2 MiB-aligned, rounded up to whole 2 MiB pages and hinted
// with MADV_HUGEPAGE, so transparent huge pages back all of them. malloc's own large blocks start
// anywhere in a 2 MiB page: their unaligned head and tail stay on 4 KiB pages (on bunny00-loop2
// about 10,000 page faults of the streaming pattern). Only memory placement: contents and results
// never depend on it. Elsewhere (WebAssembly, other systems) it is std::allocator.
#pragma once

#include <cstddef>
#include <cstdint>
#include <new>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace pmz {

#if defined(__linux__) && defined(MADV_HUGEPAGE)
namespace huge_pages {
inline constexpr size_t kPage = size_t(2) << 20;
// Blocks of at least kPage bytes mapped at a kPage boundary, smaller ones from operator new;
// out of line (the decoder library's size budget). allocate throws std::bad_alloc on failure.
void* allocate(size_t bytes);
void deallocate(void* p, size_t bytes) noexcept;
}  // namespace huge_pages

template <class T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}
  // (std::vector asks for at most max_size() = SIZE_MAX / sizeof(T) elements: no overflow)
  T* allocate(size_t n) { return static_cast<T*>(huge_pages::allocate(n * sizeof(T))); }
  void deallocate(T* p, size_t n) noexcept { huge_pages::deallocate(p, n * sizeof(T)); }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const noexcept {
    return true;
  }
};
template <class T>
using BigVector = std::vector<T, HugePageAllocator<T>>;
#else
template <class T>
using BigVector = std::vector<T>;
#endif

}  // namespace pmz
