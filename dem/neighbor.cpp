#include "dem/neighbor.h"

#include <algorithm>
#include <cmath>

#include "dem/internal_grow.h"

namespace dem {

NeighborList::Grid NeighborList::MakeGrid(const Vec3& lo, const Vec3& hi, double cutoff, size_t n) {
  Grid g;
  g.lo = lo;
  double cell = cutoff;
  const double ext[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
  int cells[3];
  const double max_cells = 4.0 * static_cast<double>(n) + 4096.0;
  for (;;) {
    double total = 1;
    for (int a = 0; a < 3; ++a) {
      cells[a] = std::max(1, static_cast<int>(std::floor(ext[a] / cell)));
      total *= cells[a];
    }
    if (total <= max_cells) break;
    cell *= 1.25;
  }
  // Cells are ext/cells wide along each axis (>= cell, except along an axis the particles span
  // less than one cell: one cell there, narrower); use one width for all axes: the smallest, but
  // never below `cell`, or a flat layer would get cells narrower than the cutoff and lose pairs.
  double width = ext[0] / cells[0];
  for (int a = 1; a < 3; ++a) width = std::min(width, ext[a] / cells[a]);
  width = std::max(width, cell);
  g.inv_cell = 1.0 / width;
  // Slab axis: the one with most cells, so that there are many slabs to share between threads.
  int order[3] = {0, 1, 2};
  std::stable_sort(order, order + 3, [&](int a, int b) { return cells[a] > cells[b]; });
  for (int k = 0; k < 3; ++k) {
    g.axis[k] = order[k];
    g.n[k] = std::max(1, static_cast<int>(std::floor(ext[order[k]] * g.inv_cell)));
  }
  return g;
}

void NeighborList::SetupGrid(const Vec3& lo, const Vec3& hi, double cutoff, size_t n) {
  const Grid g = MakeGrid(lo, hi, cutoff, n);
  lo_ = g.lo;
  inv_cell_ = g.inv_cell;
  for (int k = 0; k < 3; ++k) {
    n_[k] = g.n[k];
    axis_[k] = g.axis[k];
  }
  // Two halves per slab (awake first, then asleep: see ComputeOrder).
  cell_start_.assign(2 * static_cast<size_t>(n_[0]) * n_[1] * n_[2] + 1, 0);
  count_.assign(cell_start_.size() - 1, 0);
}

bool NeighborList::SameGrid(const Vec3& lo, const Vec3& hi, double cutoff, size_t n) const {
  if (cell_start_.empty() || slab_start.size() != static_cast<size_t>(n_[0]) + 1) return false;
  const Grid g = MakeGrid(lo, hi, cutoff, n);
  bool same = g.lo.x == lo_.x && g.lo.y == lo_.y && g.lo.z == lo_.z && g.inv_cell == inv_cell_;
  for (int k = 0; k < 3; ++k) same = same && g.n[k] == n_[k] && g.axis[k] == axis_[k];
  return same;
}

bool NeighborList::Regrid(const Vec3& lo, const Vec3& hi, double cutoff, size_t n, const Vec3* x,
                          const uint8_t* awake, std::vector<int64_t>* key, int num_threads) {
  if (cell_start_.empty() || slab_start.size() != static_cast<size_t>(n_[0]) + 1) return false;
  const Grid g = MakeGrid(lo, hi, cutoff, n);
  if (g.axis[0] != axis_[0] || g.n[0] != n_[0]) return false;
  SetupGrid(lo, hi, cutoff, n);
  const int64_t count = static_cast<int64_t>(n);
  key->resize(n);
  int64_t* k = key->data();
#pragma omp parallel for schedule(static) num_threads(num_threads)
  for (int64_t i = 0; i < count; ++i) k[i] = SortKey(x[i], awake != nullptr && !awake[i]);
  StartsFromKeys(k, count);
  return true;
}

void NeighborList::StartsFromKeys(const int64_t* key, int64_t n) {
  std::fill(count_.begin(), count_.end(), 0);
  for (int64_t i = 0; i < n; ++i) ++count_[key[i]];
  int32_t sum = 0;
  for (size_t k = 0; k < count_.size(); ++k) {
    cell_start_[k] = sum;
    sum += count_[k];
  }
  cell_start_.back() = sum;
  // Slab ranges: slab s holds sort keys [2 s n1 n2, 2 (s + 1) n1 n2).
  const int64_t per_slab = static_cast<int64_t>(n_[1]) * n_[2];
  slab_start.resize(n_[0] + 1);
  for (int s = 0; s <= n_[0]; ++s) slab_start[s] = cell_start_[2 * s * per_slab];
}

void NeighborList::SlabSpan(const Vec3& lo, const Vec3& hi, int* first, int* last) const {
  // CellAlong(0, .) is a non-decreasing function of the slab-axis coordinate.
  *first = std::isfinite(lo[axis_[0]]) ? CellAlong(0, lo) : 0;
  *last = std::isfinite(hi[axis_[0]]) ? CellAlong(0, hi) : n_[0] - 1;
}

void NeighborList::ComputeOrder(const Vec3* x, const std::vector<int32_t>& visit,
                                std::vector<int32_t>* perm, int num_threads, const uint8_t* awake) {
  const int64_t n = static_cast<int64_t>(visit.size());
  std::vector<int64_t> key(n);
#pragma omp parallel for schedule(static) num_threads(num_threads)
  for (int64_t i = 0; i < n; ++i)
    key[i] = SortKey(x[visit[i]], awake != nullptr && !awake[visit[i]]);
  // Counting sort, stable in visit order.
  StartsFromKeys(key.data(), n);
  perm->resize(n);
  std::vector<int32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (int64_t i = 0; i < n; ++i) (*perm)[fill[key[i]]++] = visit[i];
}

bool NeighborList::ComputeOrderSlabs(const Vec3* x, const std::vector<int32_t>& visit, int s0,
                                     int s1, int32_t* perm, const uint8_t* awake) {
  const int64_t per_slab = static_cast<int64_t>(n_[1]) * n_[2];
  const int64_t key_lo = 2 * s0 * per_slab, key_hi = 2 * (s1 + 1) * per_slab;
  const int32_t base = slab_start[s0];
  if (static_cast<int64_t>(visit.size()) != slab_start[s1 + 1] - base) return false;
  std::vector<int64_t>& key = key_;
  key.resize(visit.size());
  for (size_t i = 0; i < visit.size(); ++i) {
    key[i] = SortKey(x[visit[i]], awake != nullptr && !awake[visit[i]]);
    if (key[i] < key_lo || key[i] >= key_hi) return false;  // left the slabs: a full build
  }
  // Counting sort of the slabs' keys (the others keep their counts and starts), stable in visit
  // order: the order ComputeOrder gives these particles. (count_ is scratch: a restored list
  // has none.)
  count_.resize(cell_start_.size() - 1);
  std::fill(count_.begin() + key_lo, count_.begin() + key_hi, 0);
  for (const int64_t k : key) ++count_[k];
  int32_t sum = base;
  for (int64_t k = key_lo; k < key_hi; ++k) {
    cell_start_[k] = sum;
    sum += count_[k];
  }
  std::vector<int32_t> fill(cell_start_.begin() + key_lo, cell_start_.begin() + key_hi);
  for (size_t i = 0; i < visit.size(); ++i) perm[fill[key[i] - key_lo]++ - base] = visit[i];
  for (int s = s0 + 1; s <= s1; ++s) slab_start[s] = cell_start_[2 * s * per_slab];
  return true;
}

void NeighborList::BuildSlabs(const Vec3* x, const double* radius, double skin, int num_threads,
                              const int32_t* group, int slab_first, int slab_last) {
  const int num_slabs = n_[0];
  const int n1 = n_[1], n2 = n_[2];
  slab_partner_.resize(num_slabs);
  slab_count_.resize(num_slabs);
  // The pairs of i with larger storage indices: its own cell after it and the cells that come
  // later in storage order within reach. In (slab, half, second, third) offsets those are runs
  // of consecutive cells, each a contiguous range of particles, listed here in storage order so
  // that each particle's partners come out ascending (the first run starts after i):
  // - awake i: (0, awake, 0, 0..1), (0, awake, 1, -1..1), the asleep half of its own slab
  //   (0, asleep, -1..1, -1..1), and both halves of the next slab (1, *, -1..1, -1..1);
  // - asleep i: (0, asleep, 0, 0..1), (0, asleep, 1, -1..1), and the next slab's halves.
  // Without sleepers this is the usual forward half stencil of 13 cells and the own cell.
  struct RunSpec {
    int ds, half, db, dc_lo;  // slab offset, half (kOwnHalf: the particle's), row, first column
  };
  constexpr int kOwnHalf = -1;
  static constexpr RunSpec kRuns[11] = {
      {0, kOwnHalf, 0, 0}, {0, kOwnHalf, 1, -1},                  // own half, later cells
      {0, 1, -1, -1},      {0, 1, 0, -1},        {0, 1, 1, -1},   // own slab's asleep half
      {1, 0, -1, -1},      {1, 0, 0, -1},        {1, 0, 1, -1},   // next slab, awake half
      {1, 1, -1, -1},      {1, 1, 0, -1},        {1, 1, 1, -1}};  // next slab, asleep half
  const auto cell_of = [&](int slab, int half, int b, int c) {
    return ((static_cast<int64_t>(2 * slab + half)) * n1 + b) * n2 + c;
  };
#pragma omp parallel for schedule(dynamic, 1) num_threads(num_threads)
  for (int s = slab_first; s <= slab_last; ++s) {
    std::vector<int32_t>& out = slab_partner_[s];
    std::vector<int32_t>& cnt = slab_count_[s];
    cnt.clear();
    size_t used = 0;
    for (int h = 0; h < 2; ++h)
      for (int c1 = 0; c1 < n1; ++c1)
        for (int c2 = 0; c2 < n2; ++c2) {
          const int64_t cell = cell_of(s, h, c1, c2);
          const int32_t first = cell_start_[cell], last = cell_start_[cell + 1];
          if (first == last) continue;
          int32_t lo[11], hi[11];
          int runs = 0;
          for (int r = 0; r < 11; ++r) {
            if (h == 1 && r >= 2 && r < 5) continue;  // an asleep i lies in that half itself
            const RunSpec& rs = kRuns[r];
            const int a = s + rs.ds, b = c1 + rs.db, half = rs.half == kOwnHalf ? h : rs.half;
            if (a >= n_[0] || b < 0 || b >= n1) continue;
            lo[runs] = cell_start_[cell_of(a, half, b, std::max(c2 + rs.dc_lo, 0))];
            hi[runs] = cell_start_[cell_of(a, half, b, std::min(c2 + 1, n2 - 1)) + 1];
            ++runs;
          }
          for (int32_t i = first; i < last; ++i) {
            // Every candidate is written at `used`, which advances only for a pair (no branch on
            // the outcome, a coin toss for the predictor).
            size_t candidates = 0;
            for (int r = 0; r < runs; ++r) candidates += hi[r] - (r == 0 ? i + 1 : lo[r]);
            if (used + candidates > out.size()) out.resize(2 * (used + candidates));
            int32_t* buf = out.data();
            const size_t before = used;
            const Vec3 xi = x[i];
            const double ri = radius[i];
            const bool grouped = group != nullptr && group[i] >= 0;
            for (int r = 0; r < runs; ++r)
              for (int32_t j = (r == 0 ? i + 1 : lo[r]); j < hi[r]; ++j) {
                const double reach = ri + radius[j] + skin;
                const bool pair = Norm2(x[j] - xi) < reach * reach;
                const bool same_clump = grouped && group[i] == group[j];
                buf[used] = j;
                used += pair && !same_clump;
              }
            cnt.push_back(static_cast<int32_t>(used - before));
          }
        }
    out.resize(used);
  }
}

void NeighborList::Build(const Vec3* x, const double* radius, size_t n, double skin,
                         int num_threads, const int32_t* group) {
  const int num_slabs = n_[0];
  BuildSlabs(x, radius, skin, num_threads, group, 0, num_slabs - 1);
  // Concatenate the slabs in order (deterministic); each slab's part of the list starts at the
  // sum of the slabs before it.
  start.resize(n + 1);
  std::vector<size_t> slab_offset(num_slabs + 1, 0);
  for (int s = 0; s < num_slabs; ++s) slab_offset[s + 1] = slab_offset[s] + slab_partner_[s].size();
  ResizeWithRoom(partner, slab_offset[num_slabs]);
#pragma omp parallel for schedule(dynamic, 1) num_threads(num_threads)
  for (int s = 0; s < num_slabs; ++s) {
    size_t k = 0;
    int32_t offset = static_cast<int32_t>(slab_offset[s]);
    for (int32_t i = slab_start[s]; i < slab_start[s + 1]; ++i) {
      start[i] = offset;
      const int32_t c = slab_count_[s][i - slab_start[s]];
      std::copy(slab_partner_[s].begin() + k, slab_partner_[s].begin() + k + c,
                partner.begin() + offset);
      k += c;
      offset += c;
    }
  }
  start[n] = static_cast<int32_t>(slab_offset[num_slabs]);
}

}  // namespace dem
