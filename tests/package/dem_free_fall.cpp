// Links scoopsim::dem alone (find_package(scoopsim COMPONENTS dem)). Two snow spheres 0.5 m
// apart, no walls, gravity g = (0, 0, -9.81): sphere 0 dropped from rest, sphere 1 thrown with
// v0 = (0.5, 0, 1) m/s. They never touch, so each is a projectile, and velocity Verlet is exact
// for a constant force: x(t) = x0 + v0 t + g t^2 / 2 after 1000 steps of 1e-4 s (t = 0.1 s), to
// 1e-12 m (rounding only: ~1e-16 m a step). Exit 0 when both agree, 1 otherwise.
#include <cmath>
#include <cstdio>

#include "dem/system.h"

int main() {
  dem::MaterialTable materials;
  materials.Add({"snow", 300.0, 1.0e7, 0.36});  // density [kg/m^3], G [Pa], nu [-]
  dem::SystemConfig config;
  config.gravity = {0, 0, -9.81};
  config.time_step = 1e-4;
  config.skin = 1e-3;
  config.domain_min = {-1, -1, -1};
  config.domain_max = {1, 1, 1};
  dem::System system(materials, config);
  const dem::Vec3 x0[2] = {{0, 0, 0.5}, {0.5, 0, 0.5}};
  const dem::Vec3 v0[2] = {{0, 0, 0}, {0.5, 0, 1.0}};
  for (int i = 0; i < 2; ++i) system.AddParticle(x0[i], v0[i], {}, 0.005, 0);

  for (int k = 0; k < 1000; ++k) {
    const dem::StepStatus status = system.Step();
    if (!status.ok()) {
      std::printf("dem_free_fall: step %d: %s\n", k, status.message.c_str());
      return 1;
    }
  }
  const double t = system.time();
  const dem::Particles& p = system.particles();
  double worst = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const int64_t id = p.id[i];  // storage order may differ from the ids
    const double exact[3] = {x0[id].x + v0[id].x * t, x0[id].y + v0[id].y * t,
                             x0[id].z + v0[id].z * t - 0.5 * 9.81 * t * t};
    const double got[3] = {p.x[i].x, p.x[i].y, p.x[i].z};
    for (int a = 0; a < 3; ++a) worst = std::fmax(worst, std::fabs(got[a] - exact[a]));
    std::printf("dem_free_fall: sphere %lld at t = %.4f s: z = %.15f m (exact %.15f)\n",
                static_cast<long long>(id), t, got[2], exact[2]);
  }
  std::printf("dem_free_fall: worst |x - (x0 + v0 t + g t^2/2)| = %.3g m (tolerance 1e-12 m)\n",
              worst);
  return worst <= 1e-12 ? 0 : 1;
}
