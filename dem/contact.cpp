#include "dem/contact.h"

#include <cassert>
#include <map>
#include <mutex>

namespace dem {

namespace {

// Right-hand side of the nondimensional Hertz impact x'' = max(0, -x^(3/2) - zeta x^(1/4) x').
// Written as the force pushing the spheres apart (x is the overlap, v = x').
double Accel(double x, double v, double zeta) {
  if (x <= 0.0) return 0.0;
  const double q = std::sqrt(std::sqrt(x));  // x^(1/4)
  const double f = x * std::sqrt(x) + zeta * q * v;
  return -std::max(0.0, f);
}

}  // namespace

double RestitutionForBeta(double beta) {
  // RK4 on x'' = Accel(x, x'), starting at contact with unit approach speed; the collision lasts
  // about 3.2 time units. x^(1/4) is steep near x = 0, so the step is small throughout:
  // h = 1e-4 gives beta within 1e-6 (relative) of the h = 2e-5 result.
  const double zeta = std::sqrt(5.0) * beta;
  const double h = 1e-4;
  double x = 0.0, v = 1.0;
  for (int step = 0; step < 10'000'000; ++step) {
    const double k1x = v, k1v = Accel(x, v, zeta);
    const double k2x = v + 0.5 * h * k1v, k2v = Accel(x + 0.5 * h * k1x, k2x, zeta);
    const double k3x = v + 0.5 * h * k2v, k3v = Accel(x + 0.5 * h * k2x, k3x, zeta);
    const double k4x = v + h * k3v, k4v = Accel(x + h * k3x, k4x, zeta);
    const double nx = x + h / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x);
    const double nv = v + h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v);
    if (nx <= 0.0 && step > 0) {
      // Separation inside this step: the force near x = 0 is tiny, interpolate v linearly.
      const double frac = x / (x - nx);
      return -(v + frac * (nv - v));
    }
    x = nx;
    v = nv;
  }
  return 0.0;  // never separated (overdamped)
}

double BetaForRestitution(double e) {
  assert(e > 0.0 && e <= 1.0);
  if (e >= 1.0) return 0.0;
  // Each solve takes ~50 ms; scenes reuse a handful of restitution values, so cache them.
  static std::mutex mutex;
  static std::map<double, double> cache;
  {
    std::lock_guard<std::mutex> lock(mutex);
    auto it = cache.find(e);
    if (it != cache.end()) return it->second;
  }
  // RestitutionForBeta decreases monotonically; bracket and bisect.
  double lo = 0.0, hi = 0.1;
  while (RestitutionForBeta(hi) > e) hi *= 2.0;
  for (int it = 0; it < 60 && hi - lo > 1e-12; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (RestitutionForBeta(mid) > e)
      lo = mid;
    else
      hi = mid;
  }
  const double beta = 0.5 * (lo + hi);
  std::lock_guard<std::mutex> lock(mutex);
  cache[e] = beta;
  return beta;
}

double DampingBeta(const Interaction& i) {
  return i.damping == DampingLaw::kStandard ? StandardBeta(i.restitution)
                                            : BetaForRestitution(i.restitution);
}

PairConstants MakePairConstants(const Material& a, const Material& b, const Interaction& i) {
  PairConstants c;
  const double ea = a.YoungsModulus(), eb = b.YoungsModulus();
  c.e_star = 1.0 / ((1 - a.poisson * a.poisson) / ea + (1 - b.poisson * b.poisson) / eb);
  c.g_star = 1.0 / ((2 - a.poisson) / a.shear_modulus + (2 - b.poisson) / b.shear_modulus);
  c.damp = 2.0 * std::sqrt(5.0 / 6.0) * DampingBeta(i);
  c.tangential_ratio = std::sqrt(4.0 * c.g_star / c.e_star);
  c.friction = i.friction;
  c.rolling_friction = i.rolling_friction;
  c.rolling_model = i.rolling_model;
  return c;
}

}  // namespace dem
