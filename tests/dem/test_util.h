// Shared helpers for the dem tests: materials from paper Table 6 and small systems.
#pragma once

#include <gtest/gtest.h>

#include <cmath>

#include "dem/system.h"

namespace dem::test {

// Paper Table 6 snow: G 1e7 Pa, nu 0.36, rho 300 kg/m3.
inline Material Snow() { return {"snow", 300.0, 1.0e7, 0.36}; }
// A stiff wall material (steel-like) so that wall contacts differ from particle contacts.
inline Material Steel() { return {"steel", 7800.0, 7.9e10, 0.3}; }

// A table with snow (0) and steel (1) and the given snow-snow / snow-steel interaction.
inline MaterialTable SnowAndSteel(const Interaction& snow_snow, const Interaction& snow_steel) {
  MaterialTable t;
  t.Add(Snow());
  t.Add(Steel());
  t.SetInteraction(0, 0, snow_snow);
  t.SetInteraction(0, 1, snow_steel);
  t.SetInteraction(1, 1, snow_steel);
  return t;
}

// Axis-aligned cube [-h, h]^3 as 12 triangles, counter-clockwise seen from outside.
inline TriangleMesh Cube(double h, int material) {
  TriangleMesh m;
  m.material = material;
  for (int k = 0; k < 8; ++k)
    m.vertices.push_back({k & 1 ? h : -h, k & 2 ? h : -h, k & 4 ? h : -h});
  const int32_t f[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : f) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  return m;
}

inline Plane Floor(double z = 0.0, int material = 1) {
  return Plane{"floor", Vec3{0, 0, z}, Vec3{0, 0, 1}, material};
}

// Rebound speed / impact speed of a head-on Hertz impact with the damping of dem/contact.h,
//   m* x'' = -4/3 E* sqrt(R*) x^(3/2) - 2 sqrt(5/6) beta sqrt(2 E* sqrt(R* x) m*) x'
// (no tension), integrated here in physical units by Heun's method with 2e5 steps per contact
// time scale: a check independent of dem::RestitutionForBeta (nondimensional, RK4).
inline double HertzImpactRestitution(double beta, double e_star, double r_star, double m_star,
                                     double v0) {
  const double k = 4.0 / 3.0 * e_star * std::sqrt(r_star);
  const auto accel = [&](double x, double v) {
    if (x <= 0) return 0.0;
    const double sn = 2.0 * e_star * std::sqrt(r_star * x);
    const double f =
        k * x * std::sqrt(x) + 2.0 * std::sqrt(5.0 / 6.0) * beta * std::sqrt(sn * m_star) * v;
    return -std::max(0.0, f) / m_star;
  };
  // Contact time scale (m*^2 / (R* E*^2 v0))^(1/5).
  const double tc = std::pow(m_star * m_star / (r_star * e_star * e_star * v0), 0.2);
  const double h = tc / 2e5;
  double x = 0, v = v0;
  for (int step = 0; step < 100'000'000; ++step) {
    const double a1 = accel(x, v);
    const double xp = x + h * v, vp = v + h * a1;
    const double nx = x + 0.5 * h * (v + vp), nv = v + 0.5 * h * (a1 + accel(xp, vp));
    if (nx < 0 && step > 0) return -(v + x / (x - nx) * (nv - v)) / v0;
    x = nx;
    v = nv;
  }
  return 0;
}

// Steps and fails the test on bad health (STYLE.md habit 11).
inline void StepOk(System& s, int64_t steps = 1) {
  for (int64_t k = 0; k < steps; ++k) {
    const StepStatus st = s.Step();
    ASSERT_TRUE(st.ok()) << st.message;
  }
}

}  // namespace dem::test
