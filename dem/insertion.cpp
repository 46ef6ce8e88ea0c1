#include "dem/insertion.h"

#include <algorithm>
#include <cmath>

namespace dem {

std::vector<SphereSeed> InsertSpheres(const Vec3& lo, const Vec3& hi, int64_t count, double r_min,
                                      double r_max, double solid_fraction, Rng& rng) {
  std::vector<SphereSeed> out;
  // Mean sphere volume over the radius distribution relative to the largest sphere.
  const double mean_r3 =
      (std::pow(r_max, 4) - std::pow(r_min, 4)) / (4.0 * std::max(r_max - r_min, 1e-300));
  const double r3 = r_max > r_min ? mean_r3 : r_max * r_max * r_max;
  // Pitch a: one sphere of mean volume per a^3 gives the requested solid fraction.
  double a = std::cbrt(4.0 / 3.0 * M_PI * r3 / std::max(solid_fraction, 1e-6));
  a = std::max(a, 2.0 * r_max * (1.0 + 1e-9));
  const int nx = static_cast<int>(std::floor((hi.x - lo.x) / a));
  const int ny = static_cast<int>(std::floor((hi.y - lo.y) / a));
  const int nz = static_cast<int>(std::floor((hi.z - lo.z) / a));
  if (nx <= 0 || ny <= 0 || nz <= 0 || count <= 0) return out;
  // Centre the lattice in x and y.
  const double ox = lo.x + 0.5 * ((hi.x - lo.x) - nx * a) + 0.5 * a;
  const double oy = lo.y + 0.5 * ((hi.y - lo.y) - ny * a) + 0.5 * a;
  const double oz = lo.z + 0.5 * a;
  out.reserve(std::min<int64_t>(count, static_cast<int64_t>(nx) * ny * nz));
  std::vector<int> layer(static_cast<size_t>(nx) * ny);
  for (int k = 0; k < nz && static_cast<int64_t>(out.size()) < count; ++k) {
    // Shuffle the sites of this layer (Fisher-Yates with our RNG), so a partial top layer is
    // spread at random.
    for (size_t s = 0; s < layer.size(); ++s) layer[s] = static_cast<int>(s);
    for (size_t s = layer.size(); s > 1; --s) {
      const size_t r = static_cast<size_t>(rng.Next() % s);
      std::swap(layer[s - 1], layer[r]);
    }
    for (size_t s = 0; s < layer.size() && static_cast<int64_t>(out.size()) < count; ++s) {
      const int ix = layer[s] % nx, iy = layer[s] / nx;
      const double r = r_max > r_min ? rng.Uniform(r_min, r_max) : r_max;
      const double jitter = 0.5 * a - r;  // sphere stays inside its lattice cube
      Vec3 c{ox + ix * a, oy + iy * a, oz + k * a};
      c.x += rng.Uniform(-jitter, jitter);
      c.y += rng.Uniform(-jitter, jitter);
      c.z += rng.Uniform(-jitter, jitter);
      out.push_back({c, r});
    }
  }
  return out;
}

}  // namespace dem
