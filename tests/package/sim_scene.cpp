// Links scoopsim::sim (its four rooms, with dem and arm) from find_package(scoopsim), and is built
// with every installed header (all_headers.cpp). Loads the installed scenes/quick_dig.yaml: its
// materials.yaml and ../assets/scoop.stl resolve in PREFIX/share/scoopsim, and the scoop mesh read
// through assimp has the 84 triangles of assets/README.md. Exit 0 then, 1 otherwise.
#include <cstdio>

#include "sim/input/input_error.h"
#include "sim/input/scene.h"

int main() {
  try {
    const sim::Scene scene = sim::LoadScene(SCOOPSIM_SCENE);
    const size_t triangles = scene.dig.scoop.geometry.triangles.size();
    std::printf("sim_scene: %s: %lld particles, dt %.3g s, scoop %s with %zu triangles\n",
                SCOOPSIM_SCENE, static_cast<long long>(scene.bed.count), scene.time_step,
                scene.dig.scoop.mesh.c_str(), triangles);
    return triangles == 84 ? 0 : 1;
  } catch (const sim::InputError& e) {
    std::printf("sim_scene: %s\n", e.what());
    return 1;
  }
}
