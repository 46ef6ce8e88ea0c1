#include "dem/neighbor.h"

#include <algorithm>
#include <cmath>

namespace dem {

void NeighborList::SetupGrid(const Vec3& lo, const Vec3& hi, double cutoff, size_t n) {
  lo_ = lo;
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
  inv_cell_ = 1.0 / width;
  // Slab axis: the one with most cells, so that there are many slabs to share between threads.
  int order[3] = {0, 1, 2};
  std::stable_sort(order, order + 3, [&](int a, int b) { return cells[a] > cells[b]; });
  for (int g = 0; g < 3; ++g) {
    axis_[g] = order[g];
    n_[g] = std::max(1, static_cast<int>(std::floor(ext[order[g]] * inv_cell_)));
  }
  cell_start_.assign(static_cast<size_t>(n_[0]) * n_[1] * n_[2] + 1, 0);
  count_.assign(cell_start_.size() - 1, 0);
}

int64_t NeighborList::CellKey(const Vec3& x, int c[3]) const {
  for (int g = 0; g < 3; ++g) {
    // Clamp: particles outside the grid share its boundary cells (still correct, only slower).
    const double u = (x[axis_[g]] - lo_[axis_[g]]) * inv_cell_;
    int k = std::isfinite(u) ? static_cast<int>(std::floor(std::clamp(u, -1.0, 1e9))) : 0;
    c[g] = std::clamp(k, 0, n_[g] - 1);
  }
  return (static_cast<int64_t>(c[0]) * n_[1] + c[1]) * n_[2] + c[2];
}

void NeighborList::ComputeOrder(const Vec3* x, const std::vector<int32_t>& visit,
                                std::vector<int32_t>* perm) {
  const size_t n = visit.size();
  std::vector<int64_t> key(n);
  int c[3];
  std::fill(count_.begin(), count_.end(), 0);
  for (size_t i = 0; i < n; ++i) {
    key[i] = CellKey(x[visit[i]], c);
    ++count_[key[i]];
  }
  // Counting sort, stable in visit order.
  int32_t sum = 0;
  for (size_t k = 0; k < count_.size(); ++k) {
    cell_start_[k] = sum;
    sum += count_[k];
  }
  cell_start_.back() = sum;
  perm->resize(n);
  key_.resize(n);
  std::vector<int32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (size_t i = 0; i < n; ++i) {
    const int32_t dst = fill[key[i]]++;
    (*perm)[dst] = visit[i];
    key_[dst] = key[i];
  }
  // Slab ranges: slab s holds cells [s * n1 * n2, (s + 1) * n1 * n2).
  const int64_t per_slab = static_cast<int64_t>(n_[1]) * n_[2];
  slab_start.resize(n_[0] + 1);
  for (int s = 0; s <= n_[0]; ++s) slab_start[s] = cell_start_[s * per_slab];
}

void NeighborList::Build(const Vec3* x, const double* radius, size_t n, double skin,
                         int num_threads, const int32_t* group) {
  const int num_slabs = n_[0];
  slab_partner_.resize(num_slabs);
  slab_count_.resize(num_slabs);
  // Forward half stencil: the 13 neighbour cells with a larger key, plus the own cell (j > i).
  int stencil[14][3];
  int ns = 0;
  for (int da = 0; da <= 1; ++da)
    for (int db = -1; db <= 1; ++db)
      for (int dc = -1; dc <= 1; ++dc) {
        if (da == 0 && (db < 0 || (db == 0 && dc < 0))) continue;
        stencil[ns][0] = da;
        stencil[ns][1] = db;
        stencil[ns][2] = dc;
        ++ns;
      }

#pragma omp parallel for schedule(dynamic, 1) num_threads(num_threads)
  for (int s = 0; s < num_slabs; ++s) {
    std::vector<int32_t>& out = slab_partner_[s];
    std::vector<int32_t>& cnt = slab_count_[s];
    out.clear();
    cnt.clear();
    for (int32_t i = slab_start[s]; i < slab_start[s + 1]; ++i) {
      const int64_t key = key_[i];
      const int c0 = static_cast<int>(key / (static_cast<int64_t>(n_[1]) * n_[2]));
      const int c1 = static_cast<int>((key / n_[2]) % n_[1]);
      const int c2 = static_cast<int>(key % n_[2]);
      const size_t before = out.size();
      for (int t = 0; t < ns; ++t) {
        const int a = c0 + stencil[t][0], b = c1 + stencil[t][1], c = c2 + stencil[t][2];
        if (a >= n_[0] || b < 0 || b >= n_[1] || c < 0 || c >= n_[2]) continue;
        const int64_t cell = (static_cast<int64_t>(a) * n_[1] + b) * n_[2] + c;
        const int32_t first = (t == 0) ? i + 1 : cell_start_[cell];
        for (int32_t j = first; j < cell_start_[cell + 1]; ++j) {
          const double reach = radius[i] + radius[j] + skin;
          if (Norm2(x[j] - x[i]) < reach * reach &&
              (group == nullptr || group[i] < 0 || group[i] != group[j]))
            out.push_back(j);
        }
      }
      cnt.push_back(static_cast<int32_t>(out.size() - before));
    }
  }
  // Concatenate the slabs in order (deterministic), partners sorted within each particle; each
  // slab's part of the list starts at the sum of the slabs before it.
  start.resize(n + 1);
  std::vector<size_t> slab_offset(num_slabs + 1, 0);
  for (int s = 0; s < num_slabs; ++s) slab_offset[s + 1] = slab_offset[s] + slab_partner_[s].size();
  partner.resize(slab_offset[num_slabs]);
#pragma omp parallel for schedule(dynamic, 1) num_threads(num_threads)
  for (int s = 0; s < num_slabs; ++s) {
    size_t k = 0;
    int32_t offset = static_cast<int32_t>(slab_offset[s]);
    for (int32_t i = slab_start[s]; i < slab_start[s + 1]; ++i) {
      start[i] = offset;
      const int32_t c = slab_count_[s][i - slab_start[s]];
      std::copy(slab_partner_[s].begin() + k, slab_partner_[s].begin() + k + c,
                partner.begin() + offset);
      std::sort(partner.begin() + offset, partner.begin() + offset + c);
      k += c;
      offset += c;
    }
  }
  start[n] = static_cast<int32_t>(slab_offset[num_slabs]);
}

}  // namespace dem
