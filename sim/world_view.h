// A read-only view of the world at one instant, handed to observers such as the renderer
// (render/ reads sim/, never the other way). Valid only during the callback that receives it.
#pragma once

#include <functional>
#include <vector>

#include "dem/mesh.h"
#include "dem/system.h"

namespace sim {

struct MeshView {
  const dem::TriangleMesh* mesh = nullptr;  // body-frame geometry
  dem::Pose pose;                           // body -> world
};

struct WorldView {
  double time = 0;    // simulated time [s]
  int pass = 0;       // dig pass (1-based); 0 when the scene has no dig
  double rho = 0;     // distance along the trench since first contact [m]
  double force = 0;   // |F| on the scoop [N]
  double torque = 0;  // |T| on the scoop about its CoM [N m]
  const dem::Particles* particles = nullptr;
  std::vector<MeshView> meshes;
  dem::Vec3 box_min, box_max;  // bed container [m]
  dem::Vec3 gravity;           // [m/s^2]
};

// Called by the run loop between steps (never while the DEM's OpenMP threads run).
using FrameCallback = std::function<void(const WorldView&)>;

}  // namespace sim
