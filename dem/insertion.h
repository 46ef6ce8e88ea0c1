// Random non-overlapping insertion of spheres, with an RNG whose distribution code we own (so a
// seed gives the same bed on every platform and library version). Public header of the dem module.
#pragma once

#include <cstdint>
#include <vector>

#include "dem/vec3.h"

namespace dem {

// SplitMix64 (Steele, Lea & Flood 2014): small, fast, and fully specified here.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double Uniform(double a, double b) { return a + (b - a) * Uniform(); }
  uint64_t state() const { return state_; }  // Rng(state()) goes on with the same numbers

 private:
  uint64_t state_;
};

struct SphereSeed {
  Vec3 x;         // centre [m]
  double radius;  // [m]
};

// Places up to `count` spheres with radii uniform in [r_min, r_max] inside the box [lo, hi]
// (spheres entirely inside), none overlapping, at about `solid_fraction` (capped by what a jittered
// cubic lattice of pitch 2 r_max can hold, pi/6 ~ 0.52). Sites are lattice points of pitch
// a = 2 r_max (pi/6 / solid_fraction)^(1/3), each jittered by up to (a - 2 r) / 2, filled from the
// bottom (lowest z) up in a seeded random order within each layer. Returns fewer than `count`
// when the box is full.
std::vector<SphereSeed> InsertSpheres(const Vec3& lo, const Vec3& hi, int64_t count, double r_min,
                                      double r_max, double solid_fraction, Rng& rng);

}  // namespace dem
