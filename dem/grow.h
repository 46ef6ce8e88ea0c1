// Resizing the large per-pair arrays that are made again at every neighbour-list build.
#pragma once

#include <cstddef>
#include <vector>

namespace dem {

// Resizes v to n; when it must grow, reserves an eighth more. A pair count that creeps up from
// one build to the next then does not reallocate (and fault in) the whole array each time.
template <class T>
void ResizeWithRoom(std::vector<T>& v, size_t n) {
  if (n > v.capacity()) v.reserve(n + n / 8);
  v.resize(n);
}

}  // namespace dem
