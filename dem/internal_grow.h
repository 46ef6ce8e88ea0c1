// Private to dem/: nothing outside dem/ includes this header. Growing and placing the large
// arrays that are made again at every neighbour-list build.
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dem {

// Resizes v to n; when it must grow, reserves an eighth more. A pair count that creeps up from
// one build to the next then does not reallocate (and fault in) the whole array each time.
template <class T>
void ResizeWithRoom(std::vector<T>& v, size_t n) {
  if (n > v.capacity()) v.reserve(n + n / 8);
  v.resize(n);
}

// Asks the kernel to back a large array with 2 MB pages (transparent huge pages, which Debian
// gives only on request): the full-scale bed's arrays span thousands of 4 KB pages, more than
// the TLB holds. MADV_COLLAPSE (Linux 6.1) merges the pages already there at once; a second call
// on a merged range finds nothing to do. Arrays under 4 MB are left alone (no memory cost on
// small beds). Advice only: a kernel that refuses changes nothing but the speed.
template <class T>
void AdviseHugePages(const std::vector<T>& v) {
  constexpr uintptr_t kHuge = uintptr_t{2} << 20;
  const size_t bytes = v.capacity() * sizeof(T);
  if (bytes < (size_t{4} << 20)) return;
  const uintptr_t lo = (reinterpret_cast<uintptr_t>(v.data()) + kHuge - 1) & ~(kHuge - 1);
  const uintptr_t hi = (reinterpret_cast<uintptr_t>(v.data()) + bytes) & ~(kHuge - 1);
  if (hi <= lo) return;
  void* const at = reinterpret_cast<void*>(lo);
  madvise(at, hi - lo, MADV_HUGEPAGE);
#ifdef MADV_COLLAPSE
  madvise(at, hi - lo, MADV_COLLAPSE);
#endif
}

}  // namespace dem
