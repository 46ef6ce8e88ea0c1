// Neighbour search: a uniform cell grid that orders particles for memory locality, and a half
// Verlet list (each pair once, stored with the lower storage index) built from it.
//
// Parallel, deterministic force accumulation rests on this layout: particles are sorted by slab
// (one axis, the one with most cells, varying slowest; within a slab by cell, awake particles
// first), and the cells are at least one cutoff wide. A pair (i, j > i) then has j in the slab of i
// or in the next one, so processing even slabs in parallel and then odd slabs never writes one
// particle from two threads, and the order in which forces add up is fixed by the data alone,
// whatever the thread count. Public header of the dem module.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "dem/vec3.h"

namespace dem {

class NeighborList {
 public:
  // Sets up the grid over [lo, hi] with cells at least `cutoff` wide (the largest pair distance
  // that must be found: 2 r_max + skin). Caps the cell count near 4 n + 4096 by widening cells.
  void SetupGrid(const Vec3& lo, const Vec3& hi, double cutoff, size_t n);

  // Whether SetupGrid(lo, hi, cutoff, n) would give the grid set up now (and ComputeOrder has
  // placed particles on it): then the slabs that no particle entered or left since can keep
  // their order and lists (ComputeOrderSlabs, BuildSlabs).
  bool SameGrid(const Vec3& lo, const Vec3& hi, double cutoff, size_t n) const;

  // Sets up the grid SetupGrid(lo, hi, cutoff, n) gives when it has the present grid's slab
  // axis and slab count, for particles stored as ComputeOrder left them on the present grid
  // (with moves since): each particle's sort key on the new grid into `key` (storage order), and
  // the cell and slab starts counted from those keys, as ComputeOrder makes them where the
  // storage order is the new grid's. Returns false, changing nothing, where the slab axis or
  // count differs (then only SetupGrid and a full order will do).
  bool Regrid(const Vec3& lo, const Vec3& hi, double cutoff, size_t n, const Vec3* x,
              const uint8_t* awake, std::vector<int64_t>* key, int num_threads);
  // The slab of a sort key of the present grid.
  int SlabOfKey(int64_t key) const {
    return static_cast<int>(key / (2 * static_cast<int64_t>(n_[1]) * n_[2]));
  }

  // The slab a particle at x falls into (positions outside the grid: its boundary slabs).
  int SlabOf(const Vec3& x) const { return CellAlong(0, x); }

  // Storage order for locality: perm[new_index] = old_index, sorted by slab, then (with `awake`,
  // one flag per particle) the awake particles before the sleeping ones, then by cell and, within
  // a cell, by the order in which `visit` lists the particles (pass them in persistent-id order
  // to make the result independent of the previous storage order). With sleeping, the awake
  // particles, the ones every step moves, then lie together in memory.
  void ComputeOrder(const Vec3* x, const std::vector<int32_t>& visit, std::vector<int32_t>* perm,
                    int num_threads = 1, const uint8_t* awake = nullptr);

  // ComputeOrder for the particles of slabs s0 .. s1 only, the others staying where they are:
  // `visit` lists those slabs' particles (their storage indices, in persistent-id order), perm
  // gets the new order of storage positions slab_start[s0] ... (perm[new - slab_start[s0]] =
  // old), and the slabs' cell and slab starts are made again. The order is the one ComputeOrder
  // would give them when every other particle keeps its sort key. Returns false, changing
  // nothing, when some particle's key lies outside the slabs (then only a full order will do).
  bool ComputeOrderSlabs(const Vec3* x, const std::vector<int32_t>& visit, int s0, int s1,
                         int32_t* perm, const uint8_t* awake);

  // Builds the half list for particles already stored in the order ComputeOrder gave:
  // pairs (i, j > i) with |x_i - x_j| < r_i + r_j + skin. With `group` (n entries), pairs with
  // group[i] == group[j] >= 0 are left out (spheres of one rigid clump never touch).
  void Build(const Vec3* x, const double* radius, size_t n, double skin, int num_threads,
             const int32_t* group = nullptr);

  // Build's first half, for slabs slab_first .. slab_last only: each slab's pairs into its own
  // buffer (slab_pairs: the partners of its particles one after another, slab_counts: how many
  // each has), which Build then joins into start and partner. The list of a slab depends on its
  // particles and the next slab's only.
  void BuildSlabs(const Vec3* x, const double* radius, double skin, int num_threads,
                  const int32_t* group, int slab_first, int slab_last);
  const std::vector<int32_t>& slab_pairs(int s) const { return slab_partner_[s]; }
  const std::vector<int32_t>& slab_counts(int s) const { return slab_count_[s]; }

  // The slabs that hold every particle whose position at the last ComputeOrder lay in the box
  // [lo, hi]: first .. last (inclusive). Only the slab axis matters; positions outside the grid
  // fall into its boundary slabs, as they do when sorted.
  void SlabSpan(const Vec3& lo, const Vec3& hi, int* first, int* last) const;

  size_t num_pairs() const { return partner.size(); }
  int num_slabs() const { return static_cast<int>(slab_start.size()) - 1; }

  std::vector<int32_t> start;       // CSR offsets into partner (n + 1)
  std::vector<int32_t> partner;     // j of each pair (num_pairs)
  std::vector<int32_t> slab_start;  // particle range of each slab (num_slabs + 1)

  // Lists every field that lasts from one build to the next to `archive` (dem/archive.h: saved
  // and restored by System::SaveState / RestoreState).
  template <typename Archive>
  void Fields(Archive& archive) {
    archive(start);
    archive(partner);
    archive(slab_start);
    archive(lo_);
    archive(inv_cell_);
    archive(n_);
    archive(axis_);
    archive(cell_start_);
  }

 private:
  struct Grid {
    Vec3 lo;
    double inv_cell = 0;
    int n[3] = {1, 1, 1}, axis[3] = {0, 1, 2};
  };
  static Grid MakeGrid(const Vec3& lo, const Vec3& hi, double cutoff, size_t n);
  // The cell and slab starts of n particles with these sort keys, stored in key order.
  void StartsFromKeys(const int64_t* key, int64_t n);
  // Cell index along grid axis g, clamped: particles outside the grid share its boundary cells
  // (still correct, only slower).
  int CellAlong(int g, const Vec3& x) const {
    const double u = (x[axis_[g]] - lo_[axis_[g]]) * inv_cell_;
    const int k = std::isfinite(u) ? static_cast<int>(std::floor(std::clamp(u, -1.0, 1e9))) : 0;
    return std::clamp(k, 0, n_[g] - 1);
  }
  [[gnu::always_inline]] int64_t CellKey(const Vec3& x, int c[3]) const {
    for (int g = 0; g < 3; ++g) c[g] = CellAlong(g, x);
    return (static_cast<int64_t>(c[0]) * n_[1] + c[1]) * n_[2] + c[2];
  }
  // The storage sort key of a particle at x (cell_start_'s index): its slab, then the awake half
  // or (asleep) the second, then its cell within the slab.
  [[gnu::always_inline]] int64_t SortKey(const Vec3& x, bool asleep) const {
    int c[3];
    const int64_t cell = CellKey(x, c);
    const int64_t per_slab = static_cast<int64_t>(n_[1]) * n_[2];
    return (2 * c[0] + (asleep ? 1 : 0)) * per_slab + (cell - c[0] * per_slab);
  }

  Vec3 lo_;
  double inv_cell_ = 0;
  int n_[3] = {1, 1, 1};             // cells along (slab axis, second axis, third axis)
  int axis_[3] = {0, 1, 2};          // world axis of each grid axis
  std::vector<int32_t> cell_start_;  // first particle of each sort key (2 num_cells + 1):
                                     // (slab, awake then asleep half, second, third axis)
  std::vector<int32_t> count_;       // scratch (2 num_cells)
  std::vector<int64_t> key_;         // scratch (ComputeOrderSlabs)
  std::vector<std::vector<int32_t>> slab_partner_;  // per-slab build buffers
  std::vector<std::vector<int32_t>> slab_count_;
};

}  // namespace dem
