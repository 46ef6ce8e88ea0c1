// Neighbour search against an O(N^2) brute-force oracle (STYLE.md habit 11).
#include "dem/neighbor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <utility>

#include "dem/insertion.h"

namespace dem {
namespace {

struct Cloud {
  std::vector<Vec3> x;
  std::vector<double> r;
};

// Random polydisperse spheres (overlaps allowed), some outside the grid box to exercise clamping.
Cloud RandomCloud(int n, uint64_t seed, double r_min, double r_max) {
  Rng rng(seed);
  Cloud c;
  for (int i = 0; i < n; ++i) {
    c.x.push_back({rng.Uniform(-0.002, 0.032), rng.Uniform(0, 0.02), rng.Uniform(0, 0.01)});
    c.r.push_back(rng.Uniform(r_min, r_max));
  }
  return c;
}

// With sleeping, each slab stores its awake particles first (NeighborList::ComputeOrder); the list
// must not depend on that: seeds 4-6 mark a random 40% asleep.
TEST(NeighborTest, HalfListEqualsBruteForce) {
  for (uint64_t seed : {1u, 2u, 3u, 4u, 5u, 6u}) {
    const double r_min = 2e-4, r_max = 1e-3, skin = 2.5e-4;
    Cloud c = RandomCloud(3000, seed, r_min, r_max);
    std::vector<uint8_t> awake(c.x.size(), 1);
    Rng flags(100 + seed);
    if (seed > 3)
      for (uint8_t& a : awake) a = flags.Uniform(0, 1) < 0.6;
    NeighborList list;
    list.SetupGrid({0, 0, 0}, {0.03, 0.02, 0.01}, 2 * r_max + skin, c.x.size());
    std::vector<int32_t> visit(c.x.size()), perm;
    for (size_t i = 0; i < visit.size(); ++i) visit[i] = static_cast<int32_t>(i);
    list.ComputeOrder(c.x.data(), visit, &perm, 2, seed > 3 ? awake.data() : nullptr);
    for (int sl = 0; sl < list.num_slabs(); ++sl)
      for (int32_t i = list.slab_start[sl] + 1; i < list.slab_start[sl + 1]; ++i)
        ASSERT_GE(awake[perm[i - 1]], awake[perm[i]]) << "slab " << sl << ": awake ones first";
    Cloud s;  // sorted copy
    for (int32_t old : perm) {
      s.x.push_back(c.x[old]);
      s.r.push_back(c.r[old]);
    }
    list.Build(s.x.data(), s.r.data(), s.x.size(), skin, 2);

    // Oracle: every pair closer than r_i + r_j + skin, by original index.
    std::set<std::pair<int, int>> expected, found;
    for (size_t i = 0; i < c.x.size(); ++i)
      for (size_t j = i + 1; j < c.x.size(); ++j) {
        const double reach = c.r[i] + c.r[j] + skin;
        if (Norm2(c.x[i] - c.x[j]) < reach * reach)
          expected.insert({static_cast<int>(i), static_cast<int>(j)});
      }
    for (size_t i = 0; i + 1 < list.start.size(); ++i)
      for (int32_t k = list.start[i]; k < list.start[i + 1]; ++k) {
        const int32_t j = list.partner[k];
        ASSERT_GT(j, static_cast<int32_t>(i)) << "half list stores j > i";
        if (k > list.start[i]) {
          ASSERT_GT(j, list.partner[k - 1]) << "partners ascending";
        }
        const int a = perm[i], b = perm[j];
        EXPECT_TRUE(found.insert({std::min(a, b), std::max(a, b)}).second) << "pair listed twice";
      }
    EXPECT_GT(expected.size(), 1000u);
    EXPECT_EQ(found, expected) << "seed " << seed;
  }
}

// The list of a cloud sorted and built over its own bounding box, as System::Rebuild does, as a set
// of pairs of original indices; pairs of one group (group[i] == group[j] >= 0) left out when a
// group is given.
std::set<std::pair<int, int>> BuildPairs(const Cloud& c, double r_max, double skin,
                                         const std::vector<int32_t>* group) {
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const Vec3& x : c.x) {
    lo = {std::min(lo.x, x.x), std::min(lo.y, x.y), std::min(lo.z, x.z)};
    hi = {std::max(hi.x, x.x), std::max(hi.y, x.y), std::max(hi.z, x.z)};
  }
  NeighborList list;
  list.SetupGrid(lo, hi, 2 * r_max + skin, c.x.size());
  std::vector<int32_t> visit(c.x.size()), perm;
  for (size_t i = 0; i < visit.size(); ++i) visit[i] = static_cast<int32_t>(i);
  list.ComputeOrder(c.x.data(), visit, &perm);
  Cloud s;
  std::vector<int32_t> g;
  for (int32_t old : perm) {
    s.x.push_back(c.x[old]);
    s.r.push_back(c.r[old]);
    if (group) g.push_back((*group)[old]);
  }
  list.Build(s.x.data(), s.r.data(), s.x.size(), skin, 2, group ? g.data() : nullptr);
  std::set<std::pair<int, int>> found;
  for (size_t i = 0; i + 1 < list.start.size(); ++i)
    for (int32_t k = list.start[i]; k < list.start[i + 1]; ++k) {
      const int a = perm[i], b = perm[list.partner[k]];
      found.insert({std::min(a, b), std::max(a, b)});
    }
  return found;
}

std::set<std::pair<int, int>> BrutePairs(const Cloud& c, double skin,
                                         const std::vector<int32_t>* group) {
  std::set<std::pair<int, int>> expected;
  for (size_t i = 0; i < c.x.size(); ++i)
    for (size_t j = i + 1; j < c.x.size(); ++j) {
      const double reach = c.r[i] + c.r[j] + skin;
      const bool same = group && (*group)[i] >= 0 && (*group)[i] == (*group)[j];
      if (!same && Norm2(c.x[i] - c.x[j]) < reach * reach)
        expected.insert({static_cast<int>(i), static_cast<int>(j)});
    }
  return expected;
}

// A flat layer (all centres within less than one cutoff in z, as a layer resting on a floor):
// the cells must still be at least one cutoff wide along x and y.
TEST(NeighborTest, FlatLayerEqualsBruteForce) {
  const double r = 1e-3, skin = 2.5e-4;
  Rng rng(5);
  Cloud c;
  for (int i = 0; i < 800; ++i) {
    c.x.push_back({rng.Uniform(0, 0.04), rng.Uniform(0, 0.04), r + rng.Uniform(0, 0.5 * r)});
    c.r.push_back(r);
  }
  const auto expected = BrutePairs(c, skin, nullptr);
  EXPECT_GT(expected.size(), 300u);
  EXPECT_EQ(BuildPairs(c, r, skin, nullptr), expected);
}

// With groups (the spheres of one rigid clump), pairs within a group are left out, all others kept.
TEST(NeighborTest, PairsWithinAGroupAreLeftOut) {
  const double r_max = 1e-3, skin = 2.5e-4;
  const Cloud c = RandomCloud(2000, 9, 3e-4, r_max);
  std::vector<int32_t> group(c.x.size());
  for (size_t i = 0; i < group.size(); ++i)
    group[i] = i % 5 == 0 ? -1 : static_cast<int32_t>(i / 3);
  const auto expected = BrutePairs(c, skin, &group);
  EXPECT_LT(expected.size(), BrutePairs(c, skin, nullptr).size());
  EXPECT_EQ(BuildPairs(c, r_max, skin, &group), expected);
}

// The property the parallel force loop relies on: a pair's partner lies in the owner's slab or the
// next one.
TEST(NeighborTest, PartnersLieInOwnOrNextSlab) {
  const double r = 1e-3, skin = 2.5e-4;
  Cloud c = RandomCloud(4000, 7, r, r);
  NeighborList list;
  list.SetupGrid({0, 0, 0}, {0.03, 0.02, 0.01}, 2 * r + skin, c.x.size());
  std::vector<int32_t> visit(c.x.size()), perm;
  for (size_t i = 0; i < visit.size(); ++i) visit[i] = static_cast<int32_t>(i);
  list.ComputeOrder(c.x.data(), visit, &perm);
  Cloud s;
  for (int32_t old : perm) {
    s.x.push_back(c.x[old]);
    s.r.push_back(c.r[old]);
  }
  list.Build(s.x.data(), s.r.data(), s.x.size(), skin, 1);
  ASSERT_GT(list.num_slabs(), 4);
  auto slab_of = [&](int32_t i) {
    return static_cast<int>(std::upper_bound(list.slab_start.begin(), list.slab_start.end(), i) -
                            list.slab_start.begin()) -
           1;
  };
  for (size_t i = 0; i + 1 < list.start.size(); ++i)
    for (int32_t k = list.start[i]; k < list.start[i + 1]; ++k) {
      const int d = slab_of(list.partner[k]) - slab_of(static_cast<int32_t>(i));
      EXPECT_TRUE(d == 0 || d == 1) << "slab distance " << d;
    }
}

}  // namespace
}  // namespace dem
