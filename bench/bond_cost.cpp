// The bond phase's cost per bond-step (dem/bond.h) on a bonded bed: a 28 x 28 x 26 simple cubic
// lattice of touching 7 mm snow spheres (20,384; ids shuffled in space, as a pour leaves them) on
// a floor, bonded to its axis neighbours (58,912 bonds, unbreakable, damping 0.1), gravity 1.3
// m/s^2, 200 steps of warm-up then 1000 timed at half BondCriticalStep. Prints one JSON line:
// ms a step, ms of it in the bond phase (PhaseTimes::bonds), ns a bond-step, ms in the pairs.
// Not part of the CMake build (it links the dem library alone):
//   g++ -O1 -std=c++17 -fopenmp -I. bench/bond_cost.cpp build/dem/libdem.a -o /tmp/bond_cost
//   /tmp/bond_cost THREADS BONDED(1|0)
// (-O1: GCC 12.2 stops with an internal compiler error at -O2 on a file of this shape.)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>

#include "dem/system.h"
using namespace dem;
int main(int argc, char** argv) {
  const int threads = argc > 1 ? atoi(argv[1]) : 1;
  const bool bonded = argc > 2 ? atoi(argv[2]) : 1;
  const int steps = 1000;
  const double r = 3.5e-3;
  MaterialTable t;
  t.Add({"snow", 300.0, 1e7, 0.36});
  t.SetInteraction(0, 0, {0.5, 0.5, 0.0});
  BondParams b;
  b.modulus = 1e8;
  b.stiffness_ratio = 2;
  b.tensile_strength = 1e12;
  b.cohesion = 1e12;
  b.damping_ratio = 0.1;
  SystemConfig c;
  c.gravity = {0, 0, -1.3};
  c.time_step = 0.5 * BondCriticalStep(r, 300, b);
  c.skin = 1.75e-3;
  c.domain_min = {-0.1, -0.1, -0.1};
  c.domain_max = {0.5, 0.5, 0.5};
  c.planes.push_back(Plane{"floor", {0, 0, -r}, {0, 0, 1}, 0});
  System s(t, c);
  s.set_num_threads(threads);
  const int nx = 28, ny = 28, nz = 26;
  const double sp = 2 * r;
  std::vector<int> order(nx * ny * nz);
  std::iota(order.begin(), order.end(), 0);
  std::mt19937 g(5);
  std::shuffle(order.begin(), order.end(), g);  // ids random in space, as a pour's
  for (int o : order) {
    int i = o % nx, j = (o / nx) % ny, k = o / (nx * ny);
    s.AddParticle({i * sp, j * sp, k * sp}, {}, {}, r, 0);
  }
  if (bonded) {
    std::vector<Bond> bs;
    for (auto& pr : s.PairsWithinGap(0.05 * r))
      bs.push_back(MakeBond(pr.first, r, pr.second, r, sp, b));
    s.AddBonds(bs);
  }
  for (int k = 0; k < 200; k++) s.Step();
  const PhaseTimes p0 = s.phase_times();
  auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < steps; k++) s.Step();
  double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const PhaseTimes p1 = s.phase_times();
  const double nb = (double)s.intact_bond_count();
  printf(
      "{\"threads\":%d,\"particles\":%zu,\"bonds\":%.0f,\"ms_per_step\":%.4f,\"ms_bonds\":%.4f,"
      "\"ns_per_bond_step\":%.2f,\"ms_pairs\":%.4f}\n",
      threads, s.particles().size(), nb, 1e3 * wall / steps, 1e3 * (p1.bonds - p0.bonds) / steps,
      nb > 0 ? 1e9 * (p1.bonds - p0.bonds) / steps / nb : 0.0, 1e3 * (p1.pairs - p0.pairs) / steps);
}
